"""The layout of ``tlm_process``: no import cycles, one module per ``tlm`` subcommand.

What counts as an import (an edge of the graph): every ``import`` / ``from ... import``
statement anywhere in a module's code, read with ``ast`` - at module level, inside functions
and classes, and under ``if TYPE_CHECKING:``. A function-level (lazy) import keeps ``tlm
--help`` fast, which is allowed, but it only postpones a cycle, so it counts. A package's
``lazy_exports(...)`` table counts as the package importing those submodules. ``from P import
N`` is an edge to ``P.N`` when that is a module of tlm_process, else to ``P``; the packages
above an imported module (whose ``__init__`` Python runs first) are not counted, so a
package's ``__init__`` may export its own submodules.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = "tlm_process"

#: every ``tlm`` subcommand and the module that implements it
SUBCOMMANDS = ("fly", "demo", "convert", "info", "generate", "process", "evaluate", "train",
               "detect", "crosscheck", "fit", "params")


def _modules(root: Path = ROOT, package: str = PACKAGE) -> dict[str, Path]:
    """Dotted name -> file of every module of ``package`` (``__init__`` as the package)."""
    out = {}
    for f in sorted((root / package).rglob("*.py")):
        parts = list(f.relative_to(root).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = f
    return out


def _resolve(node: ast.ImportFrom, module: str, is_package: bool) -> str:
    """The absolute name of a ``from`` import's module (relative imports resolved)."""
    if not node.level:
        return node.module or ""
    base = module.split(".")
    base = base[: len(base) - node.level + (1 if is_package else 0)]
    return ".".join(base + ([node.module] if node.module else []))


def _imports(module: str, path: Path, known: set[str]) -> set[str]:
    """Modules of ``known`` that ``module`` imports (see the module docstring)."""
    is_package = path.name == "__init__.py"
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name in known)
        elif isinstance(node, ast.ImportFrom):
            base = _resolve(node, module, is_package)
            for a in node.names:
                if f"{base}.{a.name}" in known:
                    out.add(f"{base}.{a.name}")
                elif base in known:
                    out.add(base)
        elif (isinstance(node, ast.Call) and getattr(node.func, "id", None) == "lazy_exports"
              and len(node.args) > 1 and isinstance(node.args[1], ast.Name)):
            table = _assigned_dict(path, node.args[1].id)
            out.update(f"{module}.{sub}" for sub in table if f"{module}.{sub}" in known)
    out.discard(module)
    return out


def _assigned_dict(path: Path, name: str) -> list[str]:
    """String keys of the dict literal assigned to ``name`` at a module's top level."""
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        target = (node.targets[0] if isinstance(node, ast.Assign) else
                  node.target if isinstance(node, ast.AnnAssign) else None)
        if getattr(target, "id", None) == name and isinstance(node.value, ast.Dict):
            return [k.value for k in node.value.keys if isinstance(k, ast.Constant)]
    raise AssertionError(f"{path}: lazy_exports table {name} is not a dict literal")


def import_graph(root: Path = ROOT, package: str = PACKAGE) -> dict[str, set[str]]:
    """Module -> the modules of the package it imports."""
    mods = _modules(root, package)
    return {m: _imports(m, p, set(mods)) for m, p in mods.items()}


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle of ``graph`` as ``[a, b, ..., a]``, or None when it is acyclic."""
    state: dict[str, int] = {}  # 1 on the current path, 2 done
    path: list[str] = []

    def visit(m: str) -> list[str] | None:
        state[m] = 1
        path.append(m)
        for n in sorted(graph.get(m, ())):
            if state.get(n) == 1:
                return path[path.index(n):] + [n]
            if n not in state and (cycle := visit(n)):
                return cycle
        path.pop()
        state[m] = 2
        return None

    for m in sorted(graph):
        if m not in state and (cycle := visit(m)):
            return cycle
    return None


def test_find_cycle_sees_lazy_and_type_checking_imports(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text(
        "from pkg._lazy import lazy_exports\n_E = {'b': 'B'}\n"
        "__all__, __getattr__, __dir__ = lazy_exports(__name__, _E, globals())\n")
    (pkg / "_lazy.py").write_text("")
    (pkg / "a.py").write_text("def f():\n    from pkg.sub import b\n")
    (pkg / "sub" / "b.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from pkg import a\n")
    graph = import_graph(tmp_path, "pkg")
    assert graph["pkg.a"] == {"pkg.sub.b"} and graph["pkg.sub"] == {"pkg._lazy", "pkg.sub.b"}
    assert find_cycle(graph) == ["pkg.a", "pkg.sub.b", "pkg.a"]
    (pkg / "sub" / "b.py").write_text("from .. import _lazy\n")
    assert find_cycle(import_graph(tmp_path, "pkg")) is None


def test_tlm_process_has_no_import_cycle():
    graph = import_graph()
    assert len(graph) > 40
    cycle = find_cycle(graph)
    assert cycle is None, "import cycle: " + " -> ".join(cycle)


def test_every_subcommand_is_a_module_with_add_parser_and_run():
    from tlm_process import cli

    assert tuple(cli.COMMANDS) == SUBCOMMANDS
    for name, module in cli.COMMANDS.items():
        assert module == f"tlm_process.commands.{name}"
        mod = __import__(module, fromlist=["run"])
        assert callable(mod.add_parser) and callable(mod.run), module


def test_cli_only_routes():
    """cli.py builds the parser from the table and dispatches; no subcommand lives there."""
    tree = ast.parse((ROOT / PACKAGE / "cli.py").read_text(encoding="utf-8"))
    functions = {n.name for n in tree.body if isinstance(n, ast.FunctionDef)}
    assert functions == {"build_parser", "main", "_main_body", "command_module",
                         "_show_compile_notices"}, \
        functions


def test_shared_cli_module_is_a_leaf():
    graph = import_graph()
    assert graph["tlm_process.cliutil"] == set()
    users = {m for m, deps in graph.items() if "tlm_process.cliutil" in deps}
    assert {f"tlm_process.commands.{c}" for c in ("fly", "convert", "process", "evaluate",
                                                   "crosscheck")} <= users


def test_help_imports_no_heavy_module():
    """Building ``tlm``'s parser (what --help needs) imports neither pandas, numpy nor
    tlm_sim."""
    code = ("import sys; from tlm_process.cli import build_parser; build_parser(); "
            "print(sorted(m for m in ('pandas', 'numpy', 'tlm_sim', 'matplotlib') "
            "if m in sys.modules))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       cwd=ROOT, check=True)
    assert r.stdout.strip() == "[]"


def test_user_mistake_is_one_line_when_run_as_module(tmp_path):
    """``python -m tlm_process.cli``: a subcommand's UsageError is the one ``main`` catches
    (it was a second copy of the cli module's class when logcmd imported it from the CLI, and
    ``tlm convert --format zz`` ended in a traceback)."""
    log = tmp_path / "x.bin"
    log.write_bytes(b"")
    r = subprocess.run([sys.executable, "-m", "tlm_process.cli", "convert", str(log), "--out",
                        str(tmp_path / "out"), "--format", "zz"],
                       capture_output=True, text=True, cwd=ROOT)
    assert (r.returncode, r.stderr) == (
        2, "tlm: error: --format: 'zz'; choose one of csv, parquet, log\n")
