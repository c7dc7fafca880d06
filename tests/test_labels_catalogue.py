"""``tlm process`` and ``tlm evaluate`` with any set of labels (0-13): class names from
``FAULT_TYPES`` in every count table, plot, confusion matrix and report; the paper's
five-class layout kept for the paper's labels."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tlm_process.cli import main
from tlm_process.evaluate.data import EvalDataset
from tlm_process.evaluate.metrics import (
    CLASS_NAMES,
    classification_metrics,
    confusion_matrix,
    format_confusion,
    format_per_class,
    plot_confusion,
)
from tlm_process.labels import (
    class_column,
    class_labels,
    class_name,
    label_colour,
    long_name,
)
from tlm_process.pipeline.plots import plot_label_shares
from tlm_process.pipeline.report import counts_dict
from tlm_process.pipeline.stretching import (
    CLASS_COLUMNS,
    class_counts,
    fault_share,
    format_counts,
)
from tlm_sim.faults import FAULT_TYPES


def test_every_label_has_a_name_column_and_colour():
    assert [class_name(k) for k in range(5)] == list(CLASS_NAMES)
    for t in FAULT_TYPES.values():
        if t.label > 4:
            assert class_name(t.label) == long_name(t.label) == t.name
            assert class_column(t.label) == f"{t.name} Fail"
    colours = [label_colour(k) for k in range(14)]
    assert len(set(colours)) == 14
    assert class_name(42) == "label 42"


def test_class_labels_keep_the_papers_five_or_show_what_is_present():
    assert class_labels([0, 1, 1], [4]) == [0, 1, 2, 3, 4]
    assert class_labels([0, 0]) == [0, 1, 2, 3, 4]
    assert class_labels([9, 10], np.array([0, 11])) == [0, 9, 10, 11]
    assert class_labels([5], []) == [0, 5]
    assert class_labels([1, 13]) == [0, 1, 13]


def test_class_counts_share_and_report_with_new_labels(tmp_path):
    tables = {"GPS": pd.DataFrame({"label": [0, 0, 9, 9, 10, 0, 11, 0]}),
              "IMU": pd.DataFrame({"label": np.r_[np.zeros(30, int), np.full(10, 9)]})}
    c = class_counts(tables)
    assert list(c.columns) == ["Normal", "motor_partial Fail", "vibration Fail",
                               "battery Fail", "Total"]
    assert c.loc["GPS"].tolist() == [4, 2, 1, 1, 8] and c.loc["IMU"].tolist() == [30, 10, 0, 0,
                                                                                   40]
    a = fault_share(c)
    assert a["GPS"] == pytest.approx(0.5) and a["IMU"] == pytest.approx(0.25)
    assert fault_share(c.loc["GPS"]) == pytest.approx(0.5)
    assert "motor_partial Fail" in format_counts(c) and "50.00%" in format_counts(c)
    assert counts_dict(c)["GPS"] == {"0": 4, "9": 2, "10": 1, "11": 1, "total": 8}
    p = plot_label_shares(c, tmp_path / "shares.png")
    assert p.read_bytes()[:4] == b"\x89PNG"
    # the paper's labels keep Table 7's columns
    assert list(class_counts({"GPS": pd.DataFrame({"label": [0, 1]})}).columns) == list(
        CLASS_COLUMNS)


def test_confusion_metrics_and_text_with_new_labels(tmp_path):
    labels = [0, 5, 9, 12]
    y = np.array([0, 0, 5, 9, 9, 12, 12, 0])
    p = np.array([0, 5, 5, 9, 0, 12, 9, 0])
    cm = confusion_matrix(y, p, labels=labels)
    assert cm.shape == (4, 4) and cm.trace() == 5
    names = [class_name(k) for k in labels]
    r = classification_metrics(cm, names)
    assert r["classes"] == ["Normal", "gyro", "motor_partial", "gps_jam"]
    assert list(r["per_class"]) == r["classes"]
    assert r["per_class"]["motor_partial"]["support"] == 2
    text = format_confusion(cm, r["classes"])
    assert text.splitlines()[0].split() == [*r["classes"], "Class"]
    per = format_per_class(r)
    assert per.splitlines()[3].split()[0] == "motor_partial"
    assert plot_confusion(cm, tmp_path / "cm.png", class_names=names).exists()
    with pytest.raises(ValueError, match="among"):
        confusion_matrix([0, 7], [0, 0], labels=labels)


def _synthetic(n_flights: int = 6, rows: int = 60) -> pd.DataFrame:
    """Flights whose feature ``a`` tells the label apart: normal, gyro, battery, gps_jam."""
    rng = np.random.default_rng(0)
    parts = []
    for f in range(n_flights):
        lab = np.repeat([0, 5, 11, 12], rows // 4)
        parts.append(pd.DataFrame({
            "flight": f"f{f}", "TimeUS": np.arange(len(lab)) * 200_000, "label": lab,
            "a": lab / 12 + rng.normal(0, 0.01, len(lab)), "b": rng.random(len(lab))}))
    return pd.concat(parts, ignore_index=True)


def test_evaluate_scores_any_label_set():
    from tlm_process.evaluate.runner import evaluate

    df = _synthetic()
    ds = EvalDataset(path=Path("."), tables={"GPS": df}, features={"GPS": ["a", "b"]},
                     scaler=None, report={"scaling": {"applied": False}})
    xt = _synthetic(2).assign(label=lambda d: d.label.replace(12, 9))
    res = evaluate(ds, models=["J48", "ZeroR"], split="flight", seed=0, folds=3,
                   transfer={"GPS": xt})
    r = res["GPS"]["J48"]
    assert r["labels"] == [0, 5, 9, 11, 12]  # the transfer's 9 joins the classes
    assert r["classes"] == ["Normal", "gyro", "motor_partial", "battery", "gps_jam"]
    assert np.asarray(r["confusion"]).shape == (5, 5)
    assert r["accuracy"] > 0.95
    assert r["transfer"]["classes"] == r["classes"]
    assert r["transfer"]["per_class"]["motor_partial"]["support"] == len(xt) // 4


@pytest.mark.slow
def test_process_and_evaluate_flights_of_new_faults(tmp_path, capsys):
    """tlm flights with modelled new faults go through ``tlm process`` and ``tlm evaluate``:
    labels 9-11 in the data set, their names in the report and the confusion matrix."""
    from tlm_sim import fly
    from tlm_sim.faults import FaultSchedule

    types = ["vibration", "battery", "motor_partial"]
    flights = tmp_path / "flights"
    for m in (1, 2, 3):
        sched = FaultSchedule.from_shorthand([f"{t}:{60 + 50 * k}+25"
                                              for k, t in enumerate(types)])
        fly(m, faults=sched, seed=m).write(flights / f"m{m}", formats=("parquet",))
    ds = tmp_path / "ds"
    assert main(["process", str(flights), "--out", str(ds), "--test-flight", "*m3*"]) == 0
    rep = json.loads((ds / "report.json").read_text())
    labels = {str(FAULT_TYPES[t].label) for t in types}
    assert labels <= set(rep["counts"]["GPS"]) and "1" not in rep["counts"]["GPS"]
    capsys.readouterr()
    rj = tmp_path / "r.json"
    assert main(["evaluate", str(ds), "--table", "GPS", "--models", "J48", "--json", str(rj),
                 "--details"]) == 0
    out = capsys.readouterr().out
    r = json.loads(rj.read_text())["GPS"]["J48"]
    assert r["classes"] == ["Normal", *sorted(types, key=lambda t: FAULT_TYPES[t].label)]
    assert all(t in out for t in types)


def test_ingest_reads_records_of_every_type_by_type_or_label():
    from tlm_process.pipeline.ingest import parse_records

    recs = [{"type": t.name, "start_time_us": 1e6 * t.label, "end_time_us": 1e6 * t.label + 5e5}
            for t in FAULT_TYPES.values()]
    recs += [{"label": 7, "start_time_us": 9e7, "end_time_us": 9.1e7}]
    out = parse_records(recs)
    assert [r.label for r in out] == [t.label for t in FAULT_TYPES.values()] + [7]
    assert out[-1].type == "compass"
