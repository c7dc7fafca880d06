"""Detection delay and false alarms per flight hour (:mod:`tlm_process.evaluate.events`):
hand-made label/prediction sequences with analytic answers, invariants with hypothesis, and
one pass through :func:`tlm_process.evaluate.runner.evaluate` on a small synthetic data set."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tlm_process.evaluate.events import (
    PERSISTENCE_S,
    detection_summary,
    event_delays,
    false_alarms,
    format_detection_table,
)


def _seq(*parts: tuple[int, int]) -> np.ndarray:
    """Labels from (label, rows) parts."""
    return np.concatenate([np.full(n, lab, dtype=np.int64) for lab, n in parts])


def _one(y, p, hz: float = 10.0, flight: str = "A", t0_us: int = 0):
    t = t0_us + np.round(np.arange(len(y)) * 1e6 / hz).astype(np.int64)
    return np.full(len(y), flight), t, np.asarray(y), np.asarray(p)


def test_late_detection_and_wrong_class_first():
    y = _seq((0, 20), (1, 30), (0, 20))
    p = y.copy()
    p[20:28] = 2  # the first 0.8 s of the GPS fault called Acc
    ev = event_delays(*_one(y, p))
    assert ev["label"].tolist() == [1] and ev["start_s"][0] == pytest.approx(2.0)
    assert ev["cover_s"][0] == pytest.approx(3.0)
    assert ev["delay_s"][0] == pytest.approx(0.8)
    assert ev["delay_any_s"][0] == 0.0  # something was reported at once
    assert false_alarms(*_one(y, p)) == (0, pytest.approx(4.0 / 3600))


def test_flicker_is_never_a_sustained_detection():
    y = _seq((0, 10), (3, 60))
    p = y.copy()
    p[10::6] = 0  # every 6th fault row called normal: runs of 5 rows = 0.5 s
    ev = event_delays(*_one(y, p))
    assert math.isnan(ev["delay_s"][0]) and math.isnan(ev["delay_any_s"][0])
    p[10::10] = 0
    p[10:] = np.where(np.arange(60) % 10 == 0, 0, 3)  # runs of 9 rows = 0.9 s: still not
    assert math.isnan(event_delays(*_one(y, p))["delay_s"][0])
    p[10:] = np.where(np.arange(60) % 11 == 0, 0, 3)  # runs of 10 rows = 1.0 s: detected
    assert event_delays(*_one(y, p))["delay_s"][0] == pytest.approx(0.1)


def test_persistence_is_time_not_rows():
    """5 GPS rows (5 Hz) and 25 IMU rows (25 Hz) are 1 s; 4 and 24 are not (timestamps with
    the logs' jitter: GPS rows 199.92 ms apart)."""
    for hz, n in ((1e6 / 199_920, 5), (25.0, 25), (10.0, 10)):
        y = _seq((0, 3), (2, 40))
        for k, detected in ((n, True), (n - 1, False)):
            p = _seq((0, 3), (0, 10), (2, k), (0, 30 - k))
            d = event_delays(*_one(y, p, hz))["delay_s"][0]
            assert (not math.isnan(d)) is detected, (hz, k)
            if detected:
                assert d == pytest.approx(10 / hz)


def test_short_event_needs_all_its_rows():
    y = _seq((0, 20), (4, 3), (0, 20))  # a 0.3 s event
    assert event_delays(*_one(y, y))["delay_s"][0] == 0.0
    p = y.copy()
    p[20] = 0
    assert math.isnan(event_delays(*_one(y, p))["delay_s"][0])


def test_false_alarms_early_alarms_and_lingering_alarms():
    y = _seq((0, 40), (1, 30), (0, 40))
    p = y.copy()
    p[5:15] = 5  # 1.0 s on normal rows: a false alarm
    p[17:19] = 1  # 0.2 s: a flicker, not an alarm
    p[32:40] = 1  # begins 0.8 s before the fault: an early detection (delay 0)
    p[70:90] = 1  # lingers 2 s after the fault: neither
    fa, hours = false_alarms(*_one(y, p))
    assert fa == 1 and hours == pytest.approx(8.0 / 3600)
    assert event_delays(*_one(y, p))["delay_s"][0] == 0.0
    p[25:40] = 1  # begins 1.5 s before the fault: a false alarm, and still a detection
    assert false_alarms(*_one(y, p))[0] == 2
    assert event_delays(*_one(y, p))["delay_s"][0] == 0.0
    p[95:110] = 2  # a run changing class is one alarm; the flight's end stops it
    p[100:110] = 7
    assert false_alarms(*_one(y, p))[0] == 3


def test_runs_and_events_stop_at_flight_boundaries_and_order_does_not_matter():
    ya, pa = _seq((0, 20), (1, 6)), _seq((0, 20), (1, 6))
    yb, pb = _seq((1, 6), (0, 20)), _seq((1, 6), (0, 20))
    a, b = _one(ya, pa, flight="A"), _one(yb, pb, flight="B", t0_us=2_600_000)
    both = [np.concatenate(x) for x in zip(a, b, strict=True)]
    ev = event_delays(*both)
    assert ev["label"].tolist() == [1, 1]  # one event per flight, not one of 12 rows
    assert ev["delay_s"].tolist() == [0.0, 0.0]  # each event is 0.6 s: all rows needed
    pa2, pb2 = _seq((0, 20), (2, 6)), _seq((2, 6), (0, 20))  # 0.6 s + 0.6 s of Acc
    both2 = [np.concatenate(x) for x in zip(_one(_seq((0, 26)), pa2, flight="A"),
                                            _one(_seq((0, 26)), pb2, flight="B",
                                                 t0_us=2_600_000), strict=True)]
    assert false_alarms(*both2)[0] == 0  # not 1.2 s across the two flights
    rng = np.random.default_rng(0)
    perm = rng.permutation(len(both[0]))
    assert detection_summary(*[x[perm] for x in both]) == detection_summary(*both)


def test_summary_per_class_and_the_table():
    hz = 10.0
    y = _seq((0, 50), (1, 40), (0, 50), (1, 40), (0, 50), (3, 40), (0, 50))
    p = y.copy()
    p[50:55] = 0  # GPS event 1: 0.5 s late
    p[140:180] = 0  # GPS event 2: missed
    p[230:245] = 2  # Engine called Acc for 1.5 s
    p[300:320] = 9  # a false alarm
    s = detection_summary(*_one(y, p, hz))
    gps, eng = s["detection"]["GPS"], s["detection"]["Engine"]
    assert list(s["detection"]) == ["GPS", "Engine"]
    assert (gps["events"], gps["detected"], gps["detected_any"]) == (2, 1, 1)
    assert gps["delay_median_s"] == pytest.approx(0.5) == gps["delay_p90_s"]
    assert eng["delay_median_s"] == pytest.approx(1.5) and eng["delay_any_median_s"] == 0.0
    assert s["false_alarms"] == 1 and s["normal_hours"] == pytest.approx(20.0 / 3600)
    assert s["false_alarms_per_hour"] == pytest.approx(180.0)
    assert s["persistence_s"] == PERSISTENCE_S
    text = format_detection_table({"M": s, "Z": {"accuracy": 1.0}}, "title")
    assert text.splitlines()[1].split() == ["Method", "FA", "FA/h", "GPS", "Engine"]
    assert text.splitlines()[2].split() == ["M", "1", "180.00", "0.5", "(1/2)", "1.5", "(1/1)"]
    assert format_detection_table({"M": s}, transfer=True) == ""


def test_no_events_no_normal_rows_and_no_rows():
    s = detection_summary(*_one(_seq((0, 30)), _seq((0, 30))))
    assert s["detection"] == {} and s["false_alarms"] == 0
    s = detection_summary(*_one(_seq((2, 30)), _seq((0, 30))))
    assert s["detection"]["Acc"]["detected"] == 0
    assert math.isnan(s["detection"]["Acc"]["delay_median_s"])
    assert math.isnan(s["false_alarms_per_hour"])
    e = np.empty(0, dtype=np.int64)
    assert detection_summary(e.astype(str), e, e, e)["detection"] == {}


# --- invariants -----------------------------------------------------------------------------

_rates = st.sampled_from([5.0, 10.0, 25.0, 50.0])


@st.composite
def _flights(draw):
    """Several flights of label runs (labels 0-13) at one rate."""
    hz = draw(_rates)
    flights, times, labels = [], [], []
    for i in range(draw(st.integers(1, 4))):
        runs = draw(st.lists(st.tuples(st.integers(0, 13), st.integers(1, 40)), min_size=1,
                             max_size=8))
        y = _seq(*runs)
        f, t, y, _ = _one(y, y, hz, flight=f"f{i}", t0_us=draw(st.integers(0, 10**9)))
        flights.append(f)
        times.append(t)
        labels.append(y)
    return np.concatenate(flights), np.concatenate(times), np.concatenate(labels)


@settings(max_examples=60, deadline=None)
@given(_flights())
def test_perfect_predictions_detect_every_event_at_once_with_no_false_alarm(rows):
    f, t, y = rows
    ev = event_delays(f, t, y, y)
    assert (ev["delay_s"] == 0).all() and (ev["delay_any_s"] == 0).all()
    assert false_alarms(f, t, y, y)[0] == 0
    assert all(d["detected"] == d["events"] for d in detection_summary(f, t, y, y)[
        "detection"].values())
    none = np.zeros_like(y)  # a model that never reports anything: no alarm, nothing found
    assert false_alarms(f, t, y, none)[0] == 0
    assert np.isnan(event_delays(f, t, y, none)["delay_s"]).all()


@settings(max_examples=60, deadline=None)
@given(hz=_rates, label=st.integers(1, 13), before=st.integers(1, 30),
       length=st.integers(1, 200), after=st.integers(0, 30), k=st.integers(0, 200),
       other=st.integers(0, 13))
def test_predictions_late_by_k_rows_are_detected_k_rows_late(hz, label, before, length,
                                                            after, k, other):
    y = _seq((0, before), (label, length), (0, after))
    p = np.roll(y, k) if k < len(y) else np.zeros_like(y)
    p[:min(k, len(y))] = 0 if other == label else other  # whatever came before
    need = max(1, round(PERSISTENCE_S * hz))  # rows 1 s covers
    d = event_delays(*_one(y, p, hz))["delay_s"][0]
    if k == 0:
        assert d == 0
    elif length - k >= need:
        assert d == pytest.approx(k / hz, abs=1e-6)
    else:
        assert math.isnan(d)


@settings(max_examples=40, deadline=None)
@given(_flights(), st.data())
def test_flights_add_up_and_row_order_does_not_matter(rows, data):
    f, t, y = rows
    p = np.asarray(data.draw(st.lists(st.integers(0, 13), min_size=len(y), max_size=len(y))))
    whole = detection_summary(f, t, y, p)
    perm = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1))).permutation(len(y))
    assert detection_summary(f[perm], t[perm], y[perm], p[perm]) == whole
    fa = hours = 0
    events = {}
    for g in np.unique(f):
        at = f == g
        s = detection_summary(f[at], t[at], y[at], p[at])
        fa += s["false_alarms"]
        hours += s["normal_hours"]
        for c, d in s["detection"].items():
            e = events.setdefault(c, [0, 0])
            e[0] += d["events"]
            e[1] += d["detected"]
    assert whole["false_alarms"] == fa and whole["normal_hours"] == pytest.approx(hours)
    assert {c: [d["events"], d["detected"]] for c, d in whole["detection"].items()} == events


# --- through evaluate() ---------------------------------------------------------------------


def _synthetic_ds():
    """Six flights at 5 Hz (GPS-like), two faults each; feature ``x`` is the label plus
    noise, ``n`` noise: a tree finds the labels, ZeroR says Normal throughout. Flights f4,
    f5 are the test flights."""
    from tlm_process.evaluate.data import EvalDataset

    rng = np.random.default_rng(1)
    frames = []
    for i in range(6):
        y = _seq((0, 100), (1, 50), (0, 100), (3 if i % 2 else 4, 50), (0, 100))
        frames.append(pd.DataFrame({
            "flight": f"f{i}", "split": "test" if i >= 4 else "train",
            "TimeUS": 10**6 + np.arange(len(y)) * 200_000, "label": y,
            "x": y + 0.05 * rng.standard_normal(len(y)), "n": rng.standard_normal(len(y))}))
    df = pd.concat(frames, ignore_index=True)
    return EvalDataset(None, {"GPS": df}, {"GPS": ["x", "n"]}, None, {}), frames[5]


def test_evaluate_reports_detection_and_false_alarms_in_domain_and_on_transfer_rows():
    from tlm_process.evaluate.runner import evaluate

    ds, xfer = _synthetic_ds()
    res = evaluate(ds, models=["ZeroR", "J48"], transfer={"GPS": xfer}, n_jobs=1)["GPS"]
    j48, zr = res["J48"], res["ZeroR"]
    assert j48["accuracy"] > 0.99
    assert j48["detection"]["GPS"] == {
        "events": 2, "detected": 2, "detected_frac": 1.0, "delay_median_s": 0.0,
        "delay_p90_s": 0.0, "detected_any": 2, "delay_any_median_s": 0.0,
        "delay_any_p90_s": 0.0}
    assert set(j48["detection"]) == {"GPS", "Engine", "RC"}  # test flights f4 (RC), f5
    assert j48["false_alarms"] == 0 and j48["normal_hours"] == pytest.approx(2 * 300 / 5
                                                                             / 3600)
    assert zr["detection"]["GPS"]["detected"] == 0 and zr["false_alarms_per_hour"] == 0
    t = j48["transfer"]  # flight f5 again
    assert set(t["detection"]) == {"GPS", "Engine"} and t["false_alarms"] == 0
    assert t["detection"]["Engine"]["detected"] == 1
    # cross-validation: every flight tested once, the events of all folds pooled
    cv = evaluate(ds, models=["J48"], folds=3, n_jobs=1)["GPS"]["J48"]
    assert cv["detection"]["GPS"]["events"] == 6
    assert cv["detection"]["Engine"]["events"] == cv["detection"]["RC"]["events"] == 3
