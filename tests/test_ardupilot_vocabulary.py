"""ArduPilot's vocabulary is declared once, in :mod:`tlm_sim.ardupilot` (issue 39): no other
module declares an ERR/EV/mode/reason/MAV_CMD code or a physical constant of its own, and no
code compares a log's code column with a bare number. Checked on the source (ast)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest
from pymavlink import mavutil

from tlm_sim import ardupilot as AP

ROOT = Path(__file__).resolve().parents[1]
HOME = ROOT / "tlm_sim" / "ardupilot.py"
#: the vocabulary's name families: a module-level constant of one of these names outside
#: tlm_sim/ardupilot.py is a second declaration
PREFIXES = ("ERR_", "EV_", "MODE_", "RSN_", "MAV_CMD_", "MAV_FRAME_", "ARM_METHOD_", "LDET_",
            "EKF_EVT_", "CHK_", "KIND_", "TXT_")
#: declarations those prefixes match that are not ArduPilot codes (layout slots, tlm's names)
NOT_CODES = {"MODE_NEEDS_GPS", "LDET_LOG_MS", "LDET_MAX_HZ", "TXT_N"}
#: log columns whose values are codes of the vocabulary
CODE_COLUMNS = {"Id", "Subsys", "ECode", "ModeNum", "Mode", "Rsn", "CId", "Method"}
#: functions whose arguments are codes
CODE_CALLS = {"log_err", "log_ev", "log_mode", "set_mode", "err_count", "first_err",
              "mode_kept"}
#: floats that are physical constants of the vocabulary
CONSTANTS = {AP.GRAVITY_MSS, AP.M_PER_DEG_LAT, 111319.49, 111318.845}


def _sources() -> list[Path]:
    out = []
    for pkg in ("tlm_sim", "tlm_process", "tools", "benchmarks"):
        out += sorted((ROOT / pkg).rglob("*.py"))
    return [p for p in out if p != HOME]


def _is_number(node: ast.AST) -> bool:
    return (isinstance(node, ast.Constant) and type(node.value) in (int, float)
            and not isinstance(node.value, bool))


def _name(node: ast.AST) -> str:
    if isinstance(node, ast.Attribute):
        return node.attr
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant):
        return str(node.slice.value)
    return ""


def _declarations(tree: ast.Module) -> list[tuple[int, str]]:
    """(line, name) of module-level constants named like a vocabulary family."""
    out = []
    for node in tree.body:
        if not isinstance(node, ast.Assign | ast.AnnAssign):
            continue
        targets = node.targets if isinstance(node, ast.Assign) else [node.target]
        names: list[str] = []
        for t in targets:
            elts = t.elts if isinstance(t, ast.Tuple) else [t]
            names += [e.id for e in elts if isinstance(e, ast.Name)]
        value = node.value
        numeric = value is not None and (
            _is_number(value) or (isinstance(value, ast.Tuple)
                                  and all(_is_number(e) for e in value.elts)))
        for n in names:
            if numeric and n.startswith(PREFIXES) and n not in NOT_CODES:
                out.append((node.lineno, n))
    return out


def _stray(tree: ast.Module) -> list[tuple[int, str]]:
    """(line, what) of code literals: a code column compared with a number, a number passed
    to a function that takes codes, a physical constant written out."""
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            if any(_name(s) in CODE_COLUMNS for s in sides) and any(
                    _is_number(s) and s.value not in (0, -1) for s in sides):
                out.append((node.lineno, "code column compared with a number"))
        elif isinstance(node, ast.Call) and _name(node.func) in CODE_CALLS:
            if any(_is_number(a) and a.value > 0 for a in node.args[1:]):
                out.append((node.lineno, f"{_name(node.func)} with a literal code"))
        elif isinstance(node, ast.Constant) and type(node.value) is float:
            if node.value in CONSTANTS:
                out.append((node.lineno, f"constant {node.value} written out"))
    return out


def _findings(check) -> list[str]:
    """``file:line what`` of every finding of ``check(tree)`` over the checked sources."""
    out = []
    for path in _sources():
        rel = path.relative_to(ROOT).as_posix()
        out += [f"{rel}:{line} {what}" for line, what in check(ast.parse(
            path.read_text(encoding="utf-8")))]
    return out


def test_the_vocabulary_is_declared_once():
    bad = _findings(_declarations)
    assert not bad, "ArduPilot codes declared outside tlm_sim/ardupilot.py: " + ", ".join(bad)


def test_no_code_is_written_as_a_bare_number():
    bad = _findings(_stray)
    assert not bad, "literal ArduPilot codes: " + ", ".join(bad)


@pytest.mark.parametrize("src, found", [
    ("ERR_GPS = 11\n", True),
    ("EV_ARMED, EV_DISARMED = 10, 11\n", True),
    ("MODE_NEEDS_GPS = (3, 4)\n", False),
    ("x = ev[ev.Id == 10]\n", True),
    ("x = err[err.Subsys == AP.ERR_GPS]\n", False),
    ("log_err(ev, t, 24, 1)\n", True),
    ("g = 9.80665\n", True),
])
def test_the_checks_find_what_they_look_for(src, found):
    tree = ast.parse(src)
    assert bool(_declarations(tree) or _stray(tree)) == found


def test_mode_names_are_pymavlinks():
    assert AP.MODE_NAMES == dict(mavutil.mode_mapping_acm)
    for name in ("STABILIZE", "ALT_HOLD", "AUTO", "GUIDED", "LOITER", "RTL", "LAND", "POSHOLD"):
        assert AP.MODE_NAMES[getattr(AP, f"MODE_{name}")] == name


def test_name_tables_cover_their_codes():
    for prefix, table, skip in (("EV_", AP.EV_NAMES, ()),
                                ("ERR_", AP.ERR_SUBSYSTEM_NAMES, ("ERR_CODE_",))):
        codes = {v for k, v in vars(AP).items() if k.startswith(prefix)
                 and not k.startswith(skip) and isinstance(v, int)}
        assert codes == set(table)
    bits = [v for k, v in vars(AP).items() if k.startswith("F_") and isinstance(v, int)]
    assert sorted(bits) == [1 << k for k in range(AP.N_FAIL_BITS)]
