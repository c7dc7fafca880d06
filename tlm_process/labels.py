"""Class labels and their names, for every table, plot and confusion matrix of ``tlm process``
and ``tlm evaluate``.

Label 0 is normal flight and labels 1-4 the paper's four faults (Table 6), named as the paper
writes them; labels 5 and up are the rest of SITL's fault catalogue, named by their
``tlm_sim.faults.FAULT_TYPES`` type (``gyro`` 5 ... ``gps_jam`` 12, ``accel_samples`` 13, and
any type registered since: the registry is read at each call). A label no type has (a data set
from a newer tlm) is named ``label N``. Colours are the types' own (:func:`label_colour`).

Which classes a table or matrix shows (:func:`class_labels`): the paper's five whenever every
label present is one of them (the paper's Tables 7-8 and 12-18 layout, also for a data set that
lacks a class), else normal plus every label present, in label order.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from tlm_sim.faults.types import NORMAL_LABEL, type_of_label
from tlm_sim.faults.types import label_colour as _type_colour

__all__ = ["PAPER_CLASS_NAMES", "PAPER_LABELS", "class_column", "class_labels", "class_name",
           "class_names", "label_colour", "long_name"]

#: Class names of labels 0-4 as the paper's Tables 12-18 write them.
PAPER_CLASS_NAMES: tuple[str, ...] = ("Normal", "GPS", "Acc", "Engine", "RC")
#: Labels of the paper's classes (normal and its four faults).
PAPER_LABELS: tuple[int, ...] = tuple(range(len(PAPER_CLASS_NAMES)))
#: Column headings of the paper's Tables 7 and 8 for labels 0-4.
_PAPER_COLUMNS = ("Normal", "GPS Fail", "Accelerometer Fail", "Engine Fail", "RC Fail")
#: Plot names of labels 0-4.
_PAPER_LONG = ("normal", "GPS", "accelerometer", "engine", "RC")


def _type_name(label: int) -> str:
    """The registered type name of a label, ``label N`` when no type has it."""
    ftype = type_of_label(label)
    return ftype.name if ftype is not None else f"label {label}"


def class_name(label: int) -> str:
    """Short class name of a label (confusion matrices, per-class tables, JSON keys)."""
    k = int(label)
    if 0 <= k < len(PAPER_CLASS_NAMES):
        return PAPER_CLASS_NAMES[k]
    return _type_name(k)


def long_name(label: int) -> str:
    """Class name of a label in plots (``normal``, ``GPS``, ``accelerometer``, ... then the
    fault type)."""
    k = int(label)
    if 0 <= k < len(_PAPER_LONG):
        return _PAPER_LONG[k]
    return _type_name(k)


def class_column(label: int) -> str:
    """Column heading of a label in Table 7/8-style counts (``GPS Fail``, ``gyro Fail``)."""
    k = int(label)
    if 0 <= k < len(_PAPER_COLUMNS):
        return _PAPER_COLUMNS[k]
    return f"{_type_name(k)} Fail"


def label_colour(label: int) -> str:
    """Matplotlib colour of a label: grey for normal, the fault type's ``colour`` (labels 0-4
    keep the paper figures' colours), else a generated one that no other label has
    (:func:`tlm_sim.faults.types.label_colour`)."""
    return _type_colour(label)


def class_labels(*labels: Iterable[int] | np.ndarray) -> list[int]:
    """The classes to show for the labels present in ``labels`` (any number of arrays): the
    paper's 0-4 when all are among them, else normal plus every label present, sorted."""
    present: set[int] = set()
    for arr in labels:
        a = np.asarray(list(arr) if not isinstance(arr, np.ndarray) else arr)
        if a.size:
            present |= {int(x) for x in np.unique(a.astype(np.int64))}
    if present <= set(PAPER_LABELS):
        return list(PAPER_LABELS)
    return sorted(present | {NORMAL_LABEL})


def class_names(labels: Iterable[int]) -> list[str]:
    """:func:`class_name` of each label."""
    return [class_name(k) for k in labels]
