"""Issue 20 on whole flights: the X frame against SITL's X-frame reference (normal_x_s50), and
the paper's fault sequence (combined_s21's mission and faults) flown on the X frame and in
wind, where every fault of labels 1-4 must keep its signature.

On the X frame in calm air the comparison is the cross-check's (every signature metric within
35 % of SITL's "+" flight: the frame changes the mixer, not the fault). In wind the flight is
not SITL's calm one, so what is checked is what the reference README states of each fault
(the facts ``test_fault_signatures.py`` pins on SITL's logs), with the wind-dependent numbers
(how far the EKF drifts without GPS, the settling roll in gusts) left out.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import pytest

from tests.conftest import reference_path
from tlm_process.crosscheck.compare import crosscheck
from tlm_sim.flightlog import read_bin
from tlm_sim.flightlog.binwriter import frame_string

#: SITL's wind of normal_wind_s41, and the heavier weather of the held-back flights
SITL_WIND = {"SIM_WIND_SPD": 5.0, "SIM_WIND_DIR": 45.0, "SIM_WIND_TURB": 1.0}
STRONG_WIND = {"SIM_WIND_SPD": 8.0, "SIM_WIND_DIR": 200.0, "SIM_WIND_TURB": 2.0}
X = {"FRAME_CLASS": 1.0, "FRAME_TYPE": 1.0}


@lru_cache(maxsize=4)
def _paper(overrides: tuple[tuple[str, float], ...]) -> dict[str, Any]:
    return crosscheck(reference_path("combined_s21.bin"), params=dict(overrides))


def _tlm_signatures(r: dict[str, Any]) -> dict[str, dict[str, float]]:
    return {f["type"]: {row["metric"]: row["tlm"] for row in f["rows"]} for f in r["faults"]}


def test_x_frame_reference_flight():
    """normal_x_s50 (sim_vehicle -f X, FRAME_TYPE 1): tlm takes the frame from the log and
    flies it within 5 % of SITL's flight time and 3 m of its path; its RCOU has SITL's
    cruise outputs (front pair 1/3 and back pair 2/4 of the X, motors of a pair equal)."""
    import numpy as np

    src = reference_path("normal_x_s50.bin")
    r = crosscheck(src)
    assert r["scenario"]["params_from_log"]["FRAME_TYPE"] == 1
    ft = r["flight_time_s"]
    assert abs(ft["tlm"] - ft["sitl"]) / ft["sitl"] < 0.05
    assert r["trajectory_rms_m"] <= 3.0
    tlm = r["_log"].tables
    assert frame_string(r["_log"].params) == "Frame: QUAD/X"  # the MSG line of its .bin
    sitl = read_bin(str(src), types=["RCOU"])["RCOU"]
    cols = ["C1", "C2", "C3", "C4"]
    mid = {}
    for side, rc in (("tlm", tlm["RCOU"]), ("sitl", sitl)):
        n = len(rc)
        mid[side] = rc[cols].iloc[n // 3: 2 * n // 3].mean().to_numpy()
    assert np.abs(mid["tlm"] - mid["sitl"]).max() < 3.0  # us
    assert np.all(tlm["RCOU"][["C5", "C6", "C7", "C8"]].to_numpy() == 0)


def test_paper_faults_on_the_x_frame_match_sitls_plus_flight():
    """The paper's four faults on the X frame, calm, against SITL's "+" flight of the same
    scenario: at least 44 of the 46 metrics within 35 % (measured 45-46: the engine fault's
    lift-off after the restore, 0.5-0.7 s against SITL's 1.0 s, depends on how the copter lies
    after hopping on the ground), the flight time within 5 % and the path within 3 m. The
    README's facts of every fault: the weather test below."""
    r = _paper(tuple(X.items()))
    assert [f["type"] for f in r["faults"]] == ["gps", "accel", "engine", "rc"]
    passed = sum(f["passed"] for f in r["faults"])
    compared = sum(f["compared"] for f in r["faults"])
    assert compared == 46 and passed >= 44, [
        (f["type"], row["metric"]) for f in r["faults"] for row in f["rows"] if not row["pass"]]
    ft = r["flight_time_s"]
    assert abs(ft["tlm"] - ft["sitl"]) / ft["sitl"] < 0.05
    assert r["trajectory_rms_m"] <= 3.0


def _facts(kind: str, s: dict[str, float]) -> list[str]:
    """The reference README's facts of a paper fault that hold whatever the wind; returns the
    ones that do not hold."""
    facts = {
        "gps": lambda: {
            "no fix only inside": s["nofix_frac_in"] == 1.0 and s["nofix_frac_out"] == 0.0,
            "3 satellites inside, 10 after": (s["nsats_max_in"], s["nsats_min_out"]) == (3, 10),
            "EKF drifts > 100 m": s["ekf_err_max_m"] > 100.0,
            "EKF back within 0.5 s": s["ekf_recovered_after_end_s"] < 0.5,
            "AUTO kept": s["auto_kept"] == 1.0,
            "pitch up to 25-36 deg": 25.0 < s["pitch_max_deg"] < 36.0,
            "baro within 2.5 m": s["baro_alt_range_m"] < 2.5,
        },
        "accel": lambda: {
            "both IMUs stuck inside only": all(
                s[f"imu{i}_stuck_frac_in"] > 0.99 and s[f"imu{i}_stuck_frac_out"] == 0.0
                for i in (0, 1)),
            "climbs > 10 m in 3 s at full throttle": s["climb_3s_m"] > 10.0
            and s["thr_max_3s"] == 1.0,
            "EKF lane switch and vibration failsafe": s["err24_ekf_primary"] > 0
            and s["err29_vibe_fs"] > 0,
            "roll up to 25-35 deg": 25.0 < s["roll_max_deg"] < 36.0,
            "AUTO kept": s["auto_kept"] == 1.0,
        },
        "engine": lambda: {
            "falls in 2.5-3.2 s": 2.5 <= s["ground_s"] <= 3.2,
            "hits at 11-13.5 m/s": 11.0 < s["impact_speed_ms"] < 13.5,
            "tumbles (roll > 80 deg)": s["roll_max_3s_deg"] > 80.0,
            "stays armed in AUTO": s["armed_kept"] == 1.0 and s["auto_kept"] == 1.0,
            "lifts off within 1.2 s of the restore": s["liftoff_1m_after_end_s"] < 1.2,
            "10 m up 3.5-5 s after": 3.5 < s["above_10m_after_end_s"] < 5.0,
            "goes on with the mission": s["auto_after_end"] == 1.0
            and s["path_after_10m_m"] > 50.0,
        },
        "rc": lambda: {
            "RTL 1 s after the loss": abs(s["rtl_delay_s"] - 1.0) < 0.1
            and s["rtl_reason"] == 3,
            "ERR 2/2, 5/1, 5/0": s["err2_2_late_frame"] > 0 and s["err5_1_failsafe"] > 0
            and s["err5_0_cleared"] > 0,
            "RTL kept, lands home and disarms": s["rtl_kept_after_end"] == 1.0
            and 60.0 <= s["disarm_s"] <= 85.0 and s["final_home_dist_m"] < 1.0,
        },
    }[kind]()
    return [name for name, ok in facts.items() if not ok]


@pytest.mark.parametrize("weather", [
    pytest.param({**X}, id="x-calm"),
    pytest.param({**SITL_WIND}, id="plus-sitl-wind"),
    pytest.param({**X, **STRONG_WIND}, id="x-8ms-turb2"),
])
def test_paper_faults_on_x_and_in_wind_keep_their_signatures(weather):
    """The paper's four faults on the X frame, in SITL's wind on "+" and in 8 m/s wind with
    turbulence 2 on the X frame: every fact of every fault holds, and the flight time stays
    within 5 %."""
    r = _paper(tuple(weather.items()))
    sig = _tlm_signatures(r)
    assert list(sig) == ["gps", "accel", "engine", "rc"]
    for kind, s in sig.items():
        assert not _facts(kind, s), (kind, _facts(kind, s))
    ft = r["flight_time_s"]
    assert abs(ft["tlm"] - ft["sitl"]) / ft["sitl"] < 0.05
    assert r["scenario"]["overrides"] == weather
    for name, value in weather.items():
        assert r["_log"].params[name] == value


def test_facts_catch_a_broken_signature():
    """The facts are not vacuous: SITL's own calm signatures pass them, a fault that did not
    happen fails them."""
    r = _paper(tuple(X.items()))
    for kind, s in _tlm_signatures(r).items():
        assert not _facts(kind, s), kind
        broken = dict(s)
        broken.update({k: 0.0 for k in s})
        assert _facts(kind, broken), kind
