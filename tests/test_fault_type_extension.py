"""A new fault type is one record: this file defines one (``baro_offset``: both barometers read
too high, from ``SIM_BARO_GLITCH`` / ``SIM_BAR2_GLITCH``, which tlm models), registers it,
and flies, generates, labels and scores it without touching the package (the walk-through in
``docs/extending.md``, "A fault type"). The registry is restored after each test.

Measured (2026-12-06): a built-in mission with the 8 m offset from 60 to 90 s flies in ~1 s;
the logged baro reads 8.01 m above the truth in the window and the EKF's height 7.9 m above
it by the end (the copter sinks that much to hold its estimated height).
"""

from __future__ import annotations

import json
from collections.abc import Iterator, Mapping
from typing import Any

import numpy as np
import pandas as pd
import pytest

from tlm_process.fault_metrics import Flight
from tlm_process.fault_signatures import fault_signature, signature_types
from tlm_process.fault_types import (
    FaultTypeRecord,
    Knob,
    fault_type_record,
    register_fault_type,
    unregister_fault_type,
)
from tlm_process.reference import time_window
from tlm_sim.faults.types import FAULT_TYPES, FaultType

NAME = "baro_offset"
#: seconds before the fault over which the baseline is measured
BEFORE_S = 20.0


# --- the new fault type: everything tlm needs to know about it -----------------------------


def baro_offset_params(knobs: Mapping[str, Any], lat_deg: float) -> dict[str, float]:
    """One draw of the knobs -> the SITL parameters that start the fault."""
    return {"SIM_BARO_GLITCH": knobs["offset_m"], "SIM_BAR2_GLITCH": knobs["offset_m"]}


def _mean_error(rows: pd.DataFrame, values: np.ndarray, f: Flight) -> float:
    """Mean of ``values`` minus the true height above home at the rows' times [m]."""
    truth = np.interp(rows.TimeUS.to_numpy(float), f.sim_t, f.h)
    return float(np.mean(values - truth)) if len(rows) else float("nan")


def baro_offset_metrics(f: Flight, t0: float, t1: float, fault: Mapping[str, Any],
                        route: np.ndarray | None) -> dict[str, float]:
    """``baro_offset_m``: how much higher baro 1 reads than the truth from 2 s after the start
    to the end, against the 20 s before; ``ekf_height_offset_m``: the same for the primary
    EKF core's height (-XKF1.PD) over the last 5 s of the window."""
    baro = f.t["BARO"]
    baro = baro[baro.I == 0]
    xkf = f.t["XKF1"]
    xkf = xkf[xkf.C == 0]

    def baro_err(a: float, b: float) -> float:
        rows = time_window(baro, a, b)
        return _mean_error(rows, rows.Alt.to_numpy(float), f)

    def ekf_err(a: float, b: float) -> float:
        rows = time_window(xkf, a, b)
        return _mean_error(rows, -rows.PD.to_numpy(float), f)

    before = t0 - BEFORE_S * 1e6
    return {"baro_offset_m": baro_err(t0 + 2e6, t1) - baro_err(before, t0),
            "ekf_height_offset_m": ekf_err(t1 - 5e6, t1) - ekf_err(before, t0)}


def register_baro_offset() -> FaultTypeRecord:
    """The one call that adds the type (a plug-in module would make it at import)."""
    label = max(t.label for t in FAULT_TYPES.values()) + 1
    return register_fault_type(
        FaultType(NAME, label, {"SIM_BARO_GLITCH": 8.0, "SIM_BAR2_GLITCH": 8.0},
                  {"SIM_BARO_GLITCH": 0.0, "SIM_BAR2_GLITCH": 0.0},
                  "both barometers read 8 m too high (SIM_BARO_GLITCH, SIM_BAR2_GLITCH)",
                  title="Baro offset"),
        signature=baro_offset_metrics,
        knobs={"offset_m": Knob("range", (-50.0, 50.0), (6.0, 10.0))},
        params=baro_offset_params)


@pytest.fixture
def baro_offset() -> Iterator[FaultTypeRecord]:
    before = dict(FAULT_TYPES)
    record = register_baro_offset()
    try:
        yield record
    finally:
        unregister_fault_type(NAME)
    assert dict(FAULT_TYPES) == before and fault_type_record(NAME) is None


# --- tests ---------------------------------------------------------------------------------


def test_a_registered_type_is_known_everywhere(baro_offset):
    from tlm_process.generate.scenario import fault_preset, magnitude_knobs, new_types
    from tlm_process.labels import class_column, class_name, label_colour, long_name
    from tlm_process.pipeline.ingest import _record
    from tlm_sim.faults import FaultSchedule

    label = baro_offset.label
    assert label > 13 and list(FAULT_TYPES)[-1] == NAME and NAME in signature_types()
    assert class_name(label) == long_name(label) == NAME
    assert class_column(label) == "baro_offset Fail"
    colours = [label_colour(k) for k in range(40)]
    assert len(set(colours)) == 40  # no colour wraps round, registered or not
    assert _record({"label": label, "start_time_us": 1, "end_time_us": 2}, 0, "x").type == NAME
    assert NAME in new_types() and NAME in fault_preset("all")["fault_weights"]
    assert magnitude_knobs()[NAME]["offset_m"].default == (6.0, 10.0)
    fault = FaultSchedule.from_shorthand([f"{NAME}:60-90"]).faults[0]
    assert fault.label == label and dict(fault.params_start) == {"SIM_BARO_GLITCH": 8.0,
                                                                 "SIM_BAR2_GLITCH": 8.0}


def test_the_registry_refuses_clashes(baro_offset):
    ft = baro_offset.sim
    with pytest.raises(ValueError, match="already registered"):
        register_fault_type(ft, signature=baro_offset_metrics)
    with pytest.raises(ValueError, match="label 5 is 'gyro'"):
        register_fault_type(FaultType("other", 5, ft.params_start, ft.params_end, "x"),
                            signature=baro_offset_metrics)
    with pytest.raises(ValueError, match="exactly when it has knobs"):
        register_fault_type(FaultType("other", 99, ft.params_start, ft.params_end, "x"),
                            signature=baro_offset_metrics, knobs=baro_offset.knobs)
    with pytest.raises(ValueError, match="SIM_NO_SUCH"):
        register_fault_type(FaultType("other", 99, {"SIM_NO_SUCH": 1.0}, {"SIM_NO_SUCH": 0.0},
                                      "x"), signature=baro_offset_metrics)
    with pytest.raises(ValueError, match="built-in"):
        unregister_fault_type("gyro")
    assert "other" not in FAULT_TYPES


def test_worker_processes_are_refused_before_anything_is_written(baro_offset, tmp_path):
    """A process pool or a Dask cluster starts fresh interpreters that know the built-in
    types only: generate refuses them for a registered type, up front."""
    from tlm_process.generate import GenerateError, GenerateOptions, ScenarioConfig, generate

    cfg = ScenarioConfig(kinds={"single": 1.0}, fault_weights={NAME: 1.0})
    for kw in ({"executor": "process"}, {"executor": "auto", "workers": 8}, {"dask_local": 1}):
        with pytest.raises(GenerateError, match="registered in this process only"):
            generate(GenerateOptions(out=tmp_path / "ds", flights=1, config=cfg,
                                     progress=False, **kw))
    assert not (tmp_path / "ds").exists()


def test_fly_and_score(baro_offset):
    from tlm_sim import fly
    from tlm_sim.faults import FaultSchedule

    log = fly(1, faults=FaultSchedule.from_shorthand([f"{NAME}:60-90"]), seed=3)
    (rec,) = log.faults
    assert (rec["type"], rec["label"]) == (NAME, baro_offset.label)
    sig = fault_signature(log.tables, rec)
    assert sig["baro_offset_m"] == pytest.approx(8.0, abs=0.3)
    assert 6.0 < sig["ekf_height_offset_m"] < 9.0  # the EKF follows its baro


def test_generate_label_and_score(baro_offset, tmp_path):
    from tlm_process.generate import GenerateOptions, ScenarioConfig, generate
    from tlm_process.pipeline.ingest import read_dataset
    from tlm_process.pipeline.plots import plot_label_shares
    from tlm_process.pipeline.process import build_dataset, process_flight

    cfg = ScenarioConfig(kinds={"single": 1.0}, fault_weights={NAME: 1.0},
                         missions={"builtin": 1.0}, single_start_s=(20.0, 40.0),
                         hold_s=(20.0, 30.0), magnitudes={NAME: {"offset_m": (3.0, 5.0)}})
    ds = tmp_path / "ds"
    rep = generate(GenerateOptions(out=ds, flights=2, seed=7, config=cfg, executor="thread",
                                   workers=1, progress=False))
    assert (rep.ok, rep.failed) == (2, 0)
    faults = pd.read_parquet(ds / "faults.parquet")
    assert list(faults["type"]) == [NAME] * 2 and (faults["label"] == baro_offset.label).all()
    offsets = [json.loads(p)["SIM_BARO_GLITCH"] for p in faults["params_start"]]
    assert all(3.0 <= v <= 5.0 for v in offsets) and offsets[0] != offsets[1]

    flights, _ = read_dataset(ds, tables=("GPS", "IMU", "RATE", "VIBE", "EV", "MODE", "SIM",
                                          "BARO", "XKF1", "POS"))
    processed = [process_flight(f) for f in flights]
    data = build_dataset(processed, scale=False)
    assert "baro_offset Fail" in data.counts.columns
    assert plot_label_shares(data.counts, tmp_path / "shares.png").stat().st_size > 0
    for p, offset in zip(processed, offsets, strict=True):
        (w,) = p.windows
        assert (w.type, w.label) == (NAME, baro_offset.label)
        gps = p.labelled["GPS"]
        inside = (gps.TimeUS >= w.start_us) & (gps.TimeUS < w.end_us)
        assert (gps.label[inside] == baro_offset.label).all() and inside.sum() > 50
        assert (gps.label[~inside] == 0).all()
        r = p.flight.records[0]
        sig = fault_signature(p.flight.tables, {"type": r.type, "start_time_us": r.start_time_us,
                                                "end_time_us": r.end_time_us})
        assert sig["baro_offset_m"] == pytest.approx(offset, abs=0.3)
