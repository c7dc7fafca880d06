"""Former home of ``tlm generate``'s command, kept so that old imports keep working: it is
:mod:`tlm_process.commands.generate`."""

from tlm_process.commands.generate import add_parser, build_config, run

__all__ = ["add_parser", "build_config", "run"]
