"""The flight code's structure (issue 18 steps 3-5): subsystems read each other's output
blocks only, log rows are addressed by column name through one row appender, and no function
in tlm_sim or tlm_process is over 100 lines. Checked on the source (ast) and on the output
blocks' contents."""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest

from tests.test_structure_process import _modules, find_cycle, import_graph
from tlm_sim import logger as L
from tlm_sim.control import failsafe as FS
from tlm_sim.control.ahrs import ahrs_update
from tlm_sim.ekf import layout as EK
from tlm_sim.ekf.lanes import ekf_output, ekf_output_nav
from tlm_sim.flight import new_work
from tlm_sim.flightlog.schema import LOGGED_MESSAGES, SCHEMAS
from tlm_sim.sensors import layout as S

ROOT = Path(__file__).resolve().parents[1]
MAX_LINES = 100


def _sources(*packages: str) -> list[Path]:
    return sorted(p for pkg in packages for p in (ROOT / pkg).rglob("*.py"))


def _functions(path: Path) -> list[ast.FunctionDef | ast.AsyncFunctionDef]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return [n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef)]


def test_no_function_is_over_100_lines():
    long = []
    for path in _sources("tlm_sim", "tlm_process"):
        rel = path.relative_to(ROOT).as_posix()
        for fn in _functions(path):
            n = fn.end_lineno - fn.lineno + 1
            if n > MAX_LINES:
                long.append(f"{rel}:{fn.name} ({n} lines)")
    assert not long, "functions over 100 lines: " + ", ".join(long)


# ----------------------------------------------------------------------------- arguments

#: jitted functions with seven arguments (issue 39 asks for about six; none takes more than
#: seven): the number may only shrink
SEVEN = 40
#: the flight loop and its subsystem entry points take named bundles (tlm_sim/bundles.py)
BUNDLED = {"flight:run_flight": 6, "flight:_log_tick": 7, "flight:_estimate": 6,
           "flight:_ekf_inputs": 3, "flight:_read_sensors": 5, "flight:_physics_tick": 5,
           "flight:_boot": 4, "flight:_apply_schedule": 5, "control/modes:vehicle_step": 7,
           "ekf/lanes:ekf_update": 5, "ekf/gsf:gsf_update": 4, "control/dcm:dcm_update": 7,
           "control/arming:arming_step": 7}


def _jitted_arity() -> dict[str, int]:
    """``package/module:function`` -> argument count of every numba-compiled function."""
    out = {}
    for path in _sources("tlm_sim"):
        rel = path.relative_to(ROOT / "tlm_sim").with_suffix("").as_posix()
        for fn in _functions(path):
            if any("jit" in ast.unparse(d) for d in fn.decorator_list):
                out[f"{rel}:{fn.name}"] = len(fn.args.args)
    return out


def test_kernels_take_few_arguments():
    arity = _jitted_arity()
    assert len(arity) > 350
    for name, n in BUNDLED.items():
        assert arity[name] <= n, f"{name} takes {arity[name]} arguments"
    over = sorted(name for name, n in arity.items() if n > 7)
    assert not over, f"functions over seven arguments: {over}"
    assert sum(n == 7 for n in arity.values()) <= SEVEN


# ----------------------------------------------------------------------------- logging


def test_column_constants_follow_the_schema():
    assert L.TIME_US == 0
    for k, name in enumerate(L.LOG_ORDER):
        cols = getattr(L, f"{name}_COLS")
        assert cols._fields == SCHEMAS[name].columns
        assert list(cols) == [SCHEMAS[name].index(c) for c in SCHEMAS[name].columns]
        assert SCHEMAS[name].columns[L.TIME_US] == "TimeUS"
        assert getattr(L, f"K_{name}") == k
        assert {f"K_{name}", f"{name}_COLS"} <= set(L.__all__), name
    assert L.LOG_ORDER == LOGGED_MESSAGES  # a new message: its schema entry and its writer
    assert (L.K_EV, L.K_ERR) == (L.K_MODE + L.E_EV, L.K_MODE + L.E_ERR)
    # PSCN's names address PSCE and PSCD too (control.log writes all three with them)
    assert list(L.PSCN_COLS) == list(L.PSCE_COLS) == list(L.PSCD_COLS)


def _is_int(node: ast.AST) -> bool:
    return isinstance(node, ast.Constant) and type(node.value) is int


def _row_writes(path: Path) -> list[tuple[int, ast.AST]]:
    """(line, column expression) of every ``X[r, col] = ...`` / ``X[n, col] = ...``."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        targets = node.targets if isinstance(node, ast.Assign) else (
            [node.target] if isinstance(node, ast.AugAssign) else [])
        for t in targets:
            if (isinstance(t, ast.Subscript) and isinstance(t.slice, ast.Tuple)
                    and len(t.slice.elts) == 2 and isinstance(t.slice.elts[0], ast.Name)
                    and t.slice.elts[0].id in ("r", "n")):
                out.append((node.lineno, t.slice.elts[1]))
    return out


def test_log_rows_are_written_by_column_name():
    """No log column by number (``b[r, 9] = ...``): a column is a schema name (``GPS.Lat``),
    possibly plus an offset (``IMU.GyrX + k``)."""
    bad = []
    for path in _sources("tlm_sim"):
        for line, col in _row_writes(path):
            numeric = _is_int(col) or (isinstance(col, ast.BinOp) and _is_int(col.left))
            if numeric:
                bad.append(f"{path.relative_to(ROOT)}:{line}")
    assert not bad, "log columns by number at " + ", ".join(bad)


def test_one_row_appender():
    """Only logger.new_row advances a buffer's row count."""
    writers = []
    for path in _sources("tlm_sim"):
        for fn in _functions(path):
            for node in ast.walk(fn):
                targets = node.targets if isinstance(node, ast.Assign) else (
                    [node.target] if isinstance(node, ast.AugAssign) else [])
                if any(isinstance(t, ast.Subscript) and isinstance(t.value, ast.Name)
                       and t.value.id == "counts" for t in targets):
                    writers.append(f"{path.relative_to(ROOT).as_posix()}:{fn.name}")
    assert sorted(set(writers)) == ["tlm_sim/logger.py:new_row"]


def test_new_row_appends_until_the_buffer_is_full():
    bufs, counts = L.new_buffers(0.1)
    cap = bufs[L.K_EV].shape[0]
    rows = [L.new_row((bufs, counts), L.K_EV, t) for t in range(cap + 2)]
    assert rows[:cap] == list(range(cap)) and rows[cap:] == [-1, -1]
    assert counts[L.K_EV] == cap and bufs[L.K_EV][cap - 1, L.TIME_US] == cap - 1


# ----------------------------------------------------------------------------- output blocks


#: the subsystems, lowest first: a module may import its own package, a lower subsystem and
#: the foundation (every other tlm_sim module but the flight loop's), never a higher one
SUBSYSTEMS = ("dynamics", "sensors", "ekf", "control")
#: the loop that wires the subsystems together, and what compiles it: above all of them
WIRING = ("tlm_sim", "tlm_sim.flight", "tlm_sim.precompile")


def _rank(module: str) -> int:
    """0 for the foundation, 1.. for the subsystems in order, above them the wiring."""
    if module in WIRING:
        return len(SUBSYSTEMS) + 1
    part = module.split(".")[1]
    return SUBSYSTEMS.index(part) + 1 if part in SUBSYSTEMS else 0


def test_tlm_sim_has_no_import_cycle():
    graph = import_graph(package="tlm_sim")
    assert len(graph) > 80
    cycle = find_cycle(graph)
    assert cycle is None, "import cycle: " + " -> ".join(cycle)


def test_no_upward_arrow_in_tlm_sim():
    """Truth -> sensors -> EKF -> autopilot, one way (ARCHITECTURE.md's layers): no module
    imports a higher subsystem or the flight loop, and the foundation imports no subsystem."""
    graph = import_graph(package="tlm_sim")
    up = sorted(f"{m} -> {d}" for m, deps in graph.items() for d in deps
                if _rank(d) > _rank(m))
    assert not up, "upward imports: " + ", ".join(up)
    assert _rank("tlm_sim.ekf.lanes") > _rank("tlm_sim.sensors.imu") > _rank("tlm_sim.geo")


def _layout_modules() -> dict[str, Path]:
    """Every subsystem module that declares a Layout (the state and configuration arrays)."""
    mods = _modules(ROOT, "tlm_sim")
    return {m: p for m, p in mods.items() if _package(m) in SUBSYSTEMS
            and "= Layout(" in p.read_text(encoding="utf-8")}


def _layout_reads(path: Path, module: str, layouts: set[str]) -> dict[str, set[str]]:
    """Layout module -> the names a source file reads of it: ``from L import NAME``, and
    ``A.NAME`` where A is L imported as a module (``from pkg import layout as S``)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    alias: dict[str, str] = {}
    reads: dict[str, set[str]] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module:
            for a in node.names:
                if f"{node.module}.{a.name}" in layouts:
                    alias[a.asname or a.name] = f"{node.module}.{a.name}"
                elif node.module in layouts:
                    reads.setdefault(node.module, set()).add(a.name)
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name in layouts and a.asname:
                    alias[a.asname] = a.name
    for node in ast.walk(tree):
        if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                and node.value.id in alias):
            reads.setdefault(alias[node.value.id], set()).add(node.attr)
    reads.pop(module, None)
    return reads


def _package(module: str) -> str:
    return module.split(".")[1] if module.count(".") else module


def test_subsystems_read_each_other_only_through_published_blocks():
    """Every module of dynamics/, sensors/, ekf/ and control/ reads another package's layout
    only through the names that layout publishes (its ``PUBLISHED``: the EKF's output block,
    the sensors' output block, the truth the sensors sense); the lanes, filter states,
    configurations and noise streams stay their owner's."""
    import importlib

    layouts = _layout_modules()
    assert {"tlm_sim.ekf.layout", "tlm_sim.sensors.layout", "tlm_sim.dynamics.layout",
            "tlm_sim.control.layout"} <= set(layouts)
    bad, checked = [], 0
    for module, path in _modules(ROOT, "tlm_sim").items():
        if _package(module) not in SUBSYSTEMS:
            continue
        checked += 1
        for layout, names in _layout_reads(path, module, set(layouts)).items():
            if _package(layout) == _package(module):
                continue
            published = getattr(importlib.import_module(layout), "PUBLISHED", frozenset())
            inside = sorted(names - published)
            if inside:
                bad.append(f"{module} reads {layout}'s {inside}")
    assert checked > 40  # every module of the four packages
    assert not bad, "reads of another subsystem's internals: " + "; ".join(bad)


def _imported_from(tree: ast.Module, prefixes: tuple[str, ...]) -> set[str]:
    """Names a module's from-imports bind from modules under any of prefixes."""
    return {a.asname or a.name for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)
            and node.module and node.module.startswith(prefixes) for a in node.names}


def _mentions_truth(node: ast.AST) -> bool:
    """Whether an argument expression is, or indexes, the truth state (``x`` or ``state.x``)."""
    return any((isinstance(n, ast.Name) and n.id == "x")
               or (isinstance(n, ast.Attribute) and n.attr == "x") for n in ast.walk(node))


def test_estimator_and_autopilot_never_see_the_truth():
    """The EKF and the autopilot know the vehicle only through the sensors: no module of ekf/
    or control/ imports the truth-state layout, and the loop (flight.py) passes the truth
    state x only to dynamics, sensors and the simulator's own truth logs (SIM, SIM2), never to
    a function of ekf/ or control/ (PSCN.AN was once logged from the truth acceleration)."""
    truth = "tlm_sim.dynamics.layout"
    for module, path in _modules(ROOT, "tlm_sim").items():
        if _package(module) in ("tlm_sim.ekf", "tlm_sim.control"):
            assert truth not in _layout_reads(path, module, {truth}), module
    tree = ast.parse((ROOT / "tlm_sim" / "flight.py").read_text())
    guarded = _imported_from(tree, ("tlm_sim.ekf", "tlm_sim.control"))
    assert {"ahrs_update", "log_control_10hz", "ekf_update"} & guarded
    bad = [f"{node.func.id} (line {node.lineno})" for node in ast.walk(tree)
           if isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
           and node.func.id in guarded
           and any(_mentions_truth(a) for a in [*node.args, *(k.value for k in node.keywords)])]
    assert not bad, "truth state passed to the estimator or autopilot: " + ", ".join(bad)


@pytest.mark.parametrize("name", ["tlm_sim.ekf.layout", "tlm_sim.sensors.layout",
                                  "tlm_sim.dynamics.layout"])
def test_published_names_exist(name):
    import importlib

    mod = importlib.import_module(name)
    assert mod.PUBLISHED and all(isinstance(getattr(mod, n), int) for n in mod.PUBLISHED)


def test_the_published_rule_sees_a_read_of_internals(tmp_path):
    """The check above on a made-up module: a lane slot read through an alias and a from-import
    of a configuration slot are both found."""
    src = tmp_path / "m.py"
    src.write_text("from tlm_sim.ekf import layout as EK\n"
                   "from tlm_sim.sensors.layout import C_GPS_LAG_S, GE_PN\n"
                   "def f(e, eo):\n    return e[EK.HEALTHY] + eo[EK.O_PN]\n")
    reads = _layout_reads(src, "tlm_sim.control.m", set(_layout_modules()))
    assert reads["tlm_sim.ekf.layout"] == {"HEALTHY", "O_PN"}
    assert reads["tlm_sim.sensors.layout"] == {"C_GPS_LAG_S", "GE_PN"}


def _lanes(primary: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(3)
    ekf = rng.normal(size=(2, EK.N_EKF))
    sel = np.zeros(EK.N_SEL)
    sel[EK.SEL_PRIMARY] = primary
    sel[EK.SEL_N_LANES] = 2
    ekf[:, EK.IMU_INDEX] = (0.0, 1.0)
    ekf[:, EK.QW:EK.QW + 4] /= np.linalg.norm(ekf[:, EK.QW:EK.QW + 4], axis=1)[:, None]
    return ekf, sel


@pytest.mark.parametrize("primary", [0, 1])
def test_ekf_output_carries_what_the_autopilot_needs(primary):
    ekf, sel = _lanes(primary)
    ekf[:, EK.LIFE_EVENTS] = 0.0  # (published once: a second call would show none)
    out = np.full(EK.N_OUT, np.nan)
    ekf_output(ekf, sel, out)
    e = ekf[primary]
    assert out[EK.O_IMU] == primary
    assert list(out[EK.O_R00:EK.O_R22 + 1]) == list(e[EK.R00:EK.R22 + 1])
    for o, lane in ((EK.O_INNOV_VD, EK.INNOV_VD), (EK.O_INNOV_HGT, EK.INNOV_HGT),
                    (EK.O_VEL_TR, EK.VEL_TR), (EK.O_POS_TR, EK.POS_TR),
                    (EK.O_MAG_TR, EK.MAG_TR), (EK.O_BAD_IMU, EK.BAD_IMU),
                    (EK.O_PN, EK.PN), (EK.O_VD, EK.VD)):
        assert out[o] == e[lane]
    assert not np.isnan(out).any()
    nav = np.full(EK.N_OUT, np.nan)  # the per-tick part: everything the autopilot reads
    ekf_output_nav(ekf, sel, nav)
    filled = ~np.isnan(nav)
    assert (nav[filled] == out[filled]).all()
    # all but the Euler angles, square roots, counters and the records of absent lanes
    assert filled.sum() == EK.N_OUT - 10 - (EK.MAX_LANES - 2) * EK.LANE_STRIDE


@pytest.mark.parametrize("primary", [0, 1])
def test_ekf_output_carries_what_the_arming_checks_ask(primary):
    """The pre-arm checks read the EKF only through its output block: the primary lane's
    health, alignment, glitch flag and height test ratio, and one status record per lane whose
    lifecycle events are published once (the lanes forget them, the next call shows none)."""
    ekf, sel = _lanes(primary)
    ekf[:, EK.LIFE_EVENTS] = (5.0, 2.0)
    ekf[:, EK.MAG_IDX] = (2.0, 1.0)
    out = np.zeros(EK.N_OUT)
    ekf_output_nav(ekf, sel, out)
    e = ekf[primary]
    for o, lane in ((EK.O_HEALTHY, EK.HEALTHY), (EK.O_ALIGNED, EK.ALIGNED),
                    (EK.O_TILT_DONE, EK.TILT_DONE), (EK.O_YAW_DONE, EK.YAW_DONE),
                    (EK.O_GPS_GLITCHING, EK.GPS_GLITCHING), (EK.O_HGT_TR, EK.HGT_TR),
                    (EK.O_ORIGIN_OK, EK.ORIGIN_OK)):
        assert out[o] == e[lane]
    assert out[EK.O_N_LANES] == 2
    for i, events in enumerate((5.0, 2.0)):
        b = EK.O_LANES + i * EK.LANE_STRIDE
        assert out[b + EK.LS_HEALTHY] == ekf[i, EK.HEALTHY]
        assert out[b + EK.LS_ORIGIN_OK] == ekf[i, EK.ORIGIN_OK]
        assert out[b + EK.LS_IMU] == i and out[b + EK.LS_MAG] == ekf[i, EK.MAG_IDX]
        assert out[b + EK.LS_EVENTS] == events
    assert (ekf[:, EK.LIFE_EVENTS] == 0.0).all()
    ekf_output_nav(ekf, sel, out)
    assert out[EK.O_LANES + EK.LS_EVENTS] == out[EK.O_LANES + EK.LANE_STRIDE + EK.LS_EVENTS] == 0


@pytest.mark.parametrize("const_pos", [0.0, 1.0])
def test_ahrs_builds_the_controllers_inputs_from_the_output_block(const_pos):
    ekf, sel = _lanes(1)
    ekf[1, EK.F_CONST_POS] = const_pos
    ekf[1, EK.F_HORIZ_POS] = 1.0
    eo = np.zeros(EK.N_OUT)
    ekf_output(ekf, sel, eo)
    s = np.random.default_rng(4).normal(size=S.N_SENSOR_STATE)
    pos, vel, q, gyro, acc = (np.zeros(3), np.zeros(3), np.zeros(4), np.zeros(3), np.zeros(3))
    ahrs_update(eo, s, pos, vel, q, gyro, acc)
    e = ekf[1]
    ib = S.IMU_BASE + S.IMU_STRIDE  # lane 1 integrates IMU 1
    assert list(pos[:2]) == ([0.0, 0.0] if const_pos else list(e[EK.PN:EK.PN + 2]))
    assert pos[2] == e[EK.PD] and list(vel) == list(e[EK.VN:EK.VN + 3])
    assert list(q) == list(e[EK.QW:EK.QW + 4])
    assert gyro == pytest.approx(s[ib + S.I_GYR_F:ib + S.I_GYR_F + 3] - e[EK.BGX:EK.BGX + 3])
    r = e[EK.R00:EK.R22 + 1].reshape(3, 3)
    f = s[ib + S.I_ACC_F:ib + S.I_ACC_F + 3] - e[EK.BAX:EK.BAX + 3]
    assert acc == pytest.approx(r @ f + np.array([0.0, 0.0, 9.80665]))
    assert FS.ekf_position_ok(eo) == (not const_pos)
    assert eo[EK.O_VEL_TR] == e[EK.VEL_TR] and eo[EK.O_BAD_IMU] == e[EK.BAD_IMU]
    assert not math.isnan(eo[EK.O_INNOV_HGT])


def test_run_flight_work_rows_hold_a_gps_epoch_and_the_ekf_output():
    dang, dvel, rows, eo = new_work()
    assert rows.shape[1] >= S.N_GPS_EPOCH and eo.shape == (EK.N_OUT,)
    assert dang.shape == dvel.shape == (S.N_IMU, 3)


def test_sections_are_inlined_by_numba():
    """The named sections of the long flight functions are inline_jit (numba inline="always"):
    as separately compiled functions they made a cold compile ~35 % longer."""
    from tlm_sim import flight
    from tlm_sim.control import modes, wpnav

    for fn in (modes._navigate, modes._controllers, modes._crash_checks, wpnav._speed_step,
               flight._physics_tick, flight._log_tick):
        assert getattr(fn, "targetoptions", {}).get("inline") == "always", fn
