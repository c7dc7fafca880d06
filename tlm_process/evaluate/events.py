"""Detection delay per fault class and false alarms per flight hour, from per-row predictions.

Row metrics (:mod:`.metrics`) count rows; a fault detector is used on events: how soon after
a fault starts does it say so, and how often does it raise an alarm while nothing is wrong.
Everything here is computed from the rows a model predicted, per flight in time order
(``flight``, ``TimeUS``); any row order is accepted (rows are sorted here). Definitions
(also in ``docs/evaluation.md``, "Detection delay and false alarms"):

* Row interval ``dt`` of a flight: the median time between its consecutive rows. A run of
  ``n`` consecutive rows *covers* ``t_last - t_first + dt`` (``n * dt`` for regular rows):
  each row stands for one row interval.
* A *sustained* run covers at least the persistence time ``P`` (:data:`PERSISTENCE_S`),
  to half a row interval (``cover >= P - dt / 2``): for ``P`` = 1 s, 5 GPS rows (5 Hz),
  10 RATE or VIBE rows (10 Hz), 25 IMU rows (25 Hz).
* A *fault event* is a maximal run of rows of one flight with the same non-zero true label.
  Its *detection* is the first sustained run, inside the event, of rows predicted as the
  event's class (a run that began before the event is cut at its first row); an event that
  covers less than ``P`` needs all its rows predicted right. Its *detection delay* is the time
  from the event's first row to the first row of that run. An event without one is
  *missed*. The same with "any fault class" (prediction non-zero) gives ``delay_any``: how
  soon something is reported, right class or not.
* A *false alarm* is a run of non-normal predictions (any fault class, changes of class
  inside the run included) that starts on a row whose true label is Normal and covers ``P``
  before the true label leaves Normal: an alarm a persistence filter of ``P`` would raise
  while nothing is wrong. An alarm raised less than ``P`` before a fault starts counts as
  an early detection, not a false alarm; a fault's alarm lingering after its event ends
  counts as neither.
* *False alarms per flight hour*: false alarms divided by the hours of Normal rows (each
  row counts the time to the next row of its flight; a flight's last row counts ``dt``).

Medians and 90th percentiles (linear interpolation) are over the detected events only;
undefined (NaN, ``null`` in JSON) where none was detected.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from tlm_process.evaluate.metrics import aligned_table
from tlm_process.labels import class_name

__all__ = ["PERSISTENCE_S", "detection_summary", "event_delays", "false_alarms",
           "format_detection_table"]

#: Persistence time [s] a run of predictions must cover to count as a detection or an
#: alarm. ArduCopter's EKF failsafe declares a failure after 1 s of bad variances
#: (``EKF_CHECK_ITERATIONS_MAX`` = 10 checks at 10 Hz); a detector alarming on a shorter run
#: would flicker on single misclassified rows.
PERSISTENCE_S: float = 1.0


class _Rows:
    """Rows sorted by (flight, time): true and predicted labels, time [s], the flight's row
    interval ``dt`` [s] on each row, and ``first`` (True on a flight's first row)."""

    def __init__(self, flight: Any, time_us: Any, y_true: Any, y_pred: Any) -> None:
        f = np.asarray(flight)
        t = np.asarray(time_us, dtype=np.float64) * 1e-6
        y = np.asarray(y_true, dtype=np.int64)
        p = np.asarray(y_pred, dtype=np.int64)
        if not f.shape == t.shape == y.shape == p.shape or f.ndim != 1:
            raise ValueError(f"flight, time, true and predicted labels differ in shape: "
                             f"{f.shape}, {t.shape}, {y.shape}, {p.shape}")
        _, code = np.unique(f, return_inverse=True)
        order = np.lexsort((t, code))
        self.code, self.t, self.y, self.p = code[order], t[order], y[order], p[order]
        n = len(self.t)
        self.first = np.ones(n, dtype=bool)
        self.first[1:] = self.code[1:] != self.code[:-1]
        self.dt = np.zeros(n)
        starts = np.flatnonzero(self.first)
        ends = np.append(starts[1:], n)[:len(starts)]
        gaps = np.diff(self.t)
        for a, b in zip(starts, ends, strict=True):  # one median per flight
            if b - a > 1:
                self.dt[a:b] = np.median(gaps[a:b - 1])

    def __len__(self) -> int:
        return len(self.t)

    def runs(self, key: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(first, last) row of each maximal run of equal ``key`` within a flight."""
        new = self.first.copy()
        new[1:] |= key[1:] != key[:-1]
        starts = np.flatnonzero(new)
        return starts, np.append(starts[1:], len(key))[:len(starts)] - 1

    def cover(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Time [s] the runs from rows ``a`` to ``b`` cover (``t_b - t_a + dt``)."""
        return self.t[b] - self.t[a] + self.dt[a]


def _first_sustained(rows: _Rows, event: np.ndarray, hit: np.ndarray, ev_start: np.ndarray,
                     ev_need: np.ndarray) -> np.ndarray:
    """Per event (index into ``ev_start``), the delay [s] from its first row to its first
    sustained run of ``hit`` rows; NaN where there is none. ``event``: event index of each
    row (-1 outside events); ``ev_need``: the cover each event's run needs."""
    key = np.where(hit & (event >= 0), event, -1)
    a, b = rows.runs(key)
    keep = key[a] >= 0
    a, b = a[keep], b[keep]
    ev = key[a]
    ok = rows.cover(a, b) >= ev_need[ev] - rows.dt[a] / 2
    a, ev = a[ok], ev[ok]
    delay = np.full(len(ev_start), np.nan)
    # runs come in time order: the first of each event is its detection
    evs, first = np.unique(ev, return_index=True)
    delay[evs] = rows.t[a[first]] - rows.t[ev_start[evs]]
    return delay


def event_delays(flight: Any, time_us: Any, y_true: Any, y_pred: Any,
                 persistence_s: float = PERSISTENCE_S) -> dict[str, np.ndarray]:
    """The fault events of the rows (see the module docstring) in (flight, time) order:
    ``label`` (their true class), ``start_s`` (their first row's time [s]), ``cover_s``,
    ``delay_s`` (the detection delay [s], NaN: missed) and ``delay_any_s`` (the same for a
    prediction of any fault class)."""
    return _event_delays(_Rows(flight, time_us, y_true, y_pred), persistence_s)


def _event_delays(rows: _Rows, persistence_s: float) -> dict[str, np.ndarray]:
    a, b = rows.runs(rows.y)
    run = np.zeros(len(rows), dtype=np.int64)  # run index of each row
    run[a[1:]] = 1
    run = np.cumsum(run)
    fault = rows.y[a] != 0
    of_run = np.full(len(a), -1, dtype=np.int64)  # event index of each run (-1: Normal)
    of_run[fault] = np.arange(np.count_nonzero(fault))
    event = of_run[run]
    a, b = a[fault], b[fault]
    cover = rows.cover(a, b)
    need = np.minimum(cover, persistence_s)
    return {
        "label": rows.y[a], "start_s": rows.t[a], "cover_s": cover,
        "delay_s": _first_sustained(rows, event, rows.p == rows.y, a, need),
        "delay_any_s": _first_sustained(rows, event, rows.p != 0, a, need),
    }


def false_alarms(flight: Any, time_us: Any, y_true: Any, y_pred: Any,
                 persistence_s: float = PERSISTENCE_S) -> tuple[int, float]:
    """(false alarms, hours of Normal rows) of the rows (see the module docstring)."""
    return _false_alarms(_Rows(flight, time_us, y_true, y_pred), persistence_s)


def _false_alarms(rows: _Rows, persistence_s: float) -> tuple[int, float]:
    if not len(rows):
        return 0, 0.0
    alarm = rows.p != 0
    normal = rows.y == 0
    # runs of alarm rows on Normal rows that begin where the alarm begins
    key = np.where(alarm & normal, 1, 0)
    a, b = rows.runs(key)
    keep = key[a] == 1
    keep[keep] = rows.first[a[keep]] | ~alarm[np.maximum(a[keep] - 1, 0)]
    a, b = a[keep], b[keep]
    n = int(np.count_nonzero(rows.cover(a, b) >= persistence_s - rows.dt[a] / 2))
    step = np.empty(len(rows))
    step[:-1] = np.diff(rows.t)
    last = np.append(rows.first[1:], True)
    step[last] = rows.dt[last]
    return n, float(step[normal].sum() / 3600.0)


def _quantile(v: np.ndarray, q: float) -> float:
    """Percentile ``q`` of the finite values [s], to the millisecond; NaN without any."""
    v = v[np.isfinite(v)]
    return round(float(np.percentile(v, q)), 3) if len(v) else math.nan


def detection_summary(flight: Any, time_us: Any, y_true: Any, y_pred: Any,
                      persistence_s: float = PERSISTENCE_S,
                      name: Callable[[int], str] = class_name) -> dict[str, Any]:
    """The event metrics of a model's predictions, for its results: ``detection`` (class
    name -> ``events``, ``detected``, ``detected_frac``, ``delay_median_s``, ``delay_p90_s``,
    ``detected_any``, ``delay_any_median_s``, ``delay_any_p90_s``; classes in label order),
    ``false_alarms``, ``normal_hours``, ``false_alarms_per_hour`` (NaN without Normal rows)
    and ``persistence_s``."""
    rows = _Rows(flight, time_us, y_true, y_pred)
    ev = _event_delays(rows, persistence_s)
    det: dict[str, dict[str, Any]] = {}
    for lab in np.unique(ev["label"]):
        at = ev["label"] == lab
        d, da = ev["delay_s"][at], ev["delay_any_s"][at]
        n, k = int(at.sum()), int(np.isfinite(d).sum())
        det[name(int(lab))] = {
            "events": n, "detected": k, "detected_frac": k / n,
            "delay_median_s": _quantile(d, 50), "delay_p90_s": _quantile(d, 90),
            "detected_any": int(np.isfinite(da).sum()),
            "delay_any_median_s": _quantile(da, 50), "delay_any_p90_s": _quantile(da, 90)}
    fa, hours = _false_alarms(rows, persistence_s)
    return {"detection": det, "false_alarms": fa, "normal_hours": hours,
            "false_alarms_per_hour": fa / hours if hours > 0 else math.nan,
            "persistence_s": persistence_s}


def _cell(d: Mapping[str, Any] | None) -> str:
    if not d:
        return "-"
    med = d.get("delay_median_s")
    delay = f"{med:.1f}" if med is not None and math.isfinite(med) else "?"
    return f"{delay} ({d['detected']}/{d['events']})"


def format_detection_table(results: Mapping[str, Mapping[str, Any]], title: str = "",
                           transfer: bool = False) -> str:
    """One row per model: false alarms and false alarms per flight hour, then per fault
    class the median detection delay [s] and detected/events (``?``: none detected);
    ``transfer``: of the transfer rows. Empty when no model has event metrics."""
    res = {m: (r.get("transfer") or {}) if transfer else r for m, r in results.items()}
    res = {m: r for m, r in res.items() if "detection" in r}
    if not res:
        return ""
    classes = list(dict.fromkeys(c for r in res.values() for c in r["detection"]))
    head = ["Method", "FA", "FA/h", *classes]
    rows = []
    for m, r in res.items():
        fa = r.get("false_alarms_per_hour")
        rows.append([m, str(r.get("false_alarms", "?")),
                     f"{fa:.2f}" if fa is not None and math.isfinite(fa) else "?",
                     *(_cell(r["detection"].get(c)) for c in classes)])
    return aligned_table(head, rows, title)
