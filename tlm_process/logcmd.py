"""Former home of ``tlm convert`` and ``tlm info``, kept so that old imports keep working: the
log functions are in :mod:`tlm_process.binlog`, the commands in :mod:`tlm_process.commands`."""

from tlm_process.binlog import CONVERT_FORMATS, LogError, convert, format_info, log_info

__all__ = ["CONVERT_FORMATS", "LogError", "convert", "format_info", "log_info"]
