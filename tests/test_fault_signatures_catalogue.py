"""Fault signatures of SITL's catalogue (labels 5-13): the reference README's "Measured
signatures" measured by ``fault_signature`` in the genuine SITL logs (one test per reference
flight), and tlm flying motor_partial, battery and vibration on the same missions at the same
times, measured the same way (the other types' tlm flights: tests/test_fault_<type>.py).
"""

from __future__ import annotations

import json
import math
from functools import lru_cache
from typing import Any

import numpy as np
import pytest

from tests.conftest import REFERENCE, reference_path
from tlm_process.fault_signatures import (
    SIGNATURE_MESSAGES,
    fault_signature,
    route_from_tables,
    signature_types,
)
from tlm_sim.faults import FAULT_TYPES

#: reference flight of each new fault type (README "Second set")
REFS = {"gyro": "gyro_s42", "compass": "compass_s43", "baro": "baro_s44",
        "battery": "battery_s45", "gps_glitch": "gps_glitch_s46",
        "motor_partial": "motor_partial_s47", "vibration": "vibration_s48"}
TYPES = list(SIGNATURE_MESSAGES)


@lru_cache(maxsize=8)
def _reference(name: str) -> tuple[dict, dict]:
    from tlm_sim.flightlog import read_bin

    path = reference_path(f"{name}.bin")
    return read_bin(str(path), types=TYPES), json.loads(path.with_suffix(".json").read_text())


def _sitl(kind: str) -> dict[str, float]:
    tables, side = _reference(REFS[kind])
    (fault,) = [f for f in side["faults"] if f["type"] == kind]
    return fault_signature(tables, fault)


def test_every_fault_type_has_a_signature():
    assert signature_types() == tuple(FAULT_TYPES)


# --- the SITL references: the README's numbers ----------------------------------------------


def test_reference_gyro_signature():
    s = _sitl("gyro")
    assert 0.0 < s["imu0_gh_drop_s"] <= 0.05  # the first IMU record after the set
    assert s["imu0_gh_restore_s"] == pytest.approx(30.0, abs=0.05)
    assert s["imu0_std_in"] == 0.0  # frozen
    assert s["imu0_std_before"] == pytest.approx(0.0022, abs=2e-4)  # GyrY 0.0022 rad/s
    assert s["imu1_healthy_frac_in"] == 1.0
    assert s["err24_ekf_primary"] == 0 and s["lane_changes"] == 0
    assert s["ekf_err_max_m"] < 0.2 and s["roll_max_deg"] <= 0.3 and s["auto_kept"] == 1.0


def test_reference_compass_signature():
    s = _sitl("compass")
    assert s["mag0_health_drop_s"] == pytest.approx(0.53, abs=0.01)
    assert s["mag0_health_restore_s"] == pytest.approx(30.83, abs=0.01)
    assert s["mag0_std_in"] == 0.0
    assert s["mag1_healthy_frac_in"] == 1.0 and s["mag2_healthy_frac_in"] == 1.0
    assert s["err3_4_s"] == pytest.approx(0.53, abs=0.01)
    assert s["err3_0_s"] == pytest.approx(30.83, abs=0.01)
    assert s["lane_changes"] == 0 and s["ekf_err_max_m"] < 0.2 and s["auto_kept"] == 1.0
    # both cores to compass 1: MSG "EKF3 IMUn switching to compass 1" at +10.04 s, the next
    # 10 Hz XKFS row
    assert s["switch_compass_s"] == pytest.approx(10.1, abs=0.1)
    assert s["switch_compass_to"] == 1.0 and s["err24_ekf_primary"] == 0
    assert s["sm_max"] <= 0.02


def test_reference_baro_signature():
    s = _sitl("baro")
    assert s["baro_h_drop_s"] == pytest.approx(0.09, abs=0.01)
    assert s["baro_h_restore_s"] == pytest.approx(32.09, abs=0.01)
    assert s["err18_4_s"] == pytest.approx(0.09, abs=0.01)
    assert s["err18_0_s"] == pytest.approx(32.09, abs=0.01)
    assert s["alt_invalid_s"] == pytest.approx(10.19, abs=0.01)
    assert s["climb_m"] == pytest.approx(54.6, abs=0.2)  # 20.3 m -> 74.8 m
    assert s["climb_rate_max_ms"] == pytest.approx(2.64, abs=0.02)
    assert s["thr_mean_in"] == pytest.approx(0.41, abs=0.005)
    assert s["thr_mean_before"] == pytest.approx(0.37, abs=0.005)
    assert s["descent_rate_max_ms"] == pytest.approx(1.62, abs=0.02)
    assert s["back_after_end_s"] == pytest.approx(36.5, abs=0.1)
    assert s["route_dev_max_m"] == pytest.approx(132.5, abs=0.2)
    assert s["auto_kept"] == 1.0


def test_reference_battery_signature():
    s = _sitl("battery")
    assert (s["volt_before"], s["volt_in"], s["volt_after"]) == pytest.approx(
        (12.6, 10.2, 12.6), abs=1e-3)
    assert s["thr_before"] == pytest.approx(0.36, abs=0.005)
    assert s["thr_in"] == pytest.approx(0.46, abs=0.005)
    assert s["thr_after"] == pytest.approx(0.37, abs=0.005)
    assert s["err6_1_s"] == pytest.approx(10.15, abs=0.01)  # BATT_LOW_TIMER 10 s
    assert s["err6_0_after_end"] == 0 and s["auto_kept"] == 1.0  # action none, no 6/0


def test_reference_gps_glitch_signature():
    s = _sitl("gps_glitch")
    assert s["gps_offset_n_m"] == pytest.approx(33.2, abs=0.1)
    assert s["gps_offset_e_m"] == pytest.approx(27.5, abs=0.1)
    assert s["gps_offset_m"] == pytest.approx(43.1, abs=0.1)
    assert s["err24_first_s"] == pytest.approx(0.41, abs=0.01)
    assert s["err11_2_s"] == pytest.approx(1.44, abs=0.01)
    assert s["err11_0_s"] == pytest.approx(20.24, abs=0.01)
    assert s["ekf_err_max_m"] == pytest.approx(43.3, abs=0.1)
    assert s["route_dev_max_m"] == pytest.approx(33.6, abs=0.1)
    # the same sequence after the clear (+35.8 s): 11/2 at +37.24 s, 11/0 at +56.04 s
    assert s["err11_2_after_end_s"] == pytest.approx(37.24 - 35.81, abs=0.02)
    assert s["err11_0_after_end_s"] == pytest.approx(56.04 - 35.81, abs=0.02)
    assert s["ekf_err_max_after_end_m"] == pytest.approx(43.1, abs=0.1)
    assert s["lane_changes"] == 5 and s["auto_kept"] == 1.0


def test_reference_motor_partial_signature():
    s = _sitl("motor_partial")
    assert s["thr_mean_in"] == pytest.approx(0.98, abs=0.005)
    assert s["rcou_failed_mean"] == pytest.approx(1947, abs=1)
    assert s["err25_s"] == pytest.approx(2.86, abs=0.01)
    assert 5.3 <= s["ground_s"] <= 5.5  # "SIM Hit ground" at +5.47 s; truth <= 0.5 m first
    assert s["impact_speed_ms"] == pytest.approx(5.43, abs=0.01)
    assert s["roll_max_deg"] == pytest.approx(36.4, abs=0.2)
    assert s["armed_kept"] == 1.0 and s["auto_kept"] == 1.0
    assert s["liftoff_1m_after_end_s"] == pytest.approx(1.0, abs=0.1)
    assert s["above_10m_after_end_s"] == pytest.approx(4.5, abs=0.1)


def test_reference_vibration_signature():
    s = _sitl("vibration")
    assert s["vibe0_mean"] == pytest.approx(5.73, abs=0.01)
    assert s["vibe1_mean"] == pytest.approx(6.74, abs=0.01)
    assert s["vibe0_max"] == pytest.approx(11.8, abs=0.05)
    assert s["vibe1_max"] == pytest.approx(11.5, abs=0.05)
    assert s["vibe0_before_max"] <= 0.011 and s["vibe1_before_max"] <= 0.012
    assert s["clip0_in"] == 0 and s["clip1_in"] == 0
    assert s["accz_std_before"] == pytest.approx(0.03, abs=0.005)
    assert s["accz_std_in"] == pytest.approx(0.21, abs=0.01)
    assert s["thr_mean_in"] == pytest.approx(0.37, abs=0.01)
    assert s["err29_vibe_fs"] == 0 and s["ekf_err_max_m"] < 0.25 and s["auto_kept"] == 1.0


def test_route_comes_from_cmd_or_the_sidecar():
    tables, side = _reference("gps_glitch_s46")
    route = route_from_tables(tables)
    wps = np.asarray(side["mission"]["waypoints"])[:, :2]
    assert route is not None and route.shape == wps.shape
    assert np.allclose(route, wps, atol=1e-6)
    (fault,) = side["faults"]
    assert fault_signature(tables, fault, route=wps)["route_dev_max_m"] == pytest.approx(
        33.6, abs=0.1)
    no_cmd = {k: v for k, v in tables.items() if k != "CMD"}
    assert math.isnan(fault_signature(no_cmd, fault)["route_dev_max_m"])


def test_gps_jam_signature_on_a_normal_flight_shows_a_fix():
    tables, side = _reference("gyro_s42")
    (f,) = side["faults"]
    s = fault_signature(tables, dict(f, type="gps_jam"))
    assert s["fix_frac_in"] == 1.0 and s["fix_frac_out"] == 1.0
    assert s["nsats_min_in"] == s["nsats_max_in"] == 10


# --- tlm flying the same faults -------------------------------------------------------------


@lru_cache(maxsize=4)
def _tlm(kind: str) -> tuple[dict[str, float], dict[str, float], dict[str, Any]]:
    """(tlm signature, SITL signature, flight) of the reference's mission and fault."""
    from tools.fidelity_faults import fly_like_reference

    reference_path(f"{REFS[kind]}.bin")
    flight = fly_like_reference(REFERENCE, REFS[kind])
    route = np.asarray(flight["sidecar"]["mission"]["waypoints"])[:, :2]
    return (fault_signature(flight["tlm"], flight["tlm_faults"][0], route),
            fault_signature(flight["ref"], flight["ref_faults"][0], route), flight)


def _within(tlm: dict[str, float], sitl: dict[str, float], keys: list[str],
            rel: float = 0.35) -> None:
    from tlm_process.crosscheck.compare import signature_rows

    rows = {r["metric"]: r for r in signature_rows(tlm, sitl, rel)}
    bad = [f"{k}: tlm {tlm[k]:.4g} vs SITL {sitl[k]:.4g}" for k in keys if not rows[k]["pass"]]
    assert not bad, bad


@pytest.mark.slow
def test_tlm_motor_partial_comes_down_and_lifts_off_like_sitl():
    t, s, _ = _tlm("motor_partial")
    assert t["armed_kept"] == 1.0 and t["auto_kept"] == 1.0
    assert math.isfinite(t["ground_s"]) and math.isfinite(t["above_10m_after_end_s"])
    _within(t, s, ["thr_mean_in", "ground_s", "impact_speed_ms"])


@pytest.mark.slow
def test_tlm_battery_volts_and_throttle_like_sitl():
    t, s, _ = _tlm("battery")
    assert t["volt_in"] == pytest.approx(10.2, abs=0.05)
    assert t["thr_in"] > t["thr_before"] + 0.02  # SITL +0.09
    _within(t, s, ["volt_before", "volt_in", "volt_after", "thr_before", "thr_in",
                   "thr_after"])


@pytest.mark.slow
def test_tlm_vibration_vibe_level_like_sitl():
    t, s, _ = _tlm("vibration")
    assert t["vibe0_before_max"] < 0.5 and t["vibe0_mean"] > 2.0 and t["vibe1_mean"] > 2.0
    _within(t, s, ["vibe0_before_max", "vibe0_mean", "vibe1_mean", "clip0_in", "thr_mean_in",
                   "auto_kept"])
