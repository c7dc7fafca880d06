"""``tlm evaluate`` end to end on a tiny data set of three tlm flights (built once per test
session), transfer to a reference SITL log, determinism and user errors."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from tests.conftest import reference_path
from tlm_process.cli import main
from tlm_process.evaluate.data import EvaluateError

FAST = "ZeroR,OneR,J48,RandomTree,WindowHGB"


@pytest.fixture(scope="session")
def tiny_ds(tmp_path_factory):
    """Missions 1-3 with the paper's fault sequence (seeds 1-3); mission 3 is the test
    flight."""
    from tlm_process.pipeline.ingest import Flight, parse_records
    from tlm_process.pipeline.process import build_dataset, process_flight, write_dataset
    from tlm_sim import fly
    from tlm_sim.faults import FaultSchedule

    processed = []
    root = tmp_path_factory.mktemp("eval")
    for m in (1, 2, 3):
        log = fly(m, faults=FaultSchedule.paper(m), seed=m)
        if m == 3:
            log.write(root / "m3_folder", formats=("parquet",))
        fl = Flight(id=f"m{m}", source=f"tlm mission {m}", kind="tlm",
                    tables=dict(log.tables), records=parse_records(log.faults))
        p = process_flight(fl)
        p.release()
        processed.append(p)
    ds = build_dataset(processed, test_patterns=["m3"])
    out = root / "ds"
    write_dataset(ds, out)
    return out


@pytest.fixture(scope="session")
def tiny_flight_folder(tiny_ds):
    """Mission 3's flight (the tiny data set's test flight) as a ``tlm fly`` folder."""
    return tiny_ds.parent / "m3_folder"


def _run(capsys, *argv):
    rc = main(["evaluate", *map(str, argv)])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


def test_evaluate_end_to_end_table_json_and_pngs(tiny_ds, tmp_path, capsys):
    pytest.importorskip("torch")
    rj = tmp_path / "r.json"
    rc, out, err = _run(capsys, tiny_ds, "--table", "GPS", "--models", FAST + ",CNN",
                        "--cnn-epochs", "1", "--json", rj, "--out", tmp_path / "png")
    assert rc == 0, err
    head = next(line for line in out.splitlines() if line.startswith("Method"))
    assert head.split()[:8] == ["Method", "Correct%", "Incorrect%", "TP", "FP", "Precision",
                                "Recall", "F1"]
    zeror = next(line for line in out.splitlines() if line.startswith("ZeroR"))
    assert zeror.split()[5] == "?"  # never predicts a fault: precision undefined
    assert "precision undefined" in out and "[GPS] J48:" in err and "CNN epoch 1/1" in err
    res = json.loads(rj.read_text())
    assert list(res) == ["GPS"] and list(res["GPS"]) == FAST.split(",") + ["CNN"]
    r = res["GPS"]["J48"]
    for key in ("accuracy", "macro_f1", "weighted_precision", "weighted_recall", "weighted_f1",
                "weighted_tp_rate", "weighted_fp_rate", "per_class", "confusion"):
        assert key in r
    assert sum(map(sum, r["confusion"])) == r["n_test"] > 0
    assert r["fit_seconds"] >= 0 and r["predict_seconds"] >= 0
    assert "GPS: time per model" in out and "rows fitted" in out
    assert 0 < res["GPS"]["WindowHGB"]["n_fit"] <= r["n_train"]  # GPS 5 Hz: thinned to 5 Hz
    assert res["GPS"]["ZeroR"]["weighted_precision"] is None
    assert res["GPS"]["WindowHGB"]["macro_f1"] > res["GPS"]["ZeroR"]["macro_f1"]
    pngs = {p.name for p in (tmp_path / "png").iterdir()}
    assert {"GPS_J48_confusion.png", "GPS_CNN_training.png", "report.txt"} <= pngs


def test_evaluate_is_deterministic_given_the_seed(tiny_ds, tmp_path, capsys):
    def once(name, *extra):
        rc, _, err = _run(capsys, tiny_ds, "--table", "GPS", "--models",
                          "RandomTree,RandomForest", "--seed", "4", "--quiet",
                          "--json", tmp_path / name, *extra)
        assert rc == 0, err
        res = json.loads((tmp_path / name).read_text())["GPS"]
        return {m: (r["confusion"], r["macro_f1"]) for m, r in res.items()}

    a, b = once("a.json"), once("b.json")
    assert a == b
    rnd = once("c.json", "--split", "random")
    assert rnd != a


def test_evaluate_results_do_not_depend_on_jobs(tiny_ds, tiny_flight_folder, tmp_path,
                                                capsys, monkeypatch):
    """--jobs changes the speed only: RandomForest and KNN (threads), SMO (processes),
    Logistic (BLAS), the window models (OpenMP), the CNN and SeqCNN (torch), and J48,
    RandomTree and OneR (one core each, side by side on two threads) give the same test
    and transfer confusion matrices and the same training curves on 1 and 2 threads."""
    pytest.importorskip("torch")
    monkeypatch.setattr("tlm_process.evaluate.sequence.STEPS", 20)  # a short SeqCNN fit

    def once(jobs):
        rj = tmp_path / f"jobs{jobs}.json"
        rc, _, err = _run(capsys, tiny_ds, "--table", "GPS", "--models",
                          "Logistic,SMO,KNN,J48,RandomForest,RandomTree,OneR,CNN,WindowHGB,"
                          "SeqCNN", "--cnn-epochs",
                          "2",
                          "--jobs", jobs, "--quiet", "--test-on", tiny_flight_folder,
                          "--json", rj)
        assert rc == 0, err
        res = json.loads(rj.read_text())["GPS"]
        return {m: (r["confusion"], r["transfer"]["confusion"], r["macro_f1"],
                    [(h["loss"], h["accuracy"], h["val_loss"]) for h in r.get("history", [])])
                for m, r in res.items()}

    one, two = once(1), once(2)
    assert len(one["CNN"][3]) == 2 and len(one["SeqCNN"][3]) == 10
    assert one == two


def test_evaluate_booster_chooses_the_window_models_boosting(tiny_ds, tmp_path, capsys):
    """--booster sklearn fits the window models with scikit-learn's booster (recorded as
    ``booster`` in R.json; the other models are untouched); a bad name is a usage error."""
    def once(*extra):
        rj = tmp_path / f"b{len(extra)}.json"
        rc, _, err = _run(capsys, tiny_ds, "--table", "GPS", "--models", "J48,WindowHGB",
                          "--quiet", "--json", rj, *extra)
        assert rc == 0, err
        return json.loads(rj.read_text())["GPS"]

    xgb, sk = once(), once("--booster", "sklearn")
    assert xgb["WindowHGB"]["booster"] == "xgboost" and sk["WindowHGB"]["booster"] == "sklearn"
    assert "booster" not in sk["J48"] and sk["J48"]["confusion"] == xgb["J48"]["confusion"]
    assert sk["WindowHGB"]["confusion"] != xgb["WindowHGB"]["confusion"]
    with pytest.raises(SystemExit) as e:
        _run(capsys, tiny_ds, "--models", "WindowHGB", "--booster", "lightgbm")
    assert e.value.code == 2 and "lightgbm" in capsys.readouterr().err


def test_command_booster_names_match_the_temporal_module():
    from tlm_process.commands.evaluate import BOOSTER_NAMES
    from tlm_process.evaluate.temporal import WINDOW_BOOSTERS

    assert BOOSTER_NAMES == WINDOW_BOOSTERS


def test_evaluate_train_hz_thins_training_rows_only(tiny_ds, tmp_path, capsys):
    def once(hz):
        rj = tmp_path / f"hz{hz}.json"
        rc, _, err = _run(capsys, tiny_ds, "--table", "GPS", "--models", "J48,WindowHGB",
                          "--train-hz", hz, "--quiet", "--json", rj)
        assert rc == 0, err
        return json.loads(rj.read_text())["GPS"]

    every, thin = once("0"), once("1")  # GPS logs at 5 Hz: 1 Hz keeps every 5th row
    for m in ("J48", "WindowHGB"):
        assert every[m]["train_hz"] == 0 and every[m]["n_fit"] == every[m]["n_train"]
        assert thin[m]["train_hz"] == 1 and thin[m]["n_test"] == every[m]["n_test"]
        assert abs(thin[m]["n_fit"] - thin[m]["n_train"] / 5) <= 2  # 2 training flights


def test_evaluate_max_rows_on_the_command_line(tiny_ds, tmp_path, capsys):
    rj = tmp_path / "cap.json"
    rc, _, err = _run(capsys, tiny_ds, "--table", "GPS", "--models", "J48", "--train-hz", "0",
                      "--max-rows", "300", "--quiet", "--json", rj)
    assert rc == 0, err
    r = json.loads(rj.read_text())["GPS"]["J48"]
    assert r["max_rows"] == 300 and r["n_fit"] <= 300 < r["n_train"]
    with pytest.raises(SystemExit) as e:
        _run(capsys, tiny_ds, "--max-rows", "-5")
    assert e.value.code == 2 and "--max-rows" in capsys.readouterr().err


@pytest.mark.parametrize("option", ["--train-hz", "--normal-hz"])
@pytest.mark.parametrize("value", ["-1", "nan", "inf", "1e-308", "0.0009"])
def test_evaluate_rates_are_0_or_at_least_a_millihertz(capsys, option, value):
    """A rate too small to thin by (1e-308 Hz overflowed) is refused like a negative one."""
    from tlm_process.commands.evaluate import _rate_hz

    assert _rate_hz("0") == 0 and _rate_hz("0.001") == 0.001
    with pytest.raises(SystemExit) as e:
        main(["evaluate", "ds", option, value])
    assert e.value.code == 2
    assert f"argument {option}: must be 0 (every row)" in capsys.readouterr().err


def test_evaluate_normal_hz_thins_normal_training_rows_and_weights_them(tiny_ds):
    from tlm_process.evaluate import evaluate, load_dataset

    ds = load_dataset(tiny_ds, ["GPS"])
    models = ["Logistic", "RandomForest", "WindowHGB"]
    plain = evaluate(ds, tables=["GPS"], models=models, train_hz=0, normal_hz=0)["GPS"]
    thin = evaluate(ds, tables=["GPS"], models=models, train_hz=0, normal_hz=1)["GPS"]
    y = ds.tables["GPS"]["label"]
    for m in models:
        assert plain[m]["normal_every"] == 1 and thin[m]["normal_every"] == 5  # 5 Hz -> 1 Hz
        n_fault = plain[m]["n_fit"] - thin[m]["n_fit"]  # dropped rows: 4 of 5 Normal rows
        assert abs(n_fault - 0.8 * (y == 0).sum() * plain[m]["n_train"] / len(y)) < 30
        assert thin[m]["n_test"] == plain[m]["n_test"]
    with pytest.raises(EvaluateError, match="KNN takes no sample weights"):
        evaluate(ds, tables=["GPS"], models=["KNN"], normal_hz={"KNN": 1.0})
    with pytest.raises(EvaluateError, match="unknown booster 'lightgbm'"):
        evaluate(ds, tables=["GPS"], models=["WindowHGB"], booster="lightgbm")
    from tlm_process.evaluate.models import DEFAULT_NORMAL_HZ, WEIGHTED_MODELS

    assert set(DEFAULT_NORMAL_HZ) <= set(WEIGHTED_MODELS)
    default = evaluate(ds, tables=["GPS"], models=["RandomForest", "J48"])["GPS"]
    assert default["RandomForest"]["normal_hz"] == 1.0  # the default: 5 Hz, Normal 1 Hz
    assert default["RandomForest"]["normal_every"] == 5
    assert default["J48"]["normal_every"] == 1 and default["J48"]["normal_hz"] == 0.0


def test_evaluate_max_rows_caps_the_rows_fitted_normal_rows_first(tiny_ds):
    from tlm_process.evaluate import evaluate, load_dataset
    from tlm_process.evaluate.models import DEFAULT_MAX_ROWS

    ds = load_dataset(tiny_ds, ["GPS"])
    models = ["RandomForest", "J48", "CNN"]
    free = evaluate(ds, tables=["GPS"], models=models, train_hz=0, normal_hz=0,
                    max_rows=0, cnn_epochs=1)["GPS"]
    y = ds.tables["GPS"]["label"]
    share = float((y != 0).mean())  # fault rows: kept by the weighted models
    cap = int(free["J48"]["n_fit"] * (share + 1.0) / 2)
    capped = evaluate(ds, tables=["GPS"], models=models, train_hz=0, normal_hz=0,
                      max_rows=cap, cnn_epochs=1)["GPS"]
    for m in models:
        r = capped[m]
        assert r["max_rows"] == cap and r["n_fit"] <= cap < free[m]["n_fit"], m
        assert r["n_test"] == free[m]["n_test"]  # test rows are never thinned
    assert 0.05 < share < 0.6
    # RandomForest and the CNN take weights: their Normal rows went, every fault row stayed
    n_fault = int((y != 0).sum() * free["J48"]["n_train"] / len(y))
    for m in ("RandomForest", "CNN"):
        assert capped[m]["normal_every"] > 1 and capped[m]["train_hz"] == 0
        assert capped[m]["n_fit"] > 0.8 * n_fault
    assert capped["J48"]["normal_every"] == 1 and capped["J48"]["train_hz"] > 0  # stride
    assert free["J48"]["max_rows"] == 0
    assert DEFAULT_MAX_ROWS["RandomForest"] == 100_000 and "J48" not in DEFAULT_MAX_ROWS
    with pytest.raises(EvaluateError, match="row budget"):
        evaluate(ds, tables=["GPS"], models=["J48"], max_rows=-1)


def test_sample_weights_reach_the_final_estimator_of_nested_pipelines():
    from tlm_process.evaluate.models import WEIGHTED_MODELS, make_model
    from tlm_process.evaluate.runner import _fit

    rng = np.random.default_rng(0)
    X = rng.normal(size=(300, 3))
    y = (X[:, 0] > 0.3).astype(np.int64)
    for m in WEIGHTED_MODELS:
        one = _fit(make_model(m, n_features=3), X, y, None, np.ones(len(y)))
        none = _fit(make_model(m, n_features=3), X, y, None)
        assert (one.predict(X) == none.predict(X)).all(), m  # unit weights change nothing
    heavy = np.where(y == 1, 50.0, 1.0)  # weights move the prior: more rows called 1
    zr = _fit(make_model("ZeroR", n_features=3), X, y, None, heavy)
    assert (zr.predict(X) == 1).all() and (make_model("ZeroR", n_features=3).fit(X, y)
                                             .predict(X) == 0).all()


def test_evaluate_transfer_to_a_reference_sitl_log(tiny_ds, tmp_path, capsys):
    log = reference_path("combined_s21.bin")
    rj = tmp_path / "t.json"
    rc, out, err = _run(capsys, tiny_ds, "--table", "GPS", "--models", "OneR,WindowHGB",
                        "--test-on", log, "--json", rj, "--out", tmp_path / "o")
    assert rc == 0, err
    t = json.loads(rj.read_text())["GPS"]["WindowHGB"]["transfer"]
    assert t["n"] > 1000 and len(t["confusion"]) == 5
    assert t["per_class"]["GPS"]["support"] > 100  # combined_s21 has a ~29 s GPS fault
    assert "xfer macro-F1" in out and "largest feature distribution differences" in out
    # event metrics of the test flight and of the SITL log (combined_s21: GPS, Acc, Engine,
    # RC faults, one each), in the JSON and as tables
    assert list(t["detection"]) == ["GPS", "Acc", "Engine", "RC"]
    assert all(d["events"] == 1 for d in t["detection"].values())
    assert t["normal_hours"] > 0 and t["false_alarms_per_hour"] >= 0
    r = json.loads(rj.read_text())["GPS"]["OneR"]
    assert r["detection"] and r["false_alarms"] >= 0 and r["persistence_s"] == 1.0
    assert "GPS: detection delay and false alarms on the test rows" in out
    assert "GPS: detection delay and false alarms on the transfer rows" in out
    assert (tmp_path / "o" / "feature_shift.csv").exists()
    assert (tmp_path / "o" / "GPS_OneR_transfer_confusion.png").exists()


def test_evaluate_cross_validation_refits_on_every_flight_for_transfer(
        tiny_ds, tiny_flight_folder, tmp_path, capsys):
    rj = tmp_path / "cv.json"
    rc, out, err = _run(capsys, tiny_ds, "--table", "RATE", "--models", "ZeroR,J48",
                        "--folds", "3", "--test-on", tiny_flight_folder, "--json", rj)
    assert rc == 0, err
    r = json.loads(rj.read_text())["RATE"]["J48"]
    total = sum(map(sum, r["confusion"]))
    assert r["folds"] == 3 and r["n_test"] == total  # every row tested once
    assert "flight split, 3 folds" in out
    # the folder is flight m3 read again: same rows as in the data set; and it is one of the
    # flights the transfer model was refitted on, so the tree knows it better than CV's
    m3 = pd.read_parquet(tiny_ds / "RATE.parquet").query("flight == 'm3'")
    assert r["transfer"]["n"] == len(m3)
    assert r["transfer"]["accuracy"] > r["accuracy"]


@pytest.mark.parametrize("args, message", [
    (["{missing}"], "no such data set folder"),
    (["{empty}"], "not a 'tlm process' output folder"),
    (["{ds}", "--table", "BARO"], "unknown table 'BARO'"),
    (["{ds}", "--models", "J48,C4.5"], "unknown model 'C4.5'"),
    (["{ds}", "--test-frac", "0.3"], "--split random only"),
    (["{ds}", "--test-on", "{missing}"], "no such file or folder"),
    (["{ds}", "--drop-features", "RATE.Nope"], "unknown feature 'RATE.Nope'"),
    (["{ds}", "--drop-features", "BARO.Alt"], "no table BARO"),
    (["{ds}", "--drop-features", "AOutSlew"], "'AOutSlew' is not TABLE.COL"),
    (["{ds}", "--assume-normal"], "--assume-normal applies to --test-on"),
])
def test_evaluate_user_errors_are_one_line_exit_2(tiny_ds, tmp_path, capsys, args, message):
    (tmp_path / "empty").mkdir()
    subst = {"missing": tmp_path / "nope", "empty": tmp_path / "empty", "ds": tiny_ds}
    argv = [a.format(**subst) for a in args]
    if "--models" not in args:
        argv += ["--models", "ZeroR"]
    rc, _, err = _run(capsys, *argv)
    assert rc == 2
    errors = [line for line in err.splitlines() if line.startswith("tlm: error: ")]
    assert len(errors) == 1 and message in errors[0]


@pytest.fixture(scope="session")
def unlabelled_bin(tmp_path_factory):
    """A normal tlm flight (mission 1, seed 0) as a lone ``normal.bin``: no sidecar, no
    faults.json, no fault MSG lines or SIM_* parameter changes in it."""
    from tests.conftest import flown
    from tlm_sim.flightlog.binwriter import write_bin

    return write_bin(flown(1, 0), tmp_path_factory.mktemp("bare") / "normal.bin")


def test_evaluate_refuses_a_transfer_log_without_fault_labels(tiny_ds, unlabelled_bin,
                                                              tmp_path, capsys):
    rc, out, err = _run(capsys, tiny_ds, "--table", "GPS", "--models", "ZeroR",
                        "--test-on", unlabelled_bin, "--quiet")
    assert rc == 2 and out == ""
    errors = [line for line in err.splitlines() if line.startswith("tlm: error: ")]
    assert len(errors) == 1 and errors == err.splitlines()
    assert f"{unlabelled_bin}: no fault labels found (no sidecar normal.json" in errors[0]
    assert "faults.json" in errors[0] and "--assume-normal" in errors[0]
    # --assume-normal: a normal flight, as before, and said so in R.json and the table
    rj = tmp_path / "r.json"
    rc, out, err = _run(capsys, tiny_ds, "--table", "GPS", "--models", "ZeroR",
                        "--test-on", unlabelled_bin, "--assume-normal", "--json", rj)
    assert rc == 0, err
    assert "without fault labels taken as normal flights (--assume-normal)" in err
    assert "logs without labels taken as normal" in out
    r = json.loads(rj.read_text())["GPS"]["ZeroR"]
    assert r["assume_normal"] is True
    assert r["transfer"]["n"] > 100 and r["transfer"]["accuracy"] == 1.0  # all Normal


@pytest.mark.parametrize("sidecar", ["normal.json", "faults.json"])
def test_evaluate_a_log_labelled_without_faults_is_not_refused(tiny_ds, unlabelled_bin,
                                                               tmp_path, capsys, sidecar):
    log = tmp_path / "normal.bin"
    log.write_bytes(unlabelled_bin.read_bytes())
    (tmp_path / sidecar).write_text('{"faults": []}')
    rj = tmp_path / "r.json"
    rc, _, err = _run(capsys, tiny_ds, "--table", "GPS", "--models", "ZeroR", "--quiet",
                      "--test-on", log, "--json", rj)
    assert rc == 0, err
    assert json.loads(rj.read_text())["GPS"]["ZeroR"]["assume_normal"] is False


def test_evaluate_drop_features_for_a_log_that_lacks_one(tiny_ds, tiny_flight_folder,
                                                         tmp_path, capsys):
    """A transfer log without RATE.AOutSlew (as Copter 4.0/4.1 logs): refused with the
    --drop-features that avoids it, which then drops it from training and transfer."""
    old = tmp_path / "old_fw"  # a CSV-kind folder: tables and faults.json
    old.mkdir()
    for name in ("GPS", "RATE", "POS", "EV"):
        df = pd.read_parquet(tiny_flight_folder / f"{name}.parquet")
        if name == "RATE":
            df = df.drop(columns="AOutSlew")
        df.to_parquet(old / f"{name}.parquet")
    meta = json.loads((tiny_flight_folder / "meta.json").read_text())
    (old / "faults.json").write_text(json.dumps({"faults": meta["faults"]}))
    rc, _, err = _run(capsys, tiny_ds, "--table", "RATE", "--models", "ZeroR", "--quiet",
                      "--test-on", old)
    assert rc == 2
    assert err.splitlines() == [
        f"tlm: error: {old}: RATE lacks the data set's feature(s) AOutSlew (older firmware "
        "may not log it): add --drop-features RATE.AOutSlew"]
    rj = tmp_path / "r.json"
    rc, out, err = _run(capsys, tiny_ds, "--table", "RATE", "--models", "ZeroR,J48",
                        "--quiet", "--test-on", old, "--drop-features", "rate.AOutSlew",
                        "--json", rj, "--out", tmp_path / "o")
    assert rc == 0, err
    assert "dropped RATE.AOutSlew" in out
    res = json.loads(rj.read_text())["RATE"]
    assert res["J48"]["dropped_features"] == ["RATE.AOutSlew"]
    m3 = pd.read_parquet(tiny_ds / "RATE.parquet").query("flight == 'm3'")
    assert res["J48"]["transfer"]["n"] == len(m3)  # the same flight
    shift = pd.read_csv(tmp_path / "o" / "feature_shift.csv")
    assert "AOutSlew" not in set(shift["feature"]) and "AOut" in set(shift["feature"])


def test_drop_features_leaves_the_data_set_consistent(tiny_ds):
    from tlm_process.evaluate.data import drop_features, load_dataset, parse_drop_features

    ds = load_dataset(tiny_ds, ["GPS", "RATE"])
    drop = parse_drop_features(["RATE.AOutSlew,RATE.AOut", "IMU.AccX", "RATE.AOut"], ds)
    assert drop == {"RATE": ["AOutSlew", "AOut"], "IMU": ["AccX"]}  # IMU: known, not loaded
    d = drop_features(ds, drop)
    assert d.dropped == {"RATE": ["AOutSlew", "AOut"]}
    assert d.features["GPS"] == ds.features["GPS"]
    assert d.features["RATE"] == [c for c in ds.features["RATE"] if c not in drop["RATE"]]
    assert not {"AOutSlew", "AOut"} & set(d.tables["RATE"].columns)
    assert list(d.scaler.ranges["RATE"]) == d.features["RATE"]
    assert "AOut" in ds.scaler.ranges["RATE"] and "AOut" in ds.tables["RATE"]  # a copy
    with pytest.raises(EvaluateError, match="leaves table GPS without features"):
        drop_features(ds, {"GPS": list(ds.features["GPS"])})


def test_evaluate_help_lists_models_and_splits(capsys):
    with pytest.raises(SystemExit) as e:
        main(["evaluate", "--help"])
    assert e.value.code == 0
    out = capsys.readouterr().out
    assert "WindowHGB" in out and "--split" in out and "--test-on" in out
    assert "--assume-normal" in out and "--drop-features" in out
