"""Former home of ``tlm process``'s command, kept so that old imports keep working: it is
:mod:`tlm_process.commands.process`."""

from tlm_process.commands.process import add_parser, report_user_errors, run

__all__ = ["add_parser", "report_user_errors", "run"]
