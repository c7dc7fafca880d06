"""The earth magnetic field at a mission's home (issue 22): ``tlm_sim.earthfield`` against
published model values and the reference firmware's tables, the ``TLM_MAG_*`` rules, and
flights away from Canberra (compass at rest, EKF yaw, pre-arm checks, what a user sees)."""

from __future__ import annotations

import datetime as dt
import json
import math

import numpy as np
import pytest

from tests.conftest import reference_path
from tlm_process.cli import main
from tlm_sim import fly
from tlm_sim.earthfield import (
    MAG_PARAMS,
    home_field,
    igrf_field,
    sitl_table_field,
    with_home_field,
)
from tlm_sim.flight import BOOT_UTC
from tlm_sim.flightlog import read_bin
from tlm_sim.flightlog.texts import logged_texts
from tlm_sim.geo import HOME_CMAC, ne_to_latlon
from tlm_sim.mission import Mission, builtin_mission, write_wpl
from tlm_sim.params import TLM_DEFAULTS, ParamError, Params

ZURICH = (47.3977, 8.5456, 500.0)
CMAC_DEFAULT = tuple(TLM_DEFAULTS[n] for n in MAG_PARAMS)

#: NOAA/NCEI "WMM2020 Test Values" (WMM2020testvalues.pdf, the WMM2020 technical report's test
#: table): (decimal year, altitude km, lat, lon, D deg, I deg, F nT).
WMM2020_TEST_VALUES = (
    (2020.0, 0, 80, 0, -1.28, 83.14, 55000.1),
    (2020.0, 0, 0, 120, 0.16, -15.42, 41104.9),
    (2020.0, 0, -80, 240, 69.36, -72.20, 55120.6),
    (2020.0, 100, 80, 0, -1.70, 83.19, 52802.0),
    (2022.5, 0, 80, 0, 0.01, 83.19, 55101.7),
    (2022.5, 0, 0, 120, -0.06, -15.24, 41130.5),
    (2022.5, 0, -80, 240, 69.13, -72.09, 54912.1),
    (2022.5, 100, 0, 120, -0.05, -15.37, 39092.4),
)

#: AP_Declination::get_mag_field_ef of the reference firmware (2598e9d4b2, tables.cpp of
#: 2022-12-29) at CMAC and in Zurich: (lat, lon, declination, inclination, intensity gauss).
FIRMWARE_TABLE_VALUES = (
    (-35.363261, 149.165230, 12.7974, -65.7653, 0.58003),
    (47.3977, 8.5456, 3.1883, 63.1090, 0.48164),
)


def _decimal_year(y: float) -> dt.datetime:
    year = int(y)
    start = dt.datetime(year, 1, 1)
    return start + (dt.datetime(year + 1, 1, 1) - start) * (y - year)


@pytest.mark.parametrize("model", ["IGRF13", "IGRF14"])
@pytest.mark.parametrize("row", WMM2020_TEST_VALUES)
def test_igrf_agrees_with_noaa_wmm_test_values(model, row):
    """IGRF and the WMM are separate fits of the same field: they agree within the models'
    own uncertainty (WMM: ~0.3-0.5 deg declination, ~150 nT); tlm's tolerance 0.15 deg, 0.1 deg,
    0.2 %, altitude included."""
    year, alt_km, lat, lon, d, i, f = row
    dec, inc, intensity = igrf_field(lat, lon, alt_km * 1000.0, _decimal_year(year), model)
    assert dec == pytest.approx(d, abs=0.15)
    assert inc == pytest.approx(i, abs=0.1)
    assert intensity * 1e5 == pytest.approx(f, rel=0.002)


@pytest.mark.parametrize("row", FIRMWARE_TABLE_VALUES)
def test_sitl_table_field_is_the_firmware_tables(row):
    """The IGRF-13 grid tlm evaluates equals ArduPilot's tables to ~0.01 deg (the firmware's
    own IGRF implementation and generation time differ by that much)."""
    lat, lon, d, i, f = row
    dec, inc, intensity = sitl_table_field(lat, lon)
    assert dec == pytest.approx(d, abs=0.02)
    assert inc == pytest.approx(i, abs=0.01)
    assert intensity == pytest.approx(f, abs=5e-5)


def test_sitl_table_field_reproduces_sitl_compass_at_cmac():
    """normal_s11.bin's compass 0 on the pad, (224, 80, -528) mGauss body with SITL's yaw 353
    deg: the table field at CMAC rotated into the body and truncated to whole mGauss, as
    AP_Logger writes MAG ((int16_t) casts), gives exactly those numbers."""
    t = read_bin(reference_path("normal_s11.bin"), types=["MAG", "SIM"])
    mag, sim = t["MAG"], t["SIM"]
    pad = (mag.I == 0) & (mag.TimeUS > 20e6) & (mag.TimeUS < 40e6)
    rest = sim[(sim.TimeUS > 20e6) & (sim.TimeUS < 40e6)]
    assert rest.Roll.abs().max() == rest.Pitch.abs().max() == 0.0
    assert rest.Yaw.nunique() == 1
    logged = mag[pad][["MagX", "MagY", "MagZ"]].drop_duplicates().to_numpy()
    dec, inc, intensity = sitl_table_field(*HOME_CMAC[:2])
    h = 1000.0 * intensity * math.cos(math.radians(inc))
    ned = np.array([h * math.cos(math.radians(dec)), h * math.sin(math.radians(dec)),
                    1000.0 * intensity * math.sin(math.radians(inc))])
    y = math.radians(float(rest.Yaw.iloc[0]))
    body = np.array([[math.cos(y), math.sin(y), 0.0], [-math.sin(y), math.cos(y), 0.0],
                     [0.0, 0.0, 1.0]]) @ ned
    assert logged.tolist() == [np.trunc(body).tolist()]


def test_home_field_rules():
    # at SITL's home: the defaults (SITL's field measured from the reference logs), unchanged
    for m in (0, 1):
        p, f = with_home_field(Params({"TLM_MAG_MODEL": m}), HOME_CMAC, BOOT_UTC)
        assert f.values() == CMAC_DEFAULT and p == Params({"TLM_MAG_MODEL": m})
    # a home given as a log's 1e-7 degree integers is still CMAC
    near = (-353632610 * 1e-7, 1491652300 * 1e-7, 584.0)
    assert home_field(Params(), near, BOOT_UTC).values() == CMAC_DEFAULT
    # elsewhere: SITL's tables, rounded
    p, f = with_home_field(Params(), ZURICH, BOOT_UTC)
    want = tuple(round(v, k) for v, k in zip(sitl_table_field(*ZURICH[:2]), (4, 4, 6),
                                             strict=True))
    assert f.values() == want == tuple(p[n] for n in MAG_PARAMS)
    assert f.inclination_deg > 60.0  # northern hemisphere: the field points down
    assert "AP_Declination" in f.source
    assert with_home_field(p, ZURICH, BOOT_UTC)[0] is p  # resolving twice changes nothing
    # TLM_MAG_MODEL 2: IGRF-14 at home on the simulated date
    f2 = home_field(Params({"TLM_MAG_MODEL": 2}), ZURICH, BOOT_UTC)
    d, i, g = igrf_field(ZURICH[0], ZURICH[1], ZURICH[2], BOOT_UTC, "IGRF14")
    assert f2.values() == (round(d, 4), round(i, 4), round(g, 6))
    assert f2.values() != f.values() and abs(f2.declination_deg - f.declination_deg) < 1.0
    # TLM_MAG_MODEL 0: the parameters as given, whatever the home (tlm before issue 22)
    assert home_field(Params({"TLM_MAG_MODEL": 0}), ZURICH, BOOT_UTC).values() == CMAC_DEFAULT


def test_explicit_values_win():
    p, f = with_home_field(Params({"TLM_MAG_DEC_DEG": -20.0}), ZURICH, BOOT_UTC)
    table = home_field(Params(), ZURICH, BOOT_UTC)
    assert f.values() == (-20.0, table.inclination_deg, table.intensity_gauss)
    assert f.source.endswith("set: TLM_MAG_DEC_DEG") and p["TLM_MAG_DEC_DEG"] == -20.0
    given = {"TLM_MAG_DEC_DEG": 1.5, "TLM_MAG_INC_DEG": 60.0, "TLM_MAG_INT_GA": 0.5}
    for m in (0, 1, 2):
        f = home_field(Params({**given, "TLM_MAG_MODEL": m}), ZURICH, BOOT_UTC)
        assert f.values() == (1.5, 60.0, 0.5)
    # at CMAC an explicit value wins too
    assert home_field(Params({"TLM_MAG_INT_GA": 0.6}), HOME_CMAC, BOOT_UTC).values() == (
        12.65, -65.75, 0.6)
    with pytest.raises(ParamError, match="TLM_MAG_MODEL = 3 is out of range"):
        Params({"TLM_MAG_MODEL": 3})


def test_field_is_finite_everywhere():
    """Poles, date line and grid corners: finite values within the parameters' ranges."""
    for lat, lon in ((90, 180), (-90, -180), (90, 0), (0, 180), (-0.0, -180), (89.99, 179.99),
                     (-35.363261, 149.16523 + 1e-5)):
        for m in (1, 2):
            f = home_field(Params({"TLM_MAG_MODEL": m}), (lat, lon, 0.0), BOOT_UTC)
            Params(dict(zip(MAG_PARAMS, f.values(), strict=True)))  # validates the ranges


def _moved(mission: Mission, home: tuple[float, float, float]) -> Mission:
    """``mission``'s shape (north/east offsets, altitudes) around another home."""
    ned = mission.ned()
    lat, lon = ne_to_latlon(ned[:, 0], ned[:, 1], home[0], home[1])
    return Mission(waypoints=np.column_stack([lat, lon, -ned[:, 2]]), home=home,
                   name=f"{mission.name} moved", takeoff_alt=mission.takeoff_alt)


def _rest_field_ned(log) -> np.ndarray:
    """Each compass's mean reading [mGauss] over the 5 s before arming, rotated to NED by the
    true attitude (SIM): (n_compasses, 3)."""
    mag, sim = log.tables["MAG"], log.tables["SIM"]
    t1 = log.meta["armed_s"] * 1e6
    s = sim[(sim.TimeUS > t1 - 5e6) & (sim.TimeUS < t1)]
    r, p, y = (math.radians(float(s[c].mean())) for c in ("Roll", "Pitch", "Yaw"))
    cr, sr, cp, sp, cy, sy = (math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y),
                              math.sin(y))
    dcm = np.array([[cp * cy, sr * sp * cy - cr * sy, cr * sp * cy + sr * sy],
                    [cp * sy, sr * sp * sy + cr * cy, cr * sp * sy - sr * cy],
                    [-sp, sr * cp, cr * cp]])
    out = []
    for i in sorted(mag.I.unique()):
        m = mag[(mag.I == i) & (mag.TimeUS > t1 - 5e6) & (mag.TimeUS < t1)]
        out.append(dcm @ m[["MagX", "MagY", "MagZ"]].to_numpy(float).mean(axis=0))
    return np.array(out)


def _expected_ned(f: dict) -> np.ndarray:
    d, i, g = (math.radians(f["declination_deg"]), math.radians(f["inclination_deg"]),
               1000.0 * f["intensity_gauss"])
    return np.array([g * math.cos(i) * math.cos(d), g * math.cos(i) * math.sin(d),
                     g * math.sin(i)])


def _max_yaw_error_deg(log) -> float:
    """Largest |ATT.Yaw - SIM.Yaw| [deg] while armed."""
    att, sim = log.tables["ATT"], log.tables["SIM"]
    att = att[att.TimeUS > log.meta["armed_s"] * 1e6]
    t = att.TimeUS.to_numpy(float)
    truth = np.interp(t, sim.TimeUS.to_numpy(float), np.unwrap(np.radians(sim.Yaw.to_numpy())))
    err = (np.radians(att.Yaw.to_numpy(float)) - truth + np.pi) % (2 * np.pi) - np.pi
    return float(np.degrees(np.abs(err)).max())


@pytest.mark.parametrize("params", [{"TLM_BOOT_PHASE": 1}, {"TLM_MAG_DEC_DEG": -20.0}],
                         ids=["zurich_boot_phase", "zurich_explicit_declination"])
def test_flight_in_zurich_senses_the_local_field(params):
    """Mission 1's shape flown from Zurich: every compass at rest reads the field of the meta
    (Zurich's, or the explicit declination) to the 1 mGauss rounding of MAG, the EKF's yaw
    follows the true yaw, no compass-related pre-arm failure, the mission is completed."""
    log = fly(_moved(builtin_mission(1), ZURICH), params=params, seed=3)
    f = log.meta["earth_field"]
    zurich = home_field(Params(params), ZURICH, BOOT_UTC)
    assert (f["declination_deg"], f["inclination_deg"], f["intensity_gauss"]) == zurich.values()
    assert [log.params[n] for n in MAG_PARAMS] == list(zurich.values())
    rest = _rest_field_ned(log)
    assert len(rest) == 3
    # body components rounded to whole mGauss, rotated: <= 0.5 * (|cos| + |sin|) per axis
    assert np.abs(rest - _expected_ned(f)).max() < 0.75
    assert _max_yaw_error_deg(log) < 1.5
    texts = [s for _, s in logged_texts(log.meta["texts"])]
    assert not [s for s in texts if "ompass" in s or "mag field" in s.lower()]
    if params.get("TLM_BOOT_PHASE"):
        assert "EKF3 IMU0 MAG0 initial yaw alignment complete" in texts
    assert log.meta["waypoints_reached"] == log.meta["n_waypoints"]
    assert log.meta["end_reason"] == "landed"


def test_tlm_fly_mission_file_in_zurich(tmp_path, capsys):
    """What a user sees: ``tlm fly --mission-file`` with its home in Zurich prints and records
    Zurich's field (summary, meta.json, the log's PARM)."""
    wpl = write_wpl(_moved(builtin_mission(2), ZURICH), tmp_path / "zurich.waypoints")
    out = tmp_path / "out"
    assert main(["fly", "--mission-file", str(wpl), "--out", str(out), "--format", "bin"]) == 0
    zurich = home_field(Params(), ZURICH[:2] + (ZURICH[2],), BOOT_UTC)
    printed = capsys.readouterr().out
    assert f"declination {zurich.declination_deg:.2f} deg" in printed
    meta = json.loads((out / "meta.json").read_text())
    assert meta["meta"]["earth_field"]["inclination_deg"] == zurich.inclination_deg
    parm = read_bin(out / "flight.bin", types=["PARM"])["PARM"]
    logged = dict(zip(parm.Name, parm.Value, strict=True))
    for name, v in zip(MAG_PARAMS, zurich.values(), strict=True):
        assert logged[name] == pytest.approx(v, rel=1e-6)  # PARM values are float32
