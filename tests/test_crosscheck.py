"""Cross-check against the reference SITL logs: scenario reconstruction from the log alone, and
the fidelity regression tests (tolerances as documented in docs/crosscheck.md)."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from tests.conftest import reference_path
from tlm_process.cli import main
from tlm_process.crosscheck import crosscheck, gate, reconstruct

LOGS = ("normal_s11", "gps_s12", "accel_s13", "engine_s14", "rc_s15", "combined_s21")

#: log -> (max |flight time difference| as a fraction, max trajectory RMS [m]).
#: The issue's targets are 10 % and 3 m on the normal and combined flights; measured (issue 8,
#: after modelling what ArduCopter does without GPS: the position estimate at the EKF origin in
#: constant-position mode, AC_P_2D's error limit, AC_WPNav's S-curve time scaler, the AUTO
#: takeoff's completion): flight time within 0.2-1.1 %, trajectory RMS 0.06 m (normal), 0.1-0.2 m
#: (accel, engine, rc), 2.0 m (gps) and 2.5 m (combined). The combined flight meets the 3 m
#: target but not robustly: its RMS comes from where the vehicle is along the route when the
#: later faults start (tlm gains ~5 s on SITL during the accelerometer fault), and a 0.3 %
#: change of the cruise speed moves it between 2.5 and 4.4 m. So its trajectory is gated on
#: the mean over six seeds (:func:`test_combined_flight_trajectory_over_seeds`), not on one
#: realisation: with the sensors' noise in one stream seeds 0-5 gave 2.58-3.02 m (mean 2.82),
#: with one stream per sensor 2.64-2.99 m (mean 2.82), and the sidecar's seed 2.50 and 3.03 m.
TOLERANCES = {
    "normal_s11": (0.02, 0.2),
    "gps_s12": (0.02, 3.0),
    "accel_s13": (0.02, 0.4),
    "engine_s14": (0.02, 0.6),
    "rc_s15": (0.03, 0.4),
    "combined_s21": (0.03, None),
}
#: seeds of the combined flight's trajectory gate, its mean and its worst realisation [m]
COMBINED_SEEDS = range(6)
COMBINED_MEAN_RMS_M, COMBINED_MAX_RMS_M = 3.0, 4.5


@pytest.fixture(scope="module")
def results():
    return {n: crosscheck(reference_path(f"{n}.bin")) for n in LOGS}


@pytest.mark.parametrize("name", LOGS)
def test_fidelity_within_documented_tolerances(results, name):
    r = results[name]
    max_ft, max_rms = TOLERANCES[name]
    assert gate(r, max_ft, max_rms) == []
    assert r["hover_throttle"]["tlm"] == pytest.approx(r["hover_throttle"]["sitl"], abs=0.02)
    assert r["gps_hdop"]["tlm"] == r["gps_hdop"]["sitl"] == 1.21
    n_faults = 0 if name == "normal_s11" else 4 if name == "combined_s21" else 1
    assert len(r["faults"]) == n_faults


def test_combined_flight_trajectory_over_seeds():
    """The issue's 3 m target for the chaotic combined flight, as the mean over six seeds
    (each realisation within the documented spread)."""
    rms = [crosscheck(reference_path("combined_s21.bin"), seed=k)["trajectory_rms_m"]
           for k in COMBINED_SEEDS]
    assert sum(rms) / len(rms) <= COMBINED_MEAN_RMS_M, rms
    assert max(rms) <= COMBINED_MAX_RMS_M, rms


def test_normal_flight_profiles_agree(results):
    """Along the route tlm keeps within ~0.7 s of SITL (the AUTO takeoff completing before the
    route starts, the S-curve time scaler and TLM_WP_LEG_K): altitude and speed on the common
    time base agree (measured 0.26 m, 0.15 m/s; 0.52 m, 0.47 m/s before)."""
    r = results["normal_s11"]
    assert r["altitude_rms_m"] < 0.4 and r["speed_rms_ms"] < 0.3
    assert r["max_alt_m"]["tlm"] == pytest.approx(r["max_alt_m"]["sitl"], abs=1.0)
    assert r["imu_acc_std"]["tlm"] == pytest.approx(r["imu_acc_std"]["sitl"], rel=0.3)


@pytest.mark.parametrize("name", LOGS)
def test_cruise_throttle_agrees(results, name):
    """Motor air-density compensation and the battery monitor's resting-voltage estimate: the
    cruise throttle is SITL's (0.365) rather than the frame's hover thrust (0.383 before)."""
    r = results[name]["cruise_throttle"]
    assert r["tlm"] == pytest.approx(r["sitl"], abs=0.005)


def test_normal_cruise_rates_and_vertical_vibration_agree(results):
    """The S-curve corner blends, the rotor momentum-drag damping and the whole-microsecond PWM
    bring tlm's cruise within SITL's: RATE tracking error (was 0.96 / 1.1 / 4.8 deg/s against
    SITL's 0.14 / 0.14 / 2.7), IMU0 AccZ power (was 65x / 40x SITL's at 2-6 / 6-12.5 Hz) and
    VIBE z."""
    r = results["normal_s11"]
    for ax in ("roll", "pitch"):
        assert r[f"rate_err_{ax}"]["tlm"] == pytest.approx(r[f"rate_err_{ax}"]["sitl"], abs=0.06)
    assert r["rate_err_yaw"]["tlm"] == pytest.approx(r["rate_err_yaw"]["sitl"], rel=0.2)
    for band in ("0_2hz", "2_6hz", "6_12.5hz"):
        a, b = r[f"imu_acc_psd_{band}"]["tlm"], r[f"imu_acc_psd_{band}"]["sitl"]
        assert b / 4.0 < a < b * 4.0, band
    assert r["vibe_z"]["tlm"] == pytest.approx(r["vibe_z"]["sitl"], rel=0.2)


@pytest.mark.parametrize("name", ["engine_s14", "combined_s21"])
def test_engine_fall_agrees(results, name):
    """Motor 1 cut: the coning fall (thrust-axis-first attitude control, heading error capped,
    yaw left alone beyond 60 deg of thrust error) reaches the ground in SITL's time at SITL's
    speed."""
    f = [x for x in results[name]["faults"] if x["type"] == "engine"][0]
    tlm, sitl = f["tlm"], f["sitl"]
    assert tlm["ground_s"] == pytest.approx(sitl["ground_s"], abs=0.3)
    assert tlm["impact_speed_ms"] == pytest.approx(sitl["impact_speed_ms"], abs=1.0)
    assert tlm["roll_max_3s_deg"] == pytest.approx(sitl["roll_max_3s_deg"], abs=20.0)
    assert tlm["above_10m_after_end_s"] == pytest.approx(sitl["above_10m_after_end_s"], abs=1.5)


@pytest.mark.parametrize("name", ["gps_s12", "combined_s21"])
def test_gps_loss_flyaway_and_return_agree(results, name):
    """GPS loss with FS_EKF_THRESH 0: dead reckoning for 15 s, then the EKF stops aiding, the
    position controller's estimate is the EKF origin and the copter leans at ANGLE_MAX away
    from its path until GPS returns, then flies back (docs/crosscheck.md). Measured gps_s12: top
    speed 11.4 / 12.0 m/s (tlm / SITL), pitch 33 / 35 deg, path after the end 92 / 98 m,
    trajectory RMS after the recovery 0.26 m (3.8 m before issue 8)."""
    r = results[name]
    f = [x for x in r["faults"] if x["type"] == "gps"][0]
    tlm, sitl = f["tlm"], f["sitl"]
    assert tlm["speed_max_ms"] == pytest.approx(sitl["speed_max_ms"], abs=1.0)
    assert tlm["pitch_max_deg"] == pytest.approx(sitl["pitch_max_deg"], abs=3.0)
    assert tlm["path_after_end_m"] == pytest.approx(sitl["path_after_end_m"], rel=0.15)
    assert tlm["ekf_recovered_after_end_s"] < 1.0 and sitl["ekf_recovered_after_end_s"] < 1.0
    assert r["trajectory_rms_settled_m"] < 0.5
    assert r["altitude_rms_m"] < (0.6 if name == "gps_s12" else 1.5)


def test_rc_fault_signature_matches(results):
    f = results["rc_s15"]["faults"][0]
    assert f["type"] == "rc"
    tlm, sitl = f["tlm"], f["sitl"]
    assert tlm["rtl_delay_s"] == pytest.approx(sitl["rtl_delay_s"], abs=0.3)
    assert tlm["rtl_reason"] == sitl["rtl_reason"] == 3
    assert tlm["disarm_s"] == pytest.approx(sitl["disarm_s"], abs=8.0)
    assert tlm["final_home_dist_m"] < 2.0 and sitl["final_home_dist_m"] < 2.0


def test_scenario_from_the_log_alone_matches_the_sidecar(tmp_path):
    src = reference_path("combined_s21.bin")
    alone = tmp_path / "combined.bin"
    shutil.copy(src, alone)  # no sidecar beside it
    sc = reconstruct(alone)
    ref = reconstruct(src)
    assert sc.source == "log" and ref.source == "sidecar"
    np.testing.assert_allclose(sc.mission.waypoints[:, :2], ref.mission.waypoints[:, :2],
                               atol=2e-7)
    np.testing.assert_allclose(sc.mission.waypoints[:, 2], ref.mission.waypoints[:, 2],
                               atol=0.011)
    assert [f["type"] for f in sc.faults] == [f["type"] for f in ref.faults]
    for a, b in zip(sc.faults, ref.faults, strict=True):
        assert abs(a["start_time_us"] - b["start_time_us"]) < 1000
        assert abs(a["end_time_us"] - b["end_time_us"]) < 1000
    # both schedules put the faults at the same offsets from tlm's arming
    assert sc.schedule.to_dict() == ref.schedule.to_dict()


def test_crosscheck_command_writes_report_json_and_gates(tmp_path, capsys):
    src = str(reference_path("rc_s15.bin"))
    out, rj = tmp_path / "cc", tmp_path / "r.json"
    assert main(["crosscheck", src, "--out", str(out), "--json", str(rj),
                 "--max-flight-time-diff", "0.1", "--max-trajectory-rms", "3"]) == 0
    r = json.loads(rj.read_text())
    assert set(r["flight_time_s"]) == {"tlm", "sitl"}
    assert isinstance(r["trajectory_rms_m"], float) and r["faults"][0]["type"] == "rc"
    for f in ("report.md", "trajectory.png", "profiles.png", "imu_psd.png"):
        assert (out / f).stat().st_size > 0
    assert main(["crosscheck", src, "--max-trajectory-rms", "0.001"]) == 1
    assert "FAIL: trajectory RMS" in capsys.readouterr().out
    assert main(["crosscheck", str(tmp_path / "missing.bin")]) == 2


def test_docs_crosscheck_table_is_current(results):
    """docs/crosscheck.md must match today's simulator: regenerate it with
    ``python tools/crosscheck_all.py`` when this fails."""
    from pathlib import Path

    doc = (Path(__file__).resolve().parents[1] / "docs" / "crosscheck.md").read_text()
    rows = {ln.split("|")[1].strip(): [c.strip() for c in ln.split("|")[2:-1]]
            for ln in doc.splitlines() if ln.startswith("| ") and "---" not in ln}
    for k, name in enumerate(LOGS):
        r = results[name]
        assert float(rows["trajectory_rms_m"][k]) == pytest.approx(
            r["trajectory_rms_m"], rel=0.05, abs=0.05), name
        tlm_ft = float(rows["flight_time_s (tlm / SITL)"][k].split("/")[0])
        assert tlm_ft == pytest.approx(r["flight_time_s"]["tlm"], abs=1.0), name


def test_wind_cruise_attitude_agrees_with_sitl():
    """SITL's wind (normal_wind_s41: SIM_WIND_SPD 5, SIM_WIND_DIR 45, SIM_WIND_TURB 1) shakes
    the cruise attitude (crosscheck's cruise: AUTO + 20 s to 60 s before disarming, turns and
    the return included): roll std 3.7 deg against 2.5 calm (normal_s11), pitch mean -8.4 deg
    with std 6.6 against -6.4 / 2.5. tlm flying the same wind (issue 20's targets): roll and
    pitch standard deviations within 30 %, pitch mean within 2 deg (measured: 3.72 / 6.59 /
    -8.42 deg against SITL's 3.74 / 6.61 / -8.39), and calm air as calm as SITL's."""
    wind = crosscheck(reference_path("normal_wind_s41.bin"))
    calm = crosscheck(reference_path("normal_s11.bin"))
    for r in (wind, calm):
        assert gate(r, 0.05, 3.0) == []
        for k in ("att_roll_std_deg", "att_pitch_std_deg"):
            assert r[k]["tlm"] == pytest.approx(r[k]["sitl"], rel=0.3), k
        assert abs(r["att_pitch_mean_deg"]["tlm"] - r["att_pitch_mean_deg"]["sitl"]) <= 2.0
    for side in ("tlm", "sitl"):  # the wind is there on both sides
        assert wind["att_roll_std_deg"][side] > 1.3 * calm["att_roll_std_deg"][side]
        assert wind["att_pitch_std_deg"][side] > 2 * calm["att_pitch_std_deg"][side]


def test_mission_from_cmd_keeps_what_tlm_flies_and_refuses_the_rest():
    """A log's CMD items go through the mission-file rules: a hold time and a speed change are
    flown (not dropped), a parameter tlm does not fly is a ScenarioError naming the item."""
    import pandas as pd

    from tlm_process.crosscheck.scenario import ScenarioError, mission_from_cmd

    home = (-35.363261, 149.16523, 584.09)

    def cmd(rows):
        cols = ["TimeUS", "CTot", "CNum", "CId", "Prm1", "Prm2", "Prm3", "Prm4", "Lat", "Lng",
                "Alt", "Frame"]
        return pd.DataFrame([(0, len(rows), k, *r) for k, r in enumerate(rows)], columns=cols)

    base = [(16, 0, 0, 0, 0, 0.0, 0.0, 0.0, 0), (22, 0, 0, 0, 0, 0.0, 0.0, 10.0, 3)]
    wp = [(16, 5, 0, 0, 0, -35.3630, 149.1650, 12.0, 3), (178, 1, 3.0, -1, 0, 0.0, 0.0, 0.0, 0),
          (16, 0, 0, 0, 0, -35.3620, 149.1650, 12.0, 3), (20, 0, 0, 0, 0, 0.0, 0.0, 0.0, 0)]
    m = mission_from_cmd(cmd(base + wp), home, "t")
    assert m.takeoff_alt == 10.0 and list(m.hold_s) == [5.0, 0.0]
    assert np.isnan(m.speed_changes[0]) and m.speed_changes[1] == 3.0
    bad = list(wp)
    bad[0] = (16, 5, 2.0, 0, 0, -35.3630, 149.1650, 12.0, 3)  # acceptance radius 2 m
    with pytest.raises(ScenarioError, match=r"t CMD item:2: NAV_WAYPOINT param2"):
        mission_from_cmd(cmd(base + bad), home, "t")
