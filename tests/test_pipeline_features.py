"""Feature processing (Algorithm 2): drop lists, instance policy, merging flights."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from tlm_process.pipeline import PipelineError, feature_table, merge_tables, process_flight
from tlm_process.pipeline.features import DROP, INSTANCE_COLUMN, TIME_COLUMNS
from tlm_process.pipeline.ingest import Flight
from tlm_process.pipeline.process import ProcessOptions
from tlm_sim.flightlog import SCHEMAS

EXPECTED = {
    "GPS": ["Status", "NSats", "HDop", "Spd", "GCrs", "VZ"],
    "IMU": ["GyrX", "GyrY", "GyrZ", "AccX", "AccY", "AccZ", "GH", "AH"],
    "RATE": ["RDes", "R", "ROut", "PDes", "P", "POut", "YDes", "Y", "YOut", "ADes", "A", "AOut",
             "AOutSlew"],
    "VIBE": ["VibeX", "VibeY", "VibeZ"],
}


def test_drop_lists_name_real_columns_with_reasons():
    for table, drops in DROP.items():
        cols = SCHEMAS[table].columns
        for col, reason in drops.items():
            assert col in cols, (table, col)
            assert len(reason) > 20
        # every column is either dropped, a feature or TimeUS: nothing is left undecided
        assert set(cols) == set(drops) | set(EXPECTED[table]) | {"TimeUS"}
        if table in INSTANCE_COLUMN:
            assert INSTANCE_COLUMN[table] in drops
    assert all(len(r) > 20 for r in TIME_COLUMNS.values())


def _processed(flight_log, **opts):
    f = Flight("f1", "mem", "tlm", dict(flight_log.tables), [], None)
    return process_flight(f, ProcessOptions(**opts))


def test_features_of_a_tlm_flight(normal_flight):
    p = _processed(normal_flight)
    for table, feats in EXPECTED.items():
        df = p.features[table]
        assert list(df.columns) == ["flight", "TimeUS", "label", *feats]
        assert (df["flight"] == "f1").all() and str(df["flight"].dtype) == "string"
        assert df["TimeUS"].is_monotonic_increasing
        for c in feats:
            assert df[c].dtype == np.float64


def test_instance_zero_only_matches_the_papers_row_ratios(normal_flight):
    """Paper Table 7: IMU = 5.0 x GPS rows, VIBE = 1.0 x RATE rows (one instance each)."""
    p = _processed(normal_flight)
    n = {t: len(df) for t, df in p.features.items()}
    assert n["IMU"] / n["GPS"] == pytest.approx(12773 / 2555, rel=0.01)
    assert n["VIBE"] / n["RATE"] == pytest.approx(5109 / 5109, rel=0.01)
    imu = p.labelled["IMU"]
    assert n["IMU"] == int((imu["I"] == 0).sum())
    assert p.features["IMU"]["TimeUS"].tolist() == imu[imu["I"] == 0]["TimeUS"].tolist()


def test_all_instances_keep_the_instance_column_as_non_feature(normal_flight):
    p = _processed(normal_flight, instance=None)
    imu = p.features["IMU"]
    assert list(imu.columns[:4]) == ["flight", "TimeUS", "label", "I"]
    assert sorted(imu["I"].unique().tolist()) == [0, 1]
    assert len(imu) == len(p.labelled["IMU"])  # every row of the armed phase
    second = _processed(normal_flight, instance=1).features["IMU"]
    assert len(second) == int((p.labelled["IMU"]["I"] == 1).sum())


def test_time_columns_of_other_exporters_are_dropped():
    df = pd.DataFrame({"timestamp": [1.7e9, 1.7e9 + 0.2], "TimeUS": [1, 2], "I": [0, 0],
                       "Status": [6, 1], "Spd": [1.0, 2.0], "Lat": [1.0, 1.0], "label": [0, 1]})
    out = feature_table("GPS", df, "x")
    assert list(out.columns) == ["flight", "TimeUS", "label", "Status", "Spd"]


def test_non_numeric_feature_is_an_error():
    df = pd.DataFrame({"TimeUS": [1], "VibeX": ["a"], "label": [0]})
    with pytest.raises(PipelineError, match="not numeric"):
        feature_table("VIBE", df, "x")
    with pytest.raises(PipelineError, match="no feature list"):
        feature_table("ATT", df, "x")


def test_merge_flights_per_table_and_reject_different_columns():
    a = {"GPS": feature_table("GPS", pd.DataFrame(
        {"TimeUS": [1, 2], "Spd": [1.0, 2.0], "label": [0, 0]}), "a")}
    b = {"GPS": feature_table("GPS", pd.DataFrame(
        {"TimeUS": [5], "Spd": [3.0], "label": [2]}), "b")}
    m = merge_tables([a, b])["GPS"]
    assert m["flight"].tolist() == ["a", "a", "b"] and m["label"].tolist() == [0, 0, 2]
    c = {"GPS": feature_table("GPS", pd.DataFrame(
        {"TimeUS": [5], "Spd": [3.0], "NSats": [9], "label": [0]}), "c")}
    with pytest.raises(PipelineError, match=r"c: GPS columns differ from flight a's "
                                            r"\(extra: NSats; missing: -\)"):
        merge_tables([a, c])
