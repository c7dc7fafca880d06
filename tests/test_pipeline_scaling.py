"""Min-max scaling (Eq. 6): fitted on training flights only, saved, applied to new flights."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from tlm_process.pipeline import MinMaxScaler, PipelineError, split_flights
from tlm_process.pipeline.features import feature_table
from tlm_process.pipeline.process import build_dataset


def _table(flight: str, values: dict[str, list[float]]) -> pd.DataFrame:
    n = len(next(iter(values.values())))
    df = pd.DataFrame({"flight": pd.Series([flight] * n, dtype="string"),
                       "TimeUS": np.arange(n, dtype=np.int64) * 200_000,
                       "label": np.zeros(n, dtype=np.int8)})
    for k, v in values.items():
        df[k] = np.asarray(v, dtype=np.float64)
    return df


def _tables(test_values: list[float]) -> dict[str, pd.DataFrame]:
    gps = pd.concat([_table("a", {"Spd": [0.0, 2.0, 4.0], "NSats": [10.0, 10.0, 10.0]}),
                     _table("b", {"Spd": [1.0, 8.0], "NSats": [10.0, 10.0]}),
                     _table("test1", {"Spd": test_values, "NSats": [3.0] * len(test_values)})],
                    ignore_index=True)
    return {"GPS": gps}


def test_fit_uses_training_flights_only():
    s = MinMaxScaler.fit(_tables([-50.0, 99.0]), ["a", "b"])
    assert s.ranges["GPS"]["Spd"] == (0.0, 8.0)
    assert s.ranges["GPS"]["NSats"] == (10.0, 10.0)
    assert s.train_flights == ["a", "b"]
    # whatever the test flight holds, the scaler is the same
    for vals in ([1e9, -1e9], [np.nan, 3.0], [4.0]):
        assert MinMaxScaler.fit(_tables(vals), ["a", "b"]).ranges == s.ranges
    # and including it would have changed it
    assert MinMaxScaler.fit(_tables([-50.0, 99.0]), ["a", "b", "test1"]).ranges != s.ranges


def test_transform_is_eq6_and_not_clipped():
    tables = _tables([-8.0, 16.0])
    s = MinMaxScaler.fit(tables, ["a", "b"])
    out = s.transform(tables)["GPS"]
    assert out["Spd"].tolist() == pytest.approx([0, 0.25, 0.5, 0.125, 1.0, -1.0, 2.0])
    assert (out["NSats"] == 0.0).all()  # constant on the training flights -> 0
    assert out["flight"].tolist() == tables["GPS"]["flight"].tolist()
    assert out["TimeUS"].tolist() == tables["GPS"]["TimeUS"].tolist()
    back = s.inverse_table("GPS", out)
    assert back["Spd"].tolist() == pytest.approx(tables["GPS"]["Spd"].tolist())


def test_saved_scaler_scales_new_flights_the_same(tmp_path):
    tables = _tables([3.0])
    s = MinMaxScaler.fit(tables, ["a", "b"])
    path = s.save(tmp_path / "scaler.json")
    loaded = MinMaxScaler.load(path)
    assert loaded.ranges == s.ranges and loaded.train_flights == ["a", "b"]
    new = _table("later", {"Spd": [2.0, 6.0], "NSats": [10.0, 7.0]})
    assert loaded.transform_table("GPS", new)["Spd"].tolist() == [0.25, 0.75]
    with pytest.raises(PipelineError, match="lacks feature"):
        loaded.transform_table("GPS", new.drop(columns="NSats"))
    with pytest.raises(PipelineError, match="knows no table"):
        loaded.transform_table("IMU", new)
    (tmp_path / "bad.json").write_text('{"format": "something"}')
    with pytest.raises(PipelineError, match="bad.json: not a tlm min-max scaler"):
        MinMaxScaler.load(tmp_path / "bad.json")


def test_split_flights():
    ids = [f"f{i}" for i in range(10)]
    assert split_flights(ids) == (ids, [])
    train, test = split_flights(ids, 0.25, seed=3)
    assert len(test) == 2 and set(train) | set(test) == set(ids) and not set(train) & set(test)
    assert split_flights(ids, 0.25, seed=3) == (train, test)  # seeded
    assert split_flights(ids, test_patterns=["f1*"]) == (
        [f for f in ids if f != "f1"], ["f1"])
    with pytest.raises(PipelineError, match="matches no flight"):
        split_flights(ids, test_patterns=["nope*"])
    with pytest.raises(PipelineError, match="at least one for training"):
        split_flights(ids, test_patterns=["f*"])
    with pytest.raises(PipelineError, match=r"\[0, 1\)"):
        split_flights(ids, 1.0)


def test_dataset_scaler_never_sees_test_flights(normal_flight):
    """Build a data set from a real flight and a wildly different 'test' copy of it."""
    from tlm_process.pipeline import process_flight
    from tlm_process.pipeline.ingest import Flight

    def processed(fid: str, gain: float):
        tables = {n: df.copy() for n, df in normal_flight.tables.items()}
        for c in ("Spd", "VZ"):
            tables["GPS"][c] = tables["GPS"][c] * gain
        tables["IMU"]["AccZ"] = tables["IMU"]["AccZ"] * gain
        return process_flight(Flight(fid, fid, "tlm", tables, [], None))

    train = processed("train_flight", 1.0)
    ds_a = build_dataset([train, processed("test_flight", 100.0)], test_patterns=["test_*"])
    ds_b = build_dataset([train, processed("test_flight", -7.0)], test_patterns=["test_*"])
    assert ds_a.scaler is not None and ds_b.scaler is not None
    assert ds_a.scaler.ranges == ds_b.scaler.ranges
    assert ds_a.test == ["test_flight"] and ds_a.train == ["train_flight"]
    ref = feature_table("GPS", train.labelled["GPS"], "train_flight")
    assert ds_a.scaler.ranges["GPS"]["Spd"] == (ref["Spd"].min(), ref["Spd"].max())
    gps = ds_a.tables["GPS"]
    tr = gps[gps["split"] == "train"]
    assert tr["Spd"].min() == 0.0 and tr["Spd"].max() == 1.0
    assert gps[gps["split"] == "test"]["Spd"].max() > 50  # 100x the training range
