"""Former home of ``tlm evaluate``'s command, kept so that old imports keep working: it is
:mod:`tlm_process.commands.evaluate`."""

from tlm_process.commands.evaluate import MODEL_NAMES, TABLE_NAMES, add_parser, run

__all__ = ["MODEL_NAMES", "TABLE_NAMES", "add_parser", "run"]
