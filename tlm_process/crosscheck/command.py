"""Former home of ``tlm crosscheck``, kept so that old imports keep working: the cross-check is
:mod:`tlm_process.crosscheck.compare`, the command :mod:`tlm_process.commands.crosscheck`."""

from tlm_process.commands.crosscheck import add_parser, run
from tlm_process.crosscheck.compare import crosscheck, format_report, gate, plot, to_json

__all__ = ["add_parser", "crosscheck", "format_report", "gate", "plot", "run", "to_json"]
