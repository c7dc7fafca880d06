"""The Time Line Modeling pipeline (paper §4-5): ingest, fault window anchoring (Eq. 4),
feature processing (Algorithm 2), window stretching (Eq. 5), min-max scaling (Eq. 6), plots
(the ``tlm process`` command is :mod:`tlm_process.commands.process`). See ``docs/pipeline.md``.

Typical use::

    from tlm_process.pipeline import read_flights, process_flight, build_dataset

    flights = read_flights(["combined_s21.bin", "out/flight1"])
    processed = [process_flight(f) for f in flights]
    ds = build_dataset(processed, test_patterns=["combined_*"])
    ds.tables["GPS"]          # flight, split, TimeUS, label + scaled features

Names are imported lazily (on first use), so that importing a submodule (the ``tlm``
command line does for ``--help``) does not pull in pandas and tlm_sim.
"""

from __future__ import annotations

from tlm_process._lazy import lazy_exports

_EXPORTS: dict[str, str] = {
    "anchoring": "AnchorComparison FaultWindow anchor_by_position anchor_by_time anchor_flight "
                 "compare_methods label_tables",
    "dataset": "Dataset ProcessedFlight ProcessOptions",
    "errors": "AnchorError IngestError PipelineError",
    "features": "DROP feature_table merge_tables",
    "ingest": "FaultRecord Flight parse_records read_flights",
    "process": "build_dataset process_flight write_dataset",
    "scaling": "MinMaxScaler split_flights",
    "stretching": "PAPER_TABLE_7 PAPER_TABLE_8 class_counts fault_share format_counts "
                  "implied_lambda lambda_for_target stretch_schedule target_for_lambda",
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
