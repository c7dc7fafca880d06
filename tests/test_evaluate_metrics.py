"""Weka-style metrics (paper Table 11) against the paper's own confusion matrices and hand
calculations; undefined precision; text and PNG output."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from sklearn.metrics import f1_score, precision_recall_fscore_support

from tlm_process.evaluate.metrics import (
    CLASS_NAMES,
    classification_metrics,
    confusion_matrix,
    format_cell,
    format_confusion,
    format_per_class,
    format_results_table,
    plot_confusion,
    to_jsonable,
)

# The paper's Table 13 (random forest) and Table 12 (naive Bayes) confusion matrices: rows
# true Normal, GPS, Acc, Engine, RC; columns predicted in the same order.
TABLE_13 = [[847, 3, 56, 35, 4], [0, 193, 0, 0, 0], [112, 0, 293, 17, 23], [2, 0, 0, 125, 0],
            [31, 0, 0, 31, 201]]
TABLE_12 = [[780, 12, 17, 134, 2], [0, 193, 0, 0, 0], [288, 3, 153, 0, 1], [1, 0, 0, 126, 0],
            [128, 0, 0, 66, 69]]


@pytest.mark.parametrize("cm, row", [
    # Table 11: correct %, TP, FP, precision, recall, F1
    (TABLE_13, (84.08, 0.841, 0.081, 0.851, 0.841, 0.840)),   # RandomForest
    (TABLE_12, (66.95, 0.670, 0.205, 0.758, 0.670, 0.646)),   # Naive Bayes
])
def test_weighted_metrics_reproduce_table_11_from_tables_12_and_13(cm, row):
    m = classification_metrics(cm)
    assert m["correct_pct"] == pytest.approx(row[0], abs=0.01)  # the paper truncates
    got = (m["weighted_tp_rate"], m["weighted_fp_rate"], m["weighted_precision"],
           m["weighted_recall"], m["weighted_f1"])
    assert tuple(round(v, 3) for v in got) == row[1:]
    assert m["n"] == 1973


def test_random_forest_accuracy_is_the_papers_84_0851_percent():
    assert round(classification_metrics(TABLE_13)["correct_pct"], 4) == 84.0851  # §5.2 text


def test_metrics_equal_hand_computed_values():
    # 2 classes used of 5; hand-worked: N = 10, support (6, 4), predicted (7, 3)
    cm = np.zeros((5, 5), dtype=int)
    cm[0, 0], cm[0, 1], cm[1, 0], cm[1, 1] = 5, 1, 2, 2
    m = classification_metrics(cm)
    assert m["accuracy"] == pytest.approx(0.7)
    p0, r0, p1, r1 = 5 / 7, 5 / 6, 2 / 3, 2 / 4
    f0, f1 = 2 * p0 * r0 / (p0 + r0), 2 * p1 * r1 / (p1 + r1)
    assert m["per_class"]["Normal"]["precision"] == pytest.approx(p0)
    assert m["per_class"]["GPS"]["recall"] == pytest.approx(r1)
    assert m["weighted_precision"] == pytest.approx(0.6 * p0 + 0.4 * p1)
    assert m["weighted_recall"] == pytest.approx(0.7) == m["weighted_tp_rate"]
    assert m["weighted_f1"] == pytest.approx(0.6 * f0 + 0.4 * f1)
    # FP rate: class 0: 2 false of 4 negatives; class 1: 1 of 6
    assert m["weighted_fp_rate"] == pytest.approx(0.6 * 2 / 4 + 0.4 * 1 / 6)
    assert m["macro_f1"] == pytest.approx((f0 + f1) / 2)
    assert math.isnan(m["per_class"]["Acc"]["recall"])  # no Acc rows at all
    assert m["undefined_precision"] == []


def test_undefined_precision_is_nan_question_mark_and_null_in_json():
    # a ZeroR-like model: everything predicted Normal
    y = np.array([0] * 6 + [1] * 3 + [2] * 1)
    cm = confusion_matrix(y, np.zeros_like(y))
    m = classification_metrics(cm)
    assert math.isnan(m["per_class"]["GPS"]["precision"])
    assert math.isnan(m["weighted_precision"]) and math.isnan(m["weighted_f1"])
    assert m["weighted_recall"] == pytest.approx(0.6)
    assert m["undefined_precision"] == ["GPS", "Acc"]
    # macro-F1 stays defined: a never-predicted class scores 0 (as scikit-learn)
    assert m["macro_f1"] == pytest.approx(f1_score(y, np.zeros_like(y), average="macro",
                                                   zero_division=0))
    assert format_cell(m["weighted_precision"]) == "?"
    js = json.loads(json.dumps(to_jsonable(m)))
    assert js["weighted_precision"] is None and js["per_class"]["GPS"]["precision"] is None
    table = format_results_table({"ZeroR": m})
    assert "?" in table.splitlines()[-1] and "60.00%" in table


def test_macro_and_per_class_scores_match_scikit_learn():
    rng = np.random.default_rng(4)
    y = rng.integers(0, 5, 400)
    p = np.where(rng.random(400) < 0.6, y, rng.integers(0, 4, 400))  # class 4 rarely right
    m = classification_metrics(confusion_matrix(y, p))
    assert m["macro_f1"] == pytest.approx(f1_score(y, p, average="macro"))
    pr, rc, f, s = precision_recall_fscore_support(y, p, labels=range(5), zero_division=0)
    for k, name in enumerate(CLASS_NAMES):
        d = m["per_class"][name]
        assert d["recall"] == pytest.approx(rc[k]) and d["support"] == s[k]
        if d["predicted"]:
            assert d["precision"] == pytest.approx(pr[k]) and d["f1"] == pytest.approx(f[k])


def test_confusion_matrix_rejects_bad_labels_and_shapes():
    with pytest.raises(ValueError):
        confusion_matrix([0, 5], [0, 0])
    with pytest.raises(ValueError):
        confusion_matrix([0, 1], [0])


def test_text_and_png_outputs(tmp_path):
    text = format_confusion(TABLE_13)
    assert text.splitlines()[0].split() == [*CLASS_NAMES, "Class"]
    assert text.splitlines()[3].split()[:2] == ["112", "0"]
    per = format_per_class(classification_metrics(TABLE_13))
    assert per.splitlines()[2].split()[0] == "GPS"
    p = plot_confusion(TABLE_13, tmp_path / "cm.png", "RF")
    assert p.exists() and p.read_bytes()[:4] == b"\x89PNG"


def test_visible_scores_leave_out_the_classes_a_table_cannot_see():
    from tlm_process.evaluate.visible import VISIBLE, visible_scores

    assert all(0 in v for v in VISIBLE.values())
    y = np.array([0, 0, 1, 1, 7, 7])          # compass (7): GPS cannot see it
    p = np.array([0, 0, 1, 0, 0, 0])
    s = visible_scores("GPS", y, p)
    assert s["labels"] == [0, 1] and s["rows"] == 4
    assert s["macro_f1"] == pytest.approx((0.8 + 2 / 3) / 2)  # Normal 2/(2+.5), GPS 1/(1+.5)
    assert visible_scores("BARO", y, p) is None
