"""Measuring a vehicle in one log (issue 40, the measuring half of ``tlm fit``): steady
segments and their statistics on the real log171.bin (Copter 3.3, TimeMS, RATE in cdeg/s) and
on tlm's own flights."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from tests.conftest import flown, real_path
from tlm_process.fit.segment import parse_segment, steady_segments
from tlm_process.fit.stats import STAT_NAMES, StatsError, rate_unit, segment_stats


def _real171():
    from tlm_process.logread import read_log_tables

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return read_log_tables(real_path("log171.bin")).tables


def test_rate_unit_is_read_from_the_log():
    """Copter 3.3 logs RATE in centidegrees per second, 4.x (and tlm) in degrees per second."""
    assert rate_unit(_real171()) == 0.01
    assert rate_unit(flown(1).tables) == 1.0


def test_real_log_steady_segment_is_its_loiter_hover():
    """log171: the longest steady segment is the LOITER hover before the pilot's ACRO switch at
    217.2 s; nothing after the crash (inverted at full throttle) counts."""
    segs = steady_segments(_real171())
    t0, t1 = segs[0]
    assert 195e6 <= t0 < 200e6 and 214e6 < t1 <= 217.2e6
    assert all(b <= 230e6 for _, b in segs)


def test_real_log_statistics():
    """log171's hover: ~0.4 throttle, accel noise largest on x, gyro noise of several deg/s on
    roll, RATE error in deg/s (not cdeg/s), no VIBE in a 3.3 log."""
    t = _real171()
    s = segment_stats(t, 197.5e6, 216.5e6)
    assert list(s) == list(STAT_NAMES)
    assert 0.35 < s["hover_thr"] < 0.45
    assert s["acc_x_std"] > s["acc_y_std"] and 0.2 < s["acc_x_std"] < 0.8
    assert 2.0 < s["gyr_x_std_dps"] < 20.0
    assert 2.0 < s["rate_roll_err_std_dps"] < 20.0
    assert all(math.isnan(s[f"vibe_{a}"]) for a in "xyz")


def test_tlm_flight_statistics_are_sitl_quiet():
    """tlm's default flight measured the same way: SITL-quiet (issue 40's table: gyro std
    ~0.1 deg/s, VIBE ~0.005 m/s^2) and hover throttle ~0.36."""
    t = flown(1).tables
    t0, t1 = steady_segments(t)[0]
    s = segment_stats(t, t0, t1)
    assert 0.3 < s["hover_thr"] < 0.45
    assert s["gyr_x_std_dps"] < 0.5 and s["vibe_z"] < 0.05
    assert np.isfinite([s[k] for k in STAT_NAMES]).all()


def test_stats_need_rows_and_segment_text_is_checked():
    with pytest.raises(StatsError, match="no IMU rows"):
        segment_stats(flown(1).tables, 1e12, 2e12)
    assert parse_segment("197.5:207") == (197.5e6, 207e6)
    for bad in ("10", "a:b", "20:10", "-1:5"):
        with pytest.raises(StatsError):
            parse_segment(bad)
