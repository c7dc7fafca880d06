"""Monte Carlo generation of labelled fault data sets (``tlm generate``). See
``docs/generate.md``.

Typical use::

    from tlm_process.generate import (GenerateOptions, generate, read_dataset_table,
                                      scenario_from_manifest)

    report = generate(GenerateOptions(out=Path("ds"), flights=1000, seed=1))
    print("\\n".join(report.lines()))
    gps = read_dataset_table("ds", "GPS")         # every flight, column 'flight'
    spec = scenario_from_manifest("ds", 123)
    tlm_sim.fly(*spec[:5], sticks=spec.sticks)   # flight 123 again, same tables

Names are imported lazily (``tlm_process._lazy``) so that ``tlm --help`` stays fast.
"""

from __future__ import annotations

from tlm_process._lazy import lazy_exports

_EXPORTS: dict[str, str] = {
    "errors": "GenerateError",
    "executors": "open_executor",
    "manifest": "read_header read_journal scenario_from_manifest",
    "reader": "DatasetIndex index_dataset read_dataset_table",
    "runner": "GenerateOptions GenerateReport generate",
    "scenario": "FlightSpec Scenario ScenarioConfig mission_from_recipe sample_scenario",
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
