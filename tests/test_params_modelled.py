"""One source of parameter truth (issue 18 step 2): every parameter tlm accepts explicitly acts,
every parameter it does not model is refused, and whole loaded sets carry and report them."""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest

from tlm_process.cli import main
from tlm_sim import flight as FL
from tlm_sim.control.config import build_control_config
from tlm_sim.dynamics import layout as X
from tlm_sim.dynamics.body import init_state
from tlm_sim.dynamics.frame import build_frame
from tlm_sim.earthfield import with_home_field
from tlm_sim.ekf.config import build_ekf_config
from tlm_sim.faults import Fault, FaultSchedule, FaultScheduleError, Trigger, jitter_nsats
from tlm_sim.params import (
    PARAM_INFO,
    ParamError,
    Params,
    UnmodelledParamError,
    UnmodelledParamWarning,
    is_modelled,
    parameter_list,
)
from tlm_sim.profiles import profile_params
from tlm_sim.sensors.config import build_sensor_config

#: parameters the issue found accepted and ignored: each must now be refused
ISSUE_IGNORED = ("SIM_BAR3_DISABLE", "SIM_MAG_DELAY", "SIM_BAR3_DRIFT", "SIM_BAR3_FREEZE",
                 "SIM_BARO_DELAY", "SIM_GPS1_POS_X", "SIM_MAG1_DIA_X", "LOG_BITMASK",
                 "SIM_BAR3_RND", "PSC_ACCZ_D")  # (DISARM_DELAY acts since pilot modes)


def _inputs(p: Params) -> list[np.ndarray]:
    """Everything a flight builds from its parameters before flying: the four configuration
    arrays, the initial state, the log buffer sizing and the GPS.NSats jitter of a fixed log;
    first the earth field at the mission's home (TLM_MAG_*, as ``fly`` resolves it)."""
    p, _ = with_home_field(p, FL.builtin_mission(1).home, FL.BOOT_UTC)
    cfg = FL._configs(p)
    x = np.zeros(X.N_STATE)
    init_state(x, cfg.frame, math.radians(p["SIM_OPOS_HDG"]))
    status = np.array([6.0, 6.0, 1.0, 6.0, 1.0] * 4)
    nsats = jitter_nsats(status, 0, p["TLM_SAT_JITTER"]) if p["TLM_SAT_JITTER"] > 0 else status
    duration = FL.max_duration_s(FL.builtin_mission(1), p)
    return [*cfg, x, np.asarray(nsats, float), np.array([duration])]


def _candidates(name: str) -> list[float]:
    """Legal values other than the default, tried in turn."""
    info, d = PARAM_INFO[name], Params()[name]
    span = info.max - info.min
    raw = [d * 2, d * 0.5, d + 1, d - 1, d + 0.1 * span, d - 0.1 * span, info.min, info.max,
           (info.min + info.max) / 2, info.min + 0.01 * span]
    out = []
    for v in raw:
        v = float(round(v)) if info.integer else float(v)
        if v != d and info.min <= v <= info.max and v not in out:
            out.append(v)
    return out


#: parameters that act only beside others (a cross-parameter rule refuses them alone)
COMPANIONS = {"TLM_VIB_IMB": {"TLM_VIB_IMB_MOT": 1, "SIM_VIB_MOT_MAX": 300.0}}
MODELLED = sorted(n for n, i in PARAM_INFO.items() if i.modelled and not i.pinned)
PINNED = sorted(n for n, i in PARAM_INFO.items() if i.pinned)


def test_every_modelled_parameter_acts():
    """Each modelled parameter, set to some legal non-default value, changes what the flight
    is built from (no flights: the configuration arrays and initial state)."""
    silent = []
    for name in MODELLED:
        with_ = COMPANIONS.get(name, {})
        base = _inputs(Params(with_))
        for v in _candidates(name):
            try:
                p = Params({**with_, name: v})
            except ParamError:  # a cross-parameter rule (MOT_SPIN_MIN < MOT_SPIN_MAX, ...)
                continue
            if any(not np.array_equal(a, b) for a, b in zip(base, _inputs(p), strict=True)):
                break
        else:
            silent.append(name)
    assert not silent, f"modelled but acting on nothing: {silent}"
    assert len(MODELLED) > 180


def test_pinned_parameters_refuse_any_other_value():
    """SCHED_LOOP_RATE and SIM_RATE_HZ hold the one value tlm simulates; the flight loop's
    tick lengths derive from them. (FRAME_CLASS / FRAME_TYPE pick a frame of tlm_sim.frames:
    tests/test_frames.py.)"""
    assert set(PINNED) == {"SCHED_LOOP_RATE", "SIM_RATE_HZ"}
    for name in PINNED:
        assert Params()[name] == PARAM_INFO[name].min
        with pytest.raises(ParamError, match=f"{name} = .* is not supported"):
            Params({name: PARAM_INFO[name].min + 1})
    # SCHED_LOOP_RATE=50 used to change the controllers' dt without changing the loop
    with pytest.raises(ParamError, match="SCHED_LOOP_RATE"):
        Params({"SCHED_LOOP_RATE": 50})
    assert FL.LOOP_DT_US == 1e6 / Params()["SCHED_LOOP_RATE"] == 2500
    assert FL.PHYSICS_DT_US == math.floor(1e6 / Params()["SIM_RATE_HZ"]) == 833
    p = Params()
    assert build_control_config(p)[0] == build_ekf_config(p)[0] == 1.0 / 400.0


def test_every_unmodelled_parameter_is_refused_explicitly():
    p = Params()
    unmodelled = [n for n in p if not is_modelled(n)]
    assert len(unmodelled) > 1000 and set(ISSUE_IGNORED) <= set(unmodelled)
    for name in unmodelled:
        with pytest.raises(UnmodelledParamError, match=f"^{name} is not modelled by tlm"):
            Params({name: p[name]})
    with pytest.raises(UnmodelledParamError, match="SIM_BAR3_DISABLE"):
        p.updated(SIM_BAR3_DISABLE=1)
    with pytest.raises(UnmodelledParamError, match="SIM_GPS1_POS_X"):  # via its old name
        Params({"SIM_GPS_POS_X": 0.1})


def test_unmodelled_parameters_are_refused_mid_flight_and_in_schedules():
    with pytest.raises(UnmodelledParamError, match="SIM_MAG_DELAY"):
        FL.build_schedule(Params(), [(120.0, "SIM_MAG_DELAY", 20.0)])
    with pytest.raises(FaultScheduleError, match="SIM_BAR3_FREEZE is not modelled"):
        Fault("gps", Trigger("time", 60), Trigger("time", 90),
              params_start={"SIM_GPS1_ENABLE": 0, "SIM_BAR3_FREEZE": 1})
    with pytest.raises(FaultScheduleError, match="LOG_BITMASK is not modelled"):
        FaultSchedule.from_dict({"faults": [{"fault": "gps", "start": 60, "end": 90,
                                             "params_end": {"LOG_BITMASK": 0}}]})


@pytest.mark.parametrize("option", [["--param", "SIM_BAR3_DISABLE=1"],
                                    ["--set", "120:SIM_IMUT_START=30"],
                                    ["--param", "SCHED_LOOP_RATE=50"],
                                    ["--param", "SIM_RATE_HZ=400"]])
def test_cli_refuses_unmodelled_and_pinned_values(option, tmp_path, capsys):
    assert main(["fly", "--out", str(tmp_path / "o"), "--no-plot", *option]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("tlm: error: ") and "\n" not in err
    assert option[1].split("=")[0].split(":")[-1] in err


def test_builders_read_params_only():
    for build in (build_frame, build_sensor_config, build_ekf_config, build_control_config):
        with pytest.raises(TypeError, match="Params"):
            build({})
        build(Params())


def test_whole_set_carries_unmodelled_values_with_one_warning(tmp_path):
    parm = tmp_path / "vehicle.parm"
    parm.write_text("SIM_BAR3_DISABLE 1\nLOG_BITMASK 0\nWPNAV_SPEED 500\nSERIAL1_BAUD 57\n")
    with pytest.warns(UnmodelledParamWarning) as rec:
        p = Params.from_parm(parm)
    assert len(rec) == 1
    msg = str(rec[0].message)
    assert "vehicle.parm" in msg and "LOG_BITMASK=0" in msg and "SIM_BAR3_DISABLE=1" in msg
    assert "WPNAV_SPEED" not in msg and "SERIAL1_BAUD" not in msg  # modelled / default value
    assert p.unmodelled() == {"LOG_BITMASK": 0.0, "SIM_BAR3_DISABLE": 1.0}
    assert p["WPNAV_SPEED"] == 500.0
    # carried through explicit updates, profiles and pickling; explicit ones stay refused
    assert p.updated(WPNAV_SPEED=700).unmodelled() == p.unmodelled()
    assert profile_params("paper", p).unmodelled() == p.unmodelled()
    assert Params(p) == p
    with pytest.raises(UnmodelledParamError):
        p.updated(SIM_BAR3_FREEZE=1)
    # a whole set still validates what tlm knows of the parameters it carries
    with pytest.raises(ParamError, match="SIM_BARO_DISABLE = 2 is out of range"):
        Params.from_parm_text("SIM_BARO_DISABLE 2\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Params.from_parm_text("WPNAV_SPEED 500\nSIM_BARO_DISABLE 0\n")  # nothing to report


@pytest.mark.slow
def test_fly_with_a_parm_file_warns_once_and_records_meta(tmp_path, capsys):
    parm = tmp_path / "v.parm"
    parm.write_text("SIM_BAR3_DISABLE 1\nLOG_BITMASK 0\n")
    out = tmp_path / "o"
    assert main(["fly", "--mission", "3", "--out", str(out), "--params", str(parm),
                 "--no-plot", "--format", "csv"]) == 0
    err = [ln for ln in capsys.readouterr().err.splitlines() if "warning" in ln]
    assert len(err) == 1 and err[0].startswith("tlm: warning: ") and "LOG_BITMASK=0" in err[0]
    meta = json.loads((out / "meta.json").read_text())["meta"]
    assert meta["unmodelled_params"] == {"LOG_BITMASK": 0.0, "SIM_BAR3_DISABLE": 1.0}


@pytest.mark.slow
def test_wpnav_radius_acts_in_flight():
    """WPNAV_RADIUS ends a route and an RTL return: a 5 cm radius changes the flight."""
    a = FL.fly(1, seed=3)
    b = FL.fly(1, seed=3, params={"WPNAV_RADIUS": 5})
    assert a.meta["unmodelled_params"] == {}
    assert any(not a.tables[n].equals(b.tables[n]) for n in a.tables)


def test_parameter_list_declares_every_parameter():
    rows = parameter_list()
    assert [r["name"] for r in rows] == list(Params())
    by = {r["name"]: r for r in rows}
    assert by["WPNAV_SPEED"] | {"aliases": []} == {
        "name": "WPNAV_SPEED", "default": 600.0, "unit": "cm/s", "min": 10.0, "max": 2000.0,
        "integer": False, "modelled": True, "description": "waypoint horizontal speed (§4.6)",
        "aliases": []}
    assert by["SIM_GPS1_ENABLE"]["aliases"] == ["SIM_GPS_DISABLE"]
    assert by["SERIAL1_BAUD"]["modelled"] is False and by["SERIAL1_BAUD"]["unit"] is None
    assert all(r["modelled"] == is_modelled(r["name"]) for r in rows)
    assert [r["name"] for r in parameter_list(["ek3_hgt*", "SIM_GPS_DISABLE"])] == [
        "EK3_HGT_DELAY", "EK3_HGT_I_GATE", "SIM_GPS1_ENABLE"]


def test_tlm_params_command(capsys):
    assert main(["params", "WPNAV_SPEED", "SIM_BAR3_DISABLE"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split() == ["NAME", "DEFAULT", "UNIT", "RANGE", "MODELLED", "DESCRIPTION"]
    assert lines[1].split()[:2] == ["SIM_BAR3_DISABLE", "0"] and " no " in lines[1]
    assert lines[2].split()[:7] == ["WPNAV_SPEED", "600", "cm/s", "10", "..", "2000", "yes"]
    assert main(["params"]) == 0
    assert len(capsys.readouterr().out.splitlines()) == len(Params()) + 1
    assert main(["params", "--json", "--modelled"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert {r["name"] for r in rows} == {n for n in Params() if is_modelled(n)}
    assert main(["params", "--unmodelled", "SIM_BARO_*"]) == 0
    assert "SIM_BARO_RND" not in capsys.readouterr().out


def test_tlm_params_unknown_name_is_one_line(capsys):
    assert main(["params", "WPNAV_SPED"]) == 2
    err = capsys.readouterr().err
    assert err == ("tlm: error: unknown parameter 'WPNAV_SPED' (did you mean WPNAV_SPEED, "
                   "WPNAV_SPEED_UP, WPNAV_SPEED_DN?)\n")
    with pytest.raises(SystemExit) as exc:
        main(["params", "--help"])
    assert exc.value.code == 0
    assert "modelled" in capsys.readouterr().out


def test_a_loaded_16_bit_mask_logged_negative_reads_as_its_bits():
    """Copter 3.1 kept LOG_BITMASK in 16 bits: with bit 15 set its PARM row reads negative
    (nan.log: -22530). A loaded set takes it as the unsigned bits (43006, 0xA7FE); other
    negative values, and masks set explicitly, are still refused."""
    with pytest.warns(UnmodelledParamWarning):
        p = Params.from_values({"LOG_BITMASK": -22530})
    assert p["LOG_BITMASK"] == 43006.0 == float(0xA7FE)
    with pytest.warns(UnmodelledParamWarning):
        assert Params.from_parm_text("LOG_BITMASK -1\n")["LOG_BITMASK"] == 65535.0
    for bad in (-40000, -1.5):
        with pytest.raises(ParamError):
            Params.from_values({"LOG_BITMASK": bad})
    with pytest.raises(ParamError, match="out of range"):
        Params.from_values({"WPNAV_SPEED": -5})  # not a mask
    with pytest.raises(ParamError, match="out of range"):
        Params().updated(ARMING_CHECK=-1)  # set on its own: as given
