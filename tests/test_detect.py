"""The whole-log detector (tlm_process.detect): channels on a causal grid, window features,
a saved model that loads without running code, and tlm train / tlm detect end to end on the
reference SITL logs and the real logs."""

from __future__ import annotations

import json
import pickle
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.conftest import real_path, reference_path
from tlm_process.cli import main
from tlm_process.detect.channels import (
    CHANNELS,
    armed_grid,
    channel_table,
    drop_channels,
    needed_columns,
)
from tlm_process.detect.data import DetectError, LogData
from tlm_process.detect.features import feature_matrix, feature_names
from tlm_process.detect.model import WEIGHTS_FILE, Detector, load_detector
from tlm_process.detect.predict import fault_rows, find_faults


def _grid_s(t0: float, t1: float) -> np.ndarray:
    return armed_grid(int(t0 * 1e6), int(t1 * 1e6))


# --------------------------------------------------------------------------------------------
# Channels
# --------------------------------------------------------------------------------------------

def test_channel_names_are_unique_and_every_channel_names_its_log_columns():
    names = [c.name for c in CHANNELS]
    assert len(names) == len(set(names))
    for c in CHANNELS:
        assert c.kind in ("level", "delta", "state")
        assert c.needs and all(n.split(".", 1)[0].isupper() or n[0].isupper() for n in c.needs)


def test_a_channel_takes_the_last_row_at_or_before_each_grid_time():
    """Causal alignment: a row logged at 1.05 s is first seen on the 1.1 s grid row."""
    rate = pd.DataFrame({"TimeUS": [1_000_000, 1_050_000, 1_300_000],
                         **{c: [0.0, 0.0, 0.0] for c in ("RDes", "PDes", "P", "POut", "YDes",
                                                        "Y", "YOut", "ADes", "A", "AOut",
                                                        "ROut")},
                         "R": [1.0, 2.0, 3.0]})
    grid = _grid_s(1.0, 1.4)
    table, lacking = channel_table({"RATE": rate}, {}, ["RATE.R", "RATE.RErr"], grid)
    assert lacking == []
    assert table["RATE.R"].tolist() == [1.0, 2.0, 2.0, 3.0, 3.0]
    assert table["RATE.RErr"].tolist() == [1.0, 2.0, 2.0, 3.0, 3.0]  # R - RDes


def test_instances_rcou_battery_and_err_channels():
    imu = pd.DataFrame({"TimeUS": [0, 0], "I": [0, 1], "GyrX": [0.1, 0.2],
                        **{c: [0.0, 0.0] for c in ("GyrY", "GyrZ", "AccX", "AccY", "AccZ",
                                                   "GH", "AH")}})
    rcou = pd.DataFrame({"TimeUS": [0], "C1": [1800.0], "C2": [1400.0], "C3": [1400.0],
                         "C4": [1400.0], "C5": [0.0]})
    bat = pd.DataFrame({"TimeUS": [0, 100_000], "Inst": [0, 0], "Volt": [25.0, 22.2]})
    err = pd.DataFrame({"TimeUS": [50_000, 150_000], "Subsys": [5, 5], "ECode": [1, 0]})
    tables = {"IMU": imu, "RCOU": rcou, "BAT": bat, "ERR": err}
    want = ["IMU0.GyrX", "IMU1.GyrX", "RCOU.Mean", "RCOU.MaxDev", "RCOU.MinDev",
            "BAT.VoltCell", "ERR.S5", "ERR.S25"]
    t, lacking = channel_table(tables, {}, want, _grid_s(0.0, 0.2))
    assert lacking == []
    assert t["IMU0.GyrX"].iloc[0] == 0.1 and t["IMU1.GyrX"].iloc[0] == 0.2
    assert t["RCOU.Mean"].iloc[0] == pytest.approx(0.5)  # 4 motors (C5 never rises)
    assert t["RCOU.MaxDev"].iloc[0] == pytest.approx(0.3)
    assert t["RCOU.MinDev"].iloc[0] == pytest.approx(-0.1)
    assert t["BAT.VoltCell"].tolist() == pytest.approx([25.0 / 6, 22.2 / 6, 22.2 / 6])  # 6S
    assert t["ERR.S5"].tolist() == [0.0, 1.0, 0.0]
    assert t["ERR.S25"].tolist() == [0.0, 0.0, 0.0]  # no error of that subsystem: 0


def test_missing_tables_and_columns_are_named():
    gps = pd.DataFrame({"TimeUS": [0], "I": [0], "Status": [3]})
    t, lacking = channel_table({"GPS": gps}, {}, ["GPS.Status", "GPS.Spd", "IMU1.GyrX",
                                                 "MODE.ModeNum"], _grid_s(0, 0.1))
    assert "GPS.Spd" in lacking and "IMU.GyrX" in lacking
    assert "GPS.Status" not in lacking and "MODE" not in lacking  # no MODE rows: no events
    assert np.isnan(t["IMU1.GyrX"]).all()


def test_columns_of_dropped_channels_do_not_count_as_lacking():
    """A Copter 3.3 IMU has no GH / AH: a model without IMU.GH / IMU.AH (--drop-features)
    reads the log's gyros, and the log lacks nothing it needs."""
    imu = pd.DataFrame({"TimeUS": [0, 100_000], "I": [0, 0], "GyrX": [0.1, 0.2],
                        "GyrY": [0.0, 0.0], "GyrZ": [0.0, 0.0], "AccX": [0.0, 0.0],
                        "AccY": [0.0, 0.0], "AccZ": [-9.8, -9.8]})
    kept, _ = drop_channels(["IMU.GH", "IMU.AH"])
    want = [k for k in kept if k.startswith("IMU0.")]
    assert "IMU0.GyrX" in want and "IMU0.GH" not in want
    t, lacking = channel_table({"IMU": imu}, {}, want, _grid_s(0, 0.1))
    assert lacking == []
    assert t["IMU0.GyrX"].tolist() == [0.1, 0.2]


def test_drop_features_by_column_group_table_and_channel():
    kept, unknown = drop_channels(["RATE.AOutSlew"])
    assert "RATE.AOutSlew" not in kept and "RATE.AOut" in kept and not unknown
    kept, _ = drop_channels(["IMU1", "XKF3"])
    assert not any(k.startswith(("IMU1.", "XKF3")) for k in kept)
    assert any(k.startswith("IMU0.") for k in kept)
    kept, _ = drop_channels(["GPS.GCrs"])
    assert "GPS.Turn" not in kept and "GPS.Spd" in kept
    _, unknown = drop_channels(["RATE.Nope", "IMU0.GyrX"])
    assert unknown == ["RATE.Nope"]
    assert needed_columns(["RATE.RErr"]) == {"RATE.R": ["RATE.RErr"], "RATE.RDes": ["RATE.RErr"]}


# --------------------------------------------------------------------------------------------
# Features
# --------------------------------------------------------------------------------------------

def test_window_statistics_match_a_direct_computation():
    rng = np.random.default_rng(3)
    v = rng.normal(size=150)
    df = pd.DataFrame({"TimeUS": np.arange(150) * 100_000, "RATE.R": v})
    X = feature_matrix(df, ["RATE.R"], hz=10.0)
    names = feature_names(["RATE.R"])
    col = {n: X[:, i] for i, n in enumerate(names)}
    t = 120
    w = v[t - 19: t + 1]  # 2 s at 10 Hz
    assert col["RATE.R"][t] == pytest.approx(v[t], rel=1e-6)
    assert col["RATE.R_mean2s"][t] == pytest.approx(w.mean(), rel=1e-5)
    assert col["RATE.R_std2s"][t] == pytest.approx(w.std(), rel=1e-4)
    assert col["RATE.R_max2s"][t] == pytest.approx(w.max(), rel=1e-6)
    assert col["RATE.R_change2s"][t] == pytest.approx(w[-1] - w[0], rel=1e-5)
    wd = v[t - 20: t + 1]  # the 20 steps into and within the window
    assert col["RATE.R_absdiff2s"][t] == pytest.approx(np.abs(np.diff(wd)).mean(), rel=1e-5)


@settings(max_examples=25, deadline=None)
@given(st.integers(min_value=5, max_value=120), st.integers(min_value=0, max_value=2**31))
def test_features_are_causal(cut, seed):
    """Changing rows after ``cut`` changes no feature at or before it; leading NaN rows stay
    NaN (nothing is filled from the future)."""
    rng = np.random.default_rng(seed)
    n = 130
    a = rng.normal(size=n)
    a[:3] = np.nan
    b = a.copy()
    b[cut + 1:] = rng.normal(size=n - cut - 1) * 10
    chans = ["RATE.R", "MAG0.Norm", "ERR.S5"]
    fa = feature_matrix(pd.DataFrame({c: a for c in chans}), chans)
    fb = feature_matrix(pd.DataFrame({c: b for c in chans}), chans)
    np.testing.assert_array_equal(fa[: cut + 1], fb[: cut + 1])
    names = feature_names(chans)
    level = [i for i, nm in enumerate(names) if nm.startswith("RATE.R")]
    assert np.isnan(fa[:3, level]).all() and np.isfinite(fa[3:, level]).all()


def test_a_state_channel_counts_its_changes_over_the_trailing_minute():
    """An error flagged and cleared twice (a GPS glitch's start and end): the count of
    changes in the trailing 60 s tells the second flag from the first, and only past
    changes count (the future of the series moves nothing before it)."""
    n = 1500  # 150 s at 10 Hz
    v = np.zeros(n)
    v[100:300] = 2.0  # ERR 11/2 at 10 s, 11/0 at 30 s
    v[450:650] = 2.0  # again at 45 s, cleared at 65 s
    X = feature_matrix(pd.DataFrame({"ERR.S11": v}), ["ERR.S11"], hz=10.0)
    col = dict(zip(feature_names(["ERR.S11"]), X.T, strict=True))
    count = col["ERR.S11_changes60s"]
    assert count[99] == 0 and count[100] == 1 and count[300] == 2  # the first flag and clear
    assert count[450] == 3 and count[650] == 4  # the second flag: two changes before it
    assert count[699] == 4 and count[700] == 3  # the 10 s flag leaves the window at 70 s
    assert count[1249] == 1 and count[1250] == 0  # the last clear (65 s) left at 125 s
    assert col["ERR.S11_age"][460] == pytest.approx(1.0)
    mode = np.full(n, np.nan)
    mode[120:] = 3.0  # the first mode: no change (it would say when the flight started)
    mode[900:] = 6.0
    X = feature_matrix(pd.DataFrame({"ERR.S11": v, "MODE.ModeNum": mode}),
                       ["ERR.S11", "MODE.ModeNum"], hz=10.0)
    col = dict(zip(feature_names(["ERR.S11", "MODE.ModeNum"]), X.T, strict=True))
    assert col["MODE.ModeNum_changes60s"].tolist() == [0.0] * 900 + [1.0] * 600
    assert col["MODE.ModeNum_age"][:900].tolist() == [60.0] * 900  # no change yet
    assert col["MODE.ModeNum_age"][905] == pytest.approx(0.5)
    assert col["ERR.S11_age"][:100].tolist() == [60.0] * 100
    later = v.copy()
    later[500:] = 7.0
    X2 = feature_matrix(pd.DataFrame({"ERR.S11": later, "MODE.ModeNum": mode}),
                        ["ERR.S11", "MODE.ModeNum"], hz=10.0)
    np.testing.assert_array_equal(X[:500], X2[:500])


# --------------------------------------------------------------------------------------------
# Findings
# --------------------------------------------------------------------------------------------

def _pred(lab: np.ndarray) -> pd.DataFrame:
    p = np.where(lab[:, None] == np.arange(4), 0.9, 0.1 / 3)
    return pd.DataFrame({"TimeUS": np.arange(len(lab)) * 100_000, "p_Normal": p[:, 0],
                         "p_GPS": p[:, 1], "p_Acc": p[:, 2], "p_Engine": p[:, 3],
                         "label": lab})


def test_find_faults_keeps_sustained_runs_and_merges_close_ones():
    lab = np.zeros(500, dtype=int)
    lab[50:53] = 1     # 0.3 s: flicker, dropped
    lab[100:120] = 3   # 2 s
    lab[140:160] = 3   # 2 s, 2 s later: merged
    lab[300:330] = 2   # 15 s later: another fault
    found = find_faults(_pred(lab), [0, 1, 2, 3])
    assert [(f.name, f.start_s, f.end_s, f.also) for f in found] == [
        ("Engine", 10.0, pytest.approx(16.0), ()), ("Acc", 30.0, pytest.approx(33.0), ())]
    assert found[0].peak == pytest.approx(0.9)
    fault = fault_rows(_pred(lab)["TimeUS"].to_numpy(), found)
    want = np.zeros(500, dtype=int)
    want[100:160] = 3  # the gap inside the merged fault is the fault's
    want[300:330] = 2  # the flicker at 5 s is no fault
    assert np.array_equal(fault, want)


def test_runs_of_two_classes_that_touch_are_one_fault_named_by_the_main_class():
    lab = np.zeros(400, dtype=int)
    lab[100:115] = 1   # 1.5 s of GPS at the onset ...
    lab[115:200] = 2   # ... of 8.5 s of Acc
    found = find_faults(_pred(lab), [0, 1, 2, 3])
    assert [(f.name, f.start_s, f.end_s, f.also) for f in found] == [
        ("Acc", 10.0, pytest.approx(20.0), (1,))]


# --------------------------------------------------------------------------------------------
# The model folder: identical after loading; no pickle
# --------------------------------------------------------------------------------------------

def _small_detector() -> tuple[Detector, np.ndarray]:
    rng = np.random.default_rng(0)
    chans = ["RATE.R", "ERR.S5"]
    feats = feature_names(chans)
    X = rng.normal(size=(300, len(feats))).astype(np.float32)
    y = (X[:, 0] > 0.5).astype(int) + 3 * (X[:, 1] > 1.0)
    return Detector.fit(X, y, chans, feats, rounds=5), X


def test_a_saved_model_loads_and_predicts_identically(tmp_path):
    det, X = _small_detector()
    det.manifest = {"note": "test"}
    det.save(tmp_path / "m")
    back = load_detector(tmp_path / "m")
    assert back.classes == det.classes and back.channels == det.channels
    np.testing.assert_array_equal(back.predict_proba(X), det.predict_proba(X))
    assert json.loads((tmp_path / "m" / "manifest.json").read_text())["note"] == "test"


class _Payload:
    """Unpickling this would create the sentinel file."""

    def __init__(self, sentinel: str) -> None:
        self.sentinel = sentinel

    def __reduce__(self):  # noqa: ANN204
        return (Path.touch, (Path(self.sentinel),))


def test_a_pickle_in_place_of_the_weights_is_refused_unread(tmp_path):
    det, _ = _small_detector()
    det.save(tmp_path / "m")
    sentinel = tmp_path / "pwned"
    raw = pickle.dumps(_Payload(str(sentinel)))
    (tmp_path / "m" / WEIGHTS_FILE).write_bytes(raw)
    with pytest.raises(DetectError, match="pickle"):
        load_detector(tmp_path / "m")
    assert not sentinel.exists()
    # the hash is checked too: a changed UBJSON file is refused
    (tmp_path / "m" / WEIGHTS_FILE).write_bytes(b"{}")
    with pytest.raises(DetectError, match="SHA-256"):
        load_detector(tmp_path / "m")


@pytest.mark.parametrize("edit, match", [
    (lambda m: m.update(format="other"), "not a tlm detector"),
    (lambda m: m.update(version=99), "newer tlm"),
    (lambda m: m.update(channels=["NOPE.X"]), "does not know"),
    (lambda m: m["weights"].update(format="pickle"), "UBJSON"),
])
def test_a_bad_manifest_is_one_line(tmp_path, edit, match):
    det, _ = _small_detector()
    det.save(tmp_path / "m")
    mp = tmp_path / "m" / "manifest.json"
    m = json.loads(mp.read_text())
    edit(m)
    mp.write_text(json.dumps(m))
    with pytest.raises(DetectError, match=match):
        load_detector(tmp_path / "m")


def test_no_model_folder(tmp_path):
    with pytest.raises(DetectError, match="no such model"):
        load_detector(tmp_path / "none")
    (tmp_path / "empty").mkdir()
    with pytest.raises(DetectError, match="no manifest"):
        load_detector(tmp_path / "empty")


# --------------------------------------------------------------------------------------------
# tlm train / tlm detect end to end (reference SITL logs: no simulation needed)
# --------------------------------------------------------------------------------------------

#: A small, fast detector: the GPS, IMU 0, ERR and MODE channels, on four reference logs.
_TRAIN_LOGS = ("gps_s12", "rc_s15", "normal_s11", "accel_s13")


def _linked_logs(d: Path) -> Path:
    """``d`` holding links to the _TRAIN_LOGS reference logs and their sidecars."""
    for name in _TRAIN_LOGS:
        for ext in (".bin", ".json"):
            (d / f"{name}{ext}").symlink_to(reference_path(name + ext))
    return d


@pytest.fixture(scope="module")
def small_model(tmp_path_factory):
    d = _linked_logs(tmp_path_factory.mktemp("train"))
    out = d / "model"
    rc = main(["train", str(d), "--out", str(out), "--rounds", "8", "--min-child-weight", "1",
               "--quiet",
               "--tables", "GPS,IMU,ERR,MODE", "--drop-features", "IMU1", "--holdout-flight",
               "accel_s13"])
    assert rc == 0
    return out


def test_train_writes_a_manifest_with_held_out_scores(small_model):
    m = json.loads((small_model / "manifest.json").read_text())
    assert m["format"] == "tlm.detector" and m["model"] == "whole-log"
    assert set(m["classes"]) == {0, 1, 4}  # accel_s13 held out
    assert m["data"]["held_out_flights"] == ["accel_s13"]
    assert 0.0 <= m["held_out_scores"]["macro_f1"] <= 1.0
    assert all(c.startswith(("GPS.", "IMU0.", "ERR.", "MODE.")) for c in m["channels"])
    assert m["channel_info"]["GPS.Spd"]["unit"] == "m/s"
    assert (small_model / WEIGHTS_FILE).read_bytes()[:1] == b"{"


def test_detect_writes_summary_predictions_and_timeline(small_model, tmp_path, capsys):
    log = reference_path("combined_s21.bin")
    out = tmp_path / "found"
    assert main(["detect", str(small_model), str(log), str(reference_path("normal_s11.bin")),
                 "--out", str(out), "--quiet"]) == 0
    summary = pd.read_csv(out / "summary.csv")
    assert list(summary.columns) == ["log", "class", "label", "start_s", "end_s", "peak_p",
                                     "also"]
    comb = summary[summary["log"] == str(log)]
    gps = comb[comb["class"] == "GPS"]
    assert len(gps) and abs(gps["start_s"].iloc[0] - 71.7) < 3.0  # sidecar: 71.7 s
    assert (summary[summary["log"].str.endswith("normal_s11.bin")]["class"] == "none").all()
    pred = pd.read_parquet(out / "combined_s21" / "predictions.parquet")
    assert {"TimeUS", "p_Normal", "p_GPS", "p_RC", "label", "fault",
            "true_label"} <= set(pred.columns)
    t = pred["TimeUS"] * 1e-6
    for _, f in comb.iterrows():  # the decision per row is the summary's faults
        inside = (t >= f["start_s"] - 0.01) & (t < f["end_s"] - 0.01)
        assert (pred["fault"][inside] == f["label"]).all()
    assert (pred["fault"] != 0).sum() == sum(
        ((t >= f["start_s"] - 0.01) & (t < f["end_s"] - 0.01)).sum()
        for _, f in comb.iterrows())
    assert np.allclose(pred[["p_Normal", "p_GPS", "p_RC"]].sum(axis=1), 1.0, atol=1e-4)
    assert (out / "combined_s21" / "timeline.png").stat().st_size > 10_000
    assert "sidecar: GPS at 71.7 s found" in capsys.readouterr().out


def test_detect_names_missing_columns_and_the_drop_that_avoids_them(small_model, tmp_path,
                                                                    capsys):
    log = real_path("log171.bin")
    rc = main(["detect", str(small_model), str(log), "--out", str(tmp_path / "a"), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2 and "lacks" in err and "--drop-features" in err and "IMU.GH" in err
    errors = [ln for ln in err.splitlines() if not ln.startswith("tlm: warning:")]
    assert len(errors) == 1  # (log171's damaged FMT is a warning line of its own)
    rc = main(["detect", str(small_model), str(log), "--out", str(tmp_path / "b"), "--quiet",
               "--allow-missing"])
    out = capsys.readouterr().out
    assert rc == 0 and "not used (the log lacks them): " in out and "IMU.GH" in out
    assert (tmp_path / "b" / "log171" / "timeline.png").exists()


@pytest.mark.parametrize("name", ["log171.bin", "nan.log", "mechanical_fail.log",
                                  "backend_log_80k.bin"])
def test_detect_runs_on_every_real_log(small_model, tmp_path, capsys, name):
    log = real_path(name)
    rc = main(["detect", str(small_model), str(log), "--out", str(tmp_path / "o"), "--quiet",
               "--allow-missing"])
    cap = capsys.readouterr()
    assert "Traceback" not in cap.err
    if rc == 0:
        summary = pd.read_csv(tmp_path / "o" / "summary.csv")
        assert len(summary) >= 1
    else:  # refused with one line (e.g. a log too short to hold an armed span)
        errors = [ln for ln in cap.err.splitlines() if ln.startswith("tlm: error:")]
        assert rc == 2 and len(errors) == 1


def test_train_and_detect_refuse_bad_requests(tmp_path, capsys, small_model):
    assert main(["train", str(tmp_path), "--out", str(tmp_path / "m"),
                 "--drop-features", "RATE.Nope"]) == 2
    assert "RATE.Nope names no channel" in capsys.readouterr().err
    assert not (tmp_path / "m").exists()
    assert main(["train", str(tmp_path), "--out", str(tmp_path / "m"), "--tables", "FOO"]) == 2
    assert "--tables: FOO" in capsys.readouterr().err
    assert main(["detect", str(tmp_path), str(tmp_path / "x.bin"), "--out",
                 str(tmp_path / "d")]) == 2
    assert "no manifest.json" in capsys.readouterr().err
    assert main(["detect", str(small_model), str(tmp_path / "x.bin"), "--out",
                 str(tmp_path / "d"), "--quiet"]) == 2
    assert "no such log" in capsys.readouterr().err
    assert main(["train", "--list-channels"]) == 0
    assert "RATE.AOutSlew" in capsys.readouterr().out


def test_logdata_span_from_motor_outputs_when_the_log_starts_at_arming():
    """A log cut at arming (no EV, no ARM) spans from its first motor output above idle."""
    from tlm_process.detect.data import armed_span

    rcou = pd.DataFrame({"TimeUS": [1_000_000, 2_000_000, 3_000_000, 9_000_000],
                         **{f"C{i}": [1000.0, 1000.0, 1200.0, 1500.0] for i in range(1, 5)}})
    gps = pd.DataFrame({"TimeUS": [500_000, 9_500_000], "I": [0, 0]})
    (t0, t1), how = armed_span({"RCOU": rcou, "GPS": gps}, {"MOT_SPIN_ARM": 0.1})
    assert t1 == 9_500_000 and how != "never armed: whole log"
    assert t0 in (500_000, 3_000_000)
    assert isinstance(LogData("x", "x", {}, {}, (t0, t1), how), LogData)


def test_training_reads_tlm_fly_folders_with_their_parameters(normal_flight, tmp_path):
    """A tlm fly folder is a training input: its tables, its parameters (FRAME_CLASS for the
    motor channels) and its (empty) fault list."""
    from tlm_process.detect.data import read_training

    normal_flight.write(tmp_path / "f1", formats=("parquet",))
    (log,) = list(read_training([tmp_path / "f1"]))
    assert log.windows == [] and log.arming == "EV 10"
    assert log.params.get("FRAME_CLASS") == 1.0
    assert {"GPS", "IMU", "XKF4", "RCOU", "ERR"} <= set(log.tables)


def test_class_weights_give_every_fault_class_the_same_total():
    from tlm_process.detect.train import class_weights

    y = np.array([0] * 10 + [3] * 6 + [9] * 2)
    w = class_weights(y, 4)
    assert (w[y == 0] == 4).all()
    assert w[y == 3].sum() == pytest.approx(w[y == 9].sum()) == pytest.approx(4.0)


def test_a_generate_data_set_is_summarised_in_the_manifest(tmp_path):
    from tlm_process.detect.train import _source_card

    (tmp_path / "manifest.json").write_text(json.dumps(
        {"format": "tlm.dataset", "seed": 4, "flights": 12, "tlm_version": "0.1.0",
         "settings": {"scenario": {"kinds": {"none": 1.0}}}}))
    card = _source_card(str(tmp_path))
    assert card["kind"] == "tlm generate" and card["seed"] == 4 and card["flights"] == 12
    assert _source_card(str(tmp_path / "x.bin")) == {"path": str(tmp_path / "x.bin")}


def test_older_firmware_names_are_read_as_4x_names():
    from tlm_process.detect.channels import align

    ekf2 = pd.DataFrame({"TimeUS": [0], "C": [0], "SV": [0.1]})
    rcou = pd.DataFrame({"TimeUS": [0], "Ch1": [1500], "Ch2": [1500]})
    rcin = pd.DataFrame({"TimeUS": [0], "Chan1": [1500]})
    out = align({"NKF4": ekf2, "RCOU": rcou, "RCIN": rcin})
    assert out["XKF4"] is ekf2
    assert list(out["RCOU"].columns) == ["TimeUS", "C1", "C2"]
    assert list(out["RCIN"].columns) == ["TimeUS", "C1"]


def test_training_refuses_a_log_without_fault_labels(tmp_path):
    """A log with no sidecar and no fault records would be learnt as a normal flight."""
    from tlm_process.detect.data import read_training

    (tmp_path / "n.bin").symlink_to(reference_path("normal_s11.bin"))
    with pytest.raises(DetectError, match="no fault labels"):
        list(read_training([tmp_path / "n.bin"]))
    (tmp_path / "n.json").write_text('{"faults": []}')
    (log,) = list(read_training([tmp_path / "n.bin"]))
    assert log.windows == []


# --------------------------------------------------------------------------------------------
# The paper's per-table view: tlm train --models on a tlm process data set
# --------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def table_model(tmp_path_factory):
    d = _linked_logs(tmp_path_factory.mktemp("table"))
    ds = d / "ds-tlm"
    assert main(["process", *[str(d / f"{n}.bin") for n in _TRAIN_LOGS], "--out", str(ds),
                 "--quiet", "--plots", "0"]) == 0
    out = d / "model"
    assert main(["train", str(ds), "--models", "WindowHGB", "--tables", "GPS", "--out",
                 str(out), "--rounds", "8", "--min-child-weight", "1", "--quiet",
                 "--drop-features", "GPS.HDop"]) == 0
    return ds, out


def test_a_per_table_model_saves_its_table_window_and_scaler(table_model):
    ds, out = table_model
    m = json.loads((out / "manifest.json").read_text())
    assert m["model"] == "WindowHGB" and m["table"] == "GPS"
    assert "GPS.HDop" not in m["channels"] and "GPS.Spd" in m["channels"]
    assert set(m["scaler"]["ranges"]) == {c.split(".")[1] for c in m["channels"]}
    assert m["window"]["seconds"] == [2.0, 10.0] and not m["window"]["centred"]
    assert m["sources"][0]["kind"] == "tlm process"
    det = load_detector(out)
    assert det.kind == "WindowHGB"


def test_a_per_table_model_detects_on_a_log(table_model, tmp_path):
    _, out = table_model
    log = reference_path("combined_s21.bin")
    assert main(["detect", str(out), str(log), "--out", str(tmp_path / "f"), "--quiet"]) == 0
    pred = pd.read_parquet(tmp_path / "f" / "combined_s21" / "predictions.parquet")
    steps = np.diff(pred["TimeUS"].to_numpy())
    assert np.median(steps) == pytest.approx(200_000, rel=0.05)  # the GPS rows, 5 Hz
    summary = pd.read_csv(tmp_path / "f" / "summary.csv")
    gps = summary[summary["class"] == "GPS"]
    assert len(gps) and abs(gps["start_s"].iloc[0] - 71.7) < 3.0
    # the decision per row on the table's own rows: the GPS fault found is the GPS rows' fault
    t = pred["TimeUS"] * 1e-6
    inside = (t >= gps["start_s"].iloc[0] - 0.01) & (t < gps["end_s"].iloc[0] - 0.01)
    assert inside.any() and (pred["fault"][inside] == gps["label"].iloc[0]).all()


def test_train_models_refuses_what_it_cannot_save(table_model, tmp_path, capsys):
    ds, _ = table_model
    assert main(["train", str(ds), "--models", "RandomForest", "--tables", "GPS", "--out",
                 str(tmp_path / "a")]) == 2
    assert "pickles" in capsys.readouterr().err and not (tmp_path / "a").exists()
    assert main(["train", str(ds), "--out", str(tmp_path / "b")]) == 2
    assert "--models" in capsys.readouterr().err  # the whole-log detector needs raw flights
    assert main(["train", str(ds), "--models", "WindowHGB", "--tables", "GPS,IMU", "--out",
                 str(tmp_path / "c")]) == 2
    assert "one window model and one table" in capsys.readouterr().err
    assert main(["train", str(ds), "--models", "WindowHGB", "--tables", "GPS", "--out",
                 str(tmp_path / "d"), "--drop-features", "GPS.Nope"]) == 2
    assert "GPS.Nope is no feature" in capsys.readouterr().err
