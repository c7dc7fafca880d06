"""RC labels (issue 23): the paper's window (while the radio is lost) by default; with
``--rc-label failsafe`` also the RTL the radio failsafe started, until it lands."""

from __future__ import annotations

import json
from functools import lru_cache

import numpy as np
import pandas as pd
import pytest
from conftest import reference_path

from tlm_process.cli import main
from tlm_process.pipeline import PipelineError, process_flight, read_flights
from tlm_process.pipeline.anchoring import FaultWindow, extend_rc_failsafe
from tlm_process.pipeline.dataset import ProcessOptions


@lru_cache(maxsize=4)
def _processed(name: str, rc_label: str):
    flight = read_flights([reference_path(f"{name}.bin")])[0]
    return process_flight(flight, ProcessOptions(rc_label=rc_label))


def _events(name: str) -> tuple[pd.DataFrame, pd.DataFrame]:
    from tlm_sim.flightlog import read_bin

    t = read_bin(str(reference_path(f"{name}.bin")), types=["MODE", "EV"])
    return t["MODE"], t["EV"]


@pytest.mark.parametrize("name", ["rc_s15", "combined_s21"])
def test_failsafe_labels_the_rtl_until_it_lands(name):
    paper, fs = _processed(name, "window"), _processed(name, "failsafe")
    side = json.loads(reference_path(f"{name}.json").read_text())
    rc = next(f for f in side["faults"] if f["type"] == "rc")
    w_paper = next(w for w in paper.windows if w.type == "rc")
    w_fs = next(w for w in fs.windows if w.type == "rc")
    assert w_paper.end_us == rc["end_time_us"]  # the paper's: the radio's return
    assert w_fs.start_us == w_paper.start_us
    mode, ev = _events(name)
    rtl = mode[(mode.Mode == 6) & (mode.Rsn == 3)].TimeUS.iloc[0]
    assert w_paper.start_us < rtl < w_paper.end_us  # the failsafe's RTL, 1 s in
    landed = ev[(ev.Id == 18) & (ev.TimeUS > rtl)].TimeUS.iloc[0]
    assert w_fs.end_us == landed  # RC 25-35 s, the RTL ran on to the landing
    assert (w_fs.end_us - w_paper.end_us) * 1e-6 > 20.0
    # every other window is untouched, and the RC rows grow by exactly the extension
    assert [(w.type, w.start_us, w.end_us) for w in paper.windows if w.type != "rc"] == [
        (w.type, w.start_us, w.end_us) for w in fs.windows if w.type != "rc"]
    for table in ("GPS", "RATE"):
        a, b = paper.features[table], fs.features[table]
        t = a["TimeUS"].to_numpy()
        grown = (t >= w_paper.end_us) & (t < w_fs.end_us)
        assert (b["label"].to_numpy()[grown] == 4).all() and (a["label"].to_numpy()[grown] == 0
                                                                ).all()
        assert (a["label"].to_numpy()[~grown] == b["label"].to_numpy()[~grown]).all()


def _window(i: int, kind: str, label: int, a: float, b: float) -> FaultWindow:
    return FaultWindow(i, kind, label, a, b, "time")


def _tables(modes: list[tuple[float, int, int]], events: list[tuple[float, int]]):
    return {"MODE": pd.DataFrame(modes, columns=["TimeUS", "Mode", "Rsn"]),
            "EV": pd.DataFrame(events, columns=["TimeUS", "Id"])}


def test_extension_stops_at_the_next_fault_and_other_modes():
    w = [_window(0, "rc", 4, 10e6, 40e6), _window(1, "gps", 1, 60e6, 80e6)]
    # RTL by the failsafe at 11 s, never lands before the GPS fault: cut at 60 s
    t = _tables([(1e6, 3, 2), (11e6, 6, 3)], [(200e6, 18)])
    out = extend_rc_failsafe(w, t)
    assert out[0].end_us == 60e6 and out[1] == w[1]
    # the pilot (or the driver) takes another mode at 50 s: the failsafe's consequence ends
    t = _tables([(1e6, 3, 2), (11e6, 6, 3), (50e6, 5, 2)], [])
    assert extend_rc_failsafe(w, t)[0].end_us == 50e6
    # disarmed without a landing event
    t = _tables([(1e6, 3, 2), (11e6, 6, 3)], [(45e6, 11)])
    assert extend_rc_failsafe(w, t)[0].end_us == 45e6
    # the log ends in the failsafe's RTL: held to the end (or the next window)
    t = _tables([(1e6, 3, 2), (11e6, 6, 3)], [])
    assert extend_rc_failsafe(w[:1], t)[0].end_us == np.inf


def test_no_failsafe_mode_change_keeps_the_window():
    w = [_window(0, "rc", 4, 10e6, 40e6)]
    # FS_THR_ENABLE 0: no mode change; a mode change of another reason; one before the fault
    for modes in ([(1e6, 3, 2)], [(1e6, 3, 2), (20e6, 6, 2)], [(5e6, 6, 3)]):
        assert extend_rc_failsafe(w, _tables(modes, [(90e6, 18)])) == w
    # a landing inside the window: nothing to extend
    t = _tables([(1e6, 3, 2), (11e6, 6, 3)], [(30e6, 18)])
    assert extend_rc_failsafe(w, t) == w


def test_unknown_rc_labelling_is_refused():
    with pytest.raises(PipelineError, match="unknown RC labelling"):
        ProcessOptions(rc_label="rtl")


def test_process_command_option(tmp_path, capsys):
    bin_path = reference_path("rc_s15.bin")
    counts = {}
    for how in ("window", "failsafe"):
        ds = tmp_path / how
        rc = main(["process", str(bin_path), "--out", str(ds), "--plots", "0", "--quiet",
                   *(["--rc-label", how] if how != "window" else [])])
        _, err = capsys.readouterr()
        assert rc == 0, err
        report = json.loads((ds / "report.json").read_text())
        assert report["options"]["rc_label"] == how
        counts[how] = report["counts"]["GPS"]
        card = (ds / "README.md").read_text()
        assert ("through the radio failsafe's RTL" in card) == (how == "failsafe")
    assert counts["failsafe"]["4"] > counts["window"]["4"] + 100  # 5 Hz x > 20 s
    assert counts["failsafe"]["total"] == counts["window"]["total"]


def test_bad_rc_label_exits_2(tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        main(["process", "x.bin", "--out", str(tmp_path / "x"), "--rc-label", "rtl"])
    assert e.value.code == 2
    assert "--rc-label" in capsys.readouterr().err


@pytest.mark.parametrize("rc_label", ["window", "failsafe", None])
def test_evaluate_labels_transfer_logs_as_the_data_set_was_labelled(rc_label):
    """``tlm evaluate --test-on``: the transfer log gets the data set's RC labelling (a report
    without ``rc_label``, older than the option, had the paper's window)."""
    from tlm_process.evaluate.data import EvalDataset, load_transfer

    want = _processed("rc_s15", rc_label or "window").features["GPS"]
    feats = [c for c in want.columns if c not in ("flight", "TimeUS", "label")]
    ds = EvalDataset(None, {}, {"GPS": feats}, object(),  # unscaled: the scaler is not used
                     {"options": {"rc_label": rc_label} if rc_label else {},
                      "scaling": {"applied": False}})
    got = load_transfer([reference_path("rc_s15.bin")], ds, ["GPS"])["GPS"]
    assert got["TimeUS"].tolist() == want["TimeUS"].tolist()
    assert got["label"].tolist() == want["label"].tolist()
    other = _processed("rc_s15", "window" if rc_label == "failsafe" else "failsafe")
    assert (other.features["GPS"]["label"] == 4).sum() != (got["label"] == 4).sum()
