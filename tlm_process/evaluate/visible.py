"""Which fault classes each paper table can see, and transfer scores over them.

A table *sees* a class when a model trained on tlm flights tells the class apart on tlm's own
held-out flights: in-domain per-class F1 of at least 0.8 for the table's best window model
(CentredHGB) on 200 ``tlm generate`` default flights, flight split 150/50
(``bench_detection.py --flights 200 --seed 1``, 2026-11-26; ``docs/evaluation.md``, "What each
table can see"). The choice is made on tlm's flights only, never on the SITL logs the
transfer is scored on. Why the others are not seen:

* GPS (Status, NSats, HDop, Spd, GCrs, VZ): sees the GPS loss, the accelerometer fault (the
  vertical speed swings), the engine fault (a fall and a lie), the RC fault's RTL (a straight
  line home at WPNAV_SPEED), the baro fault (the climb), GPS jamming. Not the gyro, compass,
  battery or accelerometer-sample faults (the GPS does not feel them), the GPS glitch (its
  only trace is the position jump, and latitude and longitude are dropped as not universal),
  a weak motor (0.68: a short sink) or vibration (0.37).
* IMU (gyros, accels, health): sees the GPS loss (0.95: the EKF's dead reckoning changes the
  flight), the accelerometer, engine, gyro and accelerometer-sample faults. Not the RC fault
  (0.72), baro, compass, GPS glitch, weak motor (0.75), vibration (0.59: the 25 Hz IMU rows
  alias the motor-rate shaking), battery or jamming.
* RATE (desired/actual rates and outputs): sees the GPS loss (0.96), the accelerometer,
  engine, baro (0.93), weak-motor and battery faults (the outputs rise). Not the RC fault
  (0.70), gyro (the EKF borrows IMU 2's gyro: nothing changes), compass, GPS glitch, vibration
  (0.57), jamming (0.60) or accelerometer samples.
* VIBE (vibration levels): sees the accelerometer, engine, vibration and accelerometer-sample
  faults. Not the GPS loss (0.50), RC (0.09), gyro, baro, compass, GPS glitch, weak motor
  (0.66), battery or jamming: they change the vibration little.

Normal (label 0) is always visible.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

__all__ = ["VISIBLE", "visible_scores"]

#: Table -> the labels it sees (see the module docstring), Normal included.
VISIBLE: Mapping[str, tuple[int, ...]] = {
    "GPS": (0, 1, 2, 3, 4, 6, 12),
    "IMU": (0, 1, 2, 3, 5, 13),
    "RATE": (0, 1, 2, 3, 6, 9, 11),
    "VIBE": (0, 2, 3, 10, 13),
}


def visible_scores(table: str, y_true: np.ndarray, y_pred: np.ndarray
                   ) -> dict[str, object] | None:
    """Macro-F1 of ``table``'s visible classes present in ``y_true``, on the rows whose true
    class is visible (rows of classes the table cannot see are left out: no model on it could
    tell them); None for a table without a visible-class list. Keys: ``labels`` (the visible
    labels present), ``rows``, ``macro_f1``, ``f1`` (label -> F1)."""
    if table not in VISIBLE:
        return None
    from sklearn.metrics import f1_score

    yt = np.asarray(y_true)
    yp = np.asarray(y_pred)
    keep = np.isin(yt, VISIBLE[table])
    labels = sorted({int(v) for v in np.unique(yt[keep])})
    if not labels:
        return {"labels": [], "rows": 0, "macro_f1": None, "f1": {}}
    f1 = f1_score(yt[keep], yp[keep], labels=labels, average=None, zero_division=0)
    return {"labels": labels, "rows": int(keep.sum()), "macro_f1": float(np.mean(f1)),
            "f1": {str(k): float(v) for k, v in zip(labels, f1, strict=True)}}
