"""IMU sensor model pieces with known answers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tlm_sim.params import Params
from tlm_sim.rng import new_streams
from tlm_sim.sensors import layout as S
from tlm_sim.sensors.config import build_sensor_config
from tlm_sim.sensors.imu import gyro_drift


def _cfg(speed_deg: float, time_min: float) -> np.ndarray:
    return build_sensor_config(Params({"SIM_DRIFT_SPEED": speed_deg, "SIM_DRIFT_TIME": time_min}))


def test_gyro_drift_is_sitls_triangle_wave() -> None:
    """SIM_DRIFT_SPEED [deg/s per minute] for SIM_DRIFT_TIME minutes up, as long down."""
    cfg = _cfg(0.05, 5.0)
    peak = math.radians(0.05) * 5.0
    assert gyro_drift(0.0, cfg) == 0.0
    assert gyro_drift(150.0, cfg) == pytest.approx(peak / 2)
    assert gyro_drift(300.0, cfg) == pytest.approx(peak)
    assert gyro_drift(450.0, cfg) == pytest.approx(peak / 2)
    assert gyro_drift(600.0, cfg) == pytest.approx(0.0, abs=1e-15)
    assert gyro_drift(750.0, cfg) == pytest.approx(peak / 2)  # second period
    assert gyro_drift(100.0, _cfg(0.0, 5.0)) == 0.0
    assert gyro_drift(100.0, _cfg(0.05, 0.0)) == 0.0


@settings(max_examples=60, deadline=None)
@given(t_s=st.floats(0.0, 20_000.0))
def test_gyro_drift_is_periodic_and_bounded(t_s: float) -> None:
    cfg = _cfg(0.05, 5.0)
    d = gyro_drift(t_s, cfg)
    assert 0.0 <= d <= cfg[S.C_DRIFT_SPEED] * cfg[S.C_DRIFT_TIME] * (1 + 1e-12)
    assert gyro_drift(t_s + 600.0, cfg) == pytest.approx(d, abs=1e-12)


def _sample_run(cfg: np.ndarray, ticks: int = 2000) -> tuple[np.ndarray, np.ndarray]:
    """imu_sample for ``ticks`` physics ticks at hover (motors on) from a level, resting
    truth state; returns the sensor state and the noise streams after."""
    from tlm_sim.dynamics import layout as X
    from tlm_sim.sensors.imu import imu_init, imu_sample

    x = np.zeros(X.N_STATE)
    x[X.SQW] = 1.0
    x[X.SFZ] = -9.80665
    s = np.zeros(S.N_SENSOR_STATE)
    imu_init(s, cfg, 0.0)
    rng = new_streams(7, S.N_NOISE_STREAMS)
    pwm = np.full(4, 1400.0)
    for k in range(1, ticks + 1):
        imu_sample(s, x, cfg, k * 833.0, 0.4, pwm, rng)
    return s, rng


def test_a_failed_accelerometer_leaves_every_other_sensors_noise_as_it_was() -> None:
    """One noise stream per sensor (issue 18 step 6): SIM_ACCEL1_FAIL stops IMU 0's accel
    draws, and the gyros, IMU 1's accel and the GPS/baro/compass streams draw exactly what they
    drew without the fault (with one shared stream they all shifted)."""
    healthy, rng_h = _sample_run(build_sensor_config(Params()))
    failed, rng_f = _sample_run(build_sensor_config(Params({"SIM_ACCEL1_FAIL": 1.0})))
    for i in range(S.N_IMU):
        b = S.IMU_BASE + i * S.IMU_STRIDE
        np.testing.assert_array_equal(failed[b + S.I_DANG:b + S.I_DANG + 3],
                                      healthy[b + S.I_DANG:b + S.I_DANG + 3])
    b1 = S.IMU_BASE + S.IMU_STRIDE
    np.testing.assert_array_equal(failed[b1 + S.I_DVEL:b1 + S.I_DVEL + 3],
                                  healthy[b1 + S.I_DVEL:b1 + S.I_DVEL + 3])
    assert not np.array_equal(rng_f[S.RNG_ACC], rng_h[S.RNG_ACC])  # IMU 0 drew nothing
    others = [r for r in range(S.N_NOISE_STREAMS) if r != S.RNG_ACC]
    np.testing.assert_array_equal(rng_f[others], rng_h[others])
    start = new_streams(7, S.N_NOISE_STREAMS)
    rows = [S.RNG_GPS, S.RNG_BARO, S.RNG_MAG]
    np.testing.assert_array_equal(rng_h[rows], start[rows])  # the IMUs draw from their own rows
