"""Reading flights: fault records, the four input kinds, folders of inputs."""

from __future__ import annotations

import json
import shutil
from functools import lru_cache

import pandas as pd
import pytest

from tlm_process.pipeline import IngestError, parse_records, process_flight, read_flights
from tlm_process.pipeline.ingest import detect_kind, expand_inputs, unique_ids


@lru_cache(maxsize=1)
def _fault_flight():
    from tlm_sim import fly
    from tlm_sim.faults import FaultSchedule

    return fly(1, faults=FaultSchedule.from_shorthand(["gps:40-60", "rc:100-130"]), seed=4)


def test_records_of_tlm_and_sidecar_shapes():
    recs = parse_records({"faults": [
        {"type": "gps", "label": 1, "start_time_us": 1_000_000, "end_time_us": 2_000_000,
         "start_lat": -35.1, "start_lon": 149.1, "start_alt": 20.0,
         "end_lat": -35.2, "end_lon": 149.2, "end_alt": 19.0},
        {"fault": "RC", "start_time_us": 3e6, "end_by": "flight end", "end_time_us": 9e6},
        {"label": 3, "start_lat": -35.1, "start_lon": 149.1, "start_alt": 0,
         "end_lat": -35.1, "end_lon": 149.1, "end_alt": 0},
    ]})
    assert [(r.type, r.label) for r in recs] == [("gps", 1), ("rc", 4), ("engine", 3)]
    assert recs[0].has_times and recs[0].has_positions and not recs[0].held_to_end
    assert recs[0].start_pos == (-35.1, 149.1, 20.0)
    assert recs[1].held_to_end and recs[1].has_times and not recs[1].has_positions
    assert not recs[2].has_times and recs[2].has_positions
    assert parse_records([]) == [] and parse_records({"faults": None}) == []


@pytest.mark.parametrize("rec,msg", [
    ({"type": "wind", "start_time_us": 1}, "unknown fault type 'wind'"),
    ({"type": "gps", "label": 2, "start_time_us": 1}, "label 2 does not match"),
    ({"label": 15, "start_time_us": 1}, "not a fault label"),
    ({"start_time_us": 1}, "needs 'type'"),
    ({"type": "gps"}, "no start"),
    ({"type": "gps", "start_time_us": 5, "end_time_us": 5}, "not after start_time_us"),
    ({"type": "gps", "start_time_us": -1}, "start_time_us must be"),
    ({"type": "gps", "start_lat": -35, "start_lon": 149}, "start_lat, start_lon and start_alt"),
    ({"type": "gps", "start_lat": -350, "start_lon": 149, "start_alt": 1}, "not a lat/lon"),
])
def test_bad_records_are_one_line_errors(rec, msg):
    with pytest.raises(IngestError, match=msg) as exc:
        parse_records([rec], "x.json")
    assert str(exc.value).startswith("x.json: fault 1") and "\n" not in str(exc.value)


def test_tlm_folder_csv_folder_and_dataset_read_the_same_flight(tmp_path):
    log = _fault_flight()
    tlm_dir = log.write(tmp_path / "tlmrun", formats=("parquet",))
    csv_dir = tmp_path / "mp_csv"
    log.write(csv_dir, formats=("csv",))
    (csv_dir / "meta.json").unlink()
    (csv_dir / "faults.json").write_text(json.dumps({"faults": log.faults}))
    assert detect_kind(tlm_dir) == "tlm" and detect_kind(csv_dir) == "csv"

    # a dataset: raw tables of two flights with a flight column, faults.parquet
    ds = tmp_path / "gen"
    ds.mkdir()
    for name in ("GPS", "IMU", "RATE", "VIBE", "EV"):
        df = log.tables[name]
        pd.concat([df.assign(flight="m1_s4"), df.assign(flight="m1_s5")]).to_parquet(
            ds / f"{name}.parquet")
    pd.DataFrame([{**r, "flight": f} for f in ("m1_s4", "m1_s5") for r in log.faults]
                 ).drop(columns=["params_start", "params_end"]).to_parquet(ds / "faults.parquet")
    assert detect_kind(ds) == "dataset"

    flights = read_flights([tlm_dir, csv_dir, ds])
    assert [f.id for f in flights] == ["tlmrun", "mp_csv", "gen:m1_s4", "gen:m1_s5"]
    assert [f.kind for f in flights] == ["tlm", "csv", "dataset", "dataset"]
    assert flights[0].home == tuple(log.meta["home"])
    out = [process_flight(f) for f in flights]
    ref = out[0]
    assert [w.type for w in ref.windows] == ["gps", "rc"]
    for p in out[1:]:
        assert p.windows == ref.windows
        for t in ("GPS", "IMU", "RATE", "VIBE"):
            a, b = ref.features[t], p.features[t]
            assert a["label"].tolist() == b["label"].tolist()
            feats = [c for c in a.columns if c != "flight"]
            pd.testing.assert_frame_equal(a[feats], b[feats], check_dtype=False)


def test_folder_of_inputs_is_expanded_and_ids_made_unique(tmp_path):
    log = _fault_flight()
    for d in ("runs/a/flight", "runs/b/flight"):
        log.write(tmp_path / d, formats=("parquet",))
    found = expand_inputs([tmp_path / "runs" / "a", tmp_path / "runs" / "b"])
    assert [k for k, _ in found] == ["tlm", "tlm"]
    flights = read_flights([tmp_path / "runs" / "a", tmp_path / "runs" / "b"])
    assert [f.id for f in flights] == ["flight", "flight-2"]
    seen: dict[str, int] = {}
    assert [f.id for f in unique_ids(read_flights([tmp_path / "runs/a"]), seen)] == ["flight"]
    assert [f.id for f in unique_ids(read_flights([tmp_path / "runs/b"]), seen)] == ["flight-2"]


def test_bad_inputs_fail_clearly(tmp_path):
    with pytest.raises(IngestError, match="no such file or folder"):
        read_flights([tmp_path / "missing"])
    (tmp_path / "x.bin").write_bytes(b"\xa3\x95")
    with pytest.raises(IngestError, match="cannot read the DataFlash log"):
        read_flights([tmp_path / "x.bin"])
    (tmp_path / "notes.txt").write_text("hi")
    with pytest.raises(IngestError, match="not a .bin log, a flight folder or a dataset"):
        read_flights([tmp_path / "notes.txt"])
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(IngestError, match="no flights found"):
        read_flights([empty])
    csv = tmp_path / "csv"
    csv.mkdir()
    (csv / "GPS.csv").write_text("TimeUS,Status,Lat,Lng,Alt\n1,6,-35,149,500\n")
    with pytest.raises(IngestError, match="no faults.json"):
        read_flights([csv])
    (csv / "faults.json").write_text("{not json")
    with pytest.raises(IngestError, match="invalid JSON"):
        read_flights([csv])
    (csv / "faults.json").write_text('{"faults": []}')
    (csv / "GPS.csv").write_text("Time,Status\n1,6\n")
    with pytest.raises(IngestError, match="no TimeUS column"):
        read_flights([csv])
    done = tmp_path / "done"
    done.mkdir()
    (done / "report.json").write_text('{"format": "tlm.process"}')
    with pytest.raises(IngestError, match="is a 'tlm process' output"):
        read_flights([done])


def test_reference_bin_with_sidecar():
    from conftest import reference_path

    src = reference_path("rc_s15.bin")
    f = read_flights([src])[0]
    assert f.id == "rc_s15" and f.kind == "bin"
    assert f.home == (-35.363261, 149.16523, 584.0)
    assert {"GPS", "IMU", "RATE", "VIBE", "POS", "EV"} <= set(f.tables)
    assert [(r.type, r.start_time_us, r.end_time_us) for r in f.records] == [
        ("rc", 134137157, 163894416)]


def test_bin_copy_without_sidecar_reads_its_faults_from_parm(tmp_path):
    """Without a sidecar, a SITL log's fault records come from its SIM_* parameter changes:
    the same types and times as the sidecar's."""
    from conftest import reference_path

    src = reference_path("rc_s15.bin")
    dst = tmp_path / "copy.bin"
    shutil.copy(src, dst)
    own = read_flights([dst])[0].records
    shutil.copy(src.with_suffix(".json"), tmp_path / "copy.json")
    side = read_flights([dst])[0].records
    assert [r.type for r in own] == [r.type for r in side] == ["rc"]
    assert abs(own[0].start_time_us - side[0].start_time_us) < 1000
    assert read_flights([dst])[0].id == "copy"
