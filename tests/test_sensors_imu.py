"""IMU sensor model pieces with known answers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tlm_sim.params import Params
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
