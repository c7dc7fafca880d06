"""Lazy package exports: names are imported from their submodule on first use.

The ``tlm`` command line imports each subcommand's module to build ``--help``; a package whose
``__init__`` imported pandas, numba or tlm_sim eagerly would make ``tlm --help`` take seconds.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any


def lazy_exports(package: str, exports: Mapping[str, str], namespace: dict[str, Any]
                 ) -> tuple[list[str], Callable[[str], Any], Callable[[], list[str]]]:
    """``(__all__, __getattr__, __dir__)`` for ``package``.

    Args:
        package: the package's ``__name__``.
        exports: submodule name → space-separated names it provides.
        namespace: the package's ``globals()`` (a loaded name is cached there).
    """
    where = {name: mod for mod, names in exports.items() for name in names.split()}

    def getattr_(name: str) -> Any:
        mod = where.get(name)
        if mod is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{mod}"), name)
        namespace[name] = value
        return value

    def dir_() -> list[str]:
        return sorted(set(namespace) | set(where))

    return sorted(where), getattr_, dir_
