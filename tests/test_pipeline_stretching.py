"""Window stretching (Eq. 5): the formula, the paper's Tables 7/8, FaultSchedule.stretched."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from tlm_process.pipeline import (
    PAPER_TABLE_7,
    PAPER_TABLE_8,
    PipelineError,
    class_counts,
    fault_share,
    format_counts,
    implied_lambda,
    lambda_for_target,
    stretch_schedule,
    target_for_lambda,
)
from tlm_sim.faults import FaultSchedule, FaultScheduleError

# --- the formula ---------------------------------------------------------------------------


def test_lambda_hand_worked():
    # 100 rows, 25 of them faults: alpha 0.25; target 50 % -> twice the fault time
    assert lambda_for_target(0.25, 0.5) == pytest.approx(2.0)
    assert target_for_lambda(0.25, 2.0) == pytest.approx(0.5)
    # added model: 25 fault rows x lambda over 75 + 25 lambda rows = 0.5 -> lambda = 3
    assert lambda_for_target(0.25, 0.5, "added") == pytest.approx(3.0)
    assert target_for_lambda(0.25, 3.0, "added") == pytest.approx(0.5)
    assert 75 / (75 + 25 * 3.0) == pytest.approx(0.5)
    # shrinking: 40 % -> 20 % halves the windows
    assert lambda_for_target(0.4, 0.2) == pytest.approx(0.5)


@pytest.mark.parametrize("alpha,gamma", [(0.0, 0.5), (1.0, 0.5), (0.3, 0.0), (0.3, 1.0),
                                         (-0.1, 0.5), (math.nan, 0.5), (0.3, 1.5)])
def test_lambda_rejects_shares_outside_0_1(alpha, gamma):
    with pytest.raises(PipelineError):
        lambda_for_target(alpha, gamma)


def test_target_for_lambda_rejects_more_fault_than_flight():
    with pytest.raises(PipelineError, match="more than all fault"):
        target_for_lambda(0.6, 2.0)
    with pytest.raises(PipelineError, match="lambda"):
        target_for_lambda(0.3, 0.0)
    assert target_for_lambda(0.6, 2.0, "added") == pytest.approx(1.2 / 1.6)


def test_class_counts_and_fault_share():
    tables = {"GPS": pd.DataFrame({"label": [0, 0, 0, 1, 1, 4, 0, 0]}),
              "IMU": pd.DataFrame({"label": np.r_[np.zeros(30, int), np.full(10, 3)]})}
    c = class_counts(tables)
    assert c.loc["GPS"].tolist() == [5, 2, 0, 0, 1, 8]
    assert c.loc["IMU"].tolist() == [30, 0, 0, 10, 0, 40]
    a = fault_share(c)
    assert a["GPS"] == pytest.approx(3 / 8) and a["IMU"] == pytest.approx(0.25)
    assert "37.50%" in format_counts(c)
    with pytest.raises(PipelineError, match="label"):
        class_counts({"GPS": pd.DataFrame({"x": [1]})})


# --- the paper's Tables 7 and 8 --------------------------------------------------------------


def test_paper_table_7_and_8_shares_as_the_paper_states():
    a7, a8 = fault_share(PAPER_TABLE_7), fault_share(PAPER_TABLE_8)
    assert PAPER_TABLE_7.iloc[:, :5].sum(axis=1).tolist() == PAPER_TABLE_7["Total"].tolist()
    assert PAPER_TABLE_8.iloc[:, :5].sum(axis=1).tolist() == PAPER_TABLE_8["Total"].tolist()
    # "the normal data comprised 74.21%, ... abnormal 25.79%" (GPS)
    assert 100 * a7["GPS"] == pytest.approx(25.79, abs=0.005)
    # "faults account for 54.27% ... increases the fault data by 28.48%" (GPS, truncated)
    assert 100 * a8["GPS"] == pytest.approx(54.27, abs=0.01)
    assert 100 * (a8["GPS"] - a7["GPS"]) == pytest.approx(28.48, abs=0.01)


def test_paper_implied_lambda_reproduces_table_8_from_table_7():
    lam = implied_lambda(PAPER_TABLE_7, PAPER_TABLE_8)
    assert lam["GPS"] == pytest.approx(4284 / 7893 / (659 / 2555))
    assert lam.round(1).tolist() == [2.1, 2.1, 2.1, 2.1]  # one lambda for every table
    a7 = fault_share(PAPER_TABLE_7)
    for table in ("IMU", "RATE", "VIBE"):
        gamma = target_for_lambda(a7[table], lam["GPS"])  # Table 8 predicted from GPS' lambda
        faults_pred = gamma * PAPER_TABLE_8.loc[table, "Total"]
        faults_8 = PAPER_TABLE_8.loc[table, "Total"] - PAPER_TABLE_8.loc[table, "Normal"]
        assert abs(faults_pred - faults_8) / PAPER_TABLE_8.loc[table, "Total"] < 0.0015
    # the 'added' model would need a lambda of about 3.4 for the same shares
    assert implied_lambda(PAPER_TABLE_7, PAPER_TABLE_8, "added").round(1).tolist() == [3.4] * 4


# --- FaultSchedule.stretched ----------------------------------------------------------------


def _spans(s: FaultSchedule) -> list[float]:
    return [f.end.value - f.start.value for f in s]


def _gaps(s: FaultSchedule) -> list[float]:
    return [b.start.value - a.end.value for a, b in zip(s, list(s)[1:], strict=False)]


def test_stretched_scales_windows_and_keeps_gaps():
    base = FaultSchedule.paper(21)
    for lam in (2.0, 0.5, 1.37):
        s = base.stretched(lam)
        assert [f.type for f in s] == [f.type for f in base]
        assert s[0].start == base[0].start
        assert _spans(s) == pytest.approx([lam * d for d in _spans(base)], abs=2e-6)
        assert _gaps(s) == pytest.approx(_gaps(base), abs=2e-6)
    assert base.stretched(1.0) == base
    assert stretch_schedule(base, 2.0) == base.stretched(2.0)


def test_stretched_without_shift_keeps_starts_or_reports_overlap():
    s = FaultSchedule.from_shorthand(["gps:60-70", "rc:100-110"])
    kept = s.stretched(2.0, shift=False)
    assert [f.start.value for f in kept] == [60.0, 100.0]
    assert [f.end.value for f in kept] == [80.0, 120.0]
    with pytest.raises(FaultScheduleError, match=r"fault 2 \(rc\): stretched by lambda 5.*"
                                                 "must not overlap"):
        s.stretched(5.0, shift=False)


def test_stretched_past_the_flight_is_an_error():
    s = FaultSchedule.from_shorthand(["gps:60-100", "rc:120-150"])
    assert s.stretched(2.0, max_time_s=400)[1].end.value == 220.0  # 160 + 2 x 30
    with pytest.raises(FaultScheduleError, match="after the end of the flight"):
        s.stretched(2.0, max_time_s=200)


def test_stretched_waypoint_windows_count_waypoints():
    s = FaultSchedule.from_shorthand(["gps:wp10-wp14", "accel:wp20-wp21", "rc:wp40-"])
    t = s.stretched(2.2)
    # 4 wp -> round(8.8) = 9 (5 added: the next start moves 5 on); 1 wp -> round(2.2) = 2
    # (1 more: the last start moves 5 + 1 on)
    assert [(f.start.to_value(), f.end.to_value() if f.end else None) for f in t] == [
        ("wp10", "wp19"), ("wp25", "wp27"), ("wp46", None)]
    assert s.stretched(0.1)[0].end.to_value() == "wp11"  # at least one waypoint
    with pytest.raises(FaultScheduleError, match="beyond the mission's last waypoint"):
        s.stretched(2.2, n_waypoints=40)


def test_stretched_rejects_mixed_windows_and_bad_lambda():
    with pytest.raises(FaultScheduleError, match="both be times or both waypoints"):
        FaultSchedule.from_shorthand(["gps:wp10-140"]).stretched(2.0)
    for bad in (0, -1.0, math.inf, math.nan, "2", True):
        with pytest.raises(FaultScheduleError, match="lambda"):
            FaultSchedule.paper(1).stretched(bad)


def test_stretched_held_fault_unchanged():
    s = FaultSchedule.from_shorthand(["gps:60-70", "rc:100-"])
    t = s.stretched(3.0)
    assert t[1].end is None and t[1].start.value == 120.0


def test_stretched_schedule_is_flown_with_stretched_windows():
    from tlm_sim import fly

    base = FaultSchedule.from_shorthand(["gps:40-60", "accel:80-90"])
    log = fly(1, faults=base.stretched(1.5), seed=2)
    durations = [r["duration_s"] for r in log.faults]
    assert durations == pytest.approx([30.0, 15.0], abs=0.005)  # one 400 Hz loop tick
    # the accel fault keeps its 20 s gap after the stretched GPS fault (ends at 70 s)
    assert [r["start_time_us"] * 1e-6 for r in log.faults] == pytest.approx([40.0, 90.0],
                                                                             abs=0.005)
