"""Read any ArduPilot log into normalised tables: DataFlash ``.bin`` files of every firmware
generation and the text ``.log`` files Mission Planner and old firmware write.

:func:`read_log_tables` gives one DataFrame per message type in the layout ArduCopter 4.x logs
(what tlm's simulator and the reference SITL logs use), whatever the log's age:

* **Time.** Every table gets ``TimeUS`` (int64, µs since boot). 4.x rows carry it. Copter
  3.x stamps rows with ``TimeMS`` (ms since boot): ``TimeUS = TimeMS * 1000`` and ``TimeMS``
  is kept. Copter 3.x's GPS row (columns ``TimeMS, Week, ..., T``) holds the GPS time of week
  in ``TimeMS`` and the boot time in ``T`` [ms]: ``TimeUS = T * 1000`` there. A message without
  any time column (FMT, PARM, MODE, EV, ERR, CMD of 3.x; ATT, CTUN, MOT of 3.1) takes the time
  of the last stamped message before it in the file (log order, as pymavlink does; rows before
  the first stamp take the first stamp).
* **Instances.** Numbered-instance messages are folded into the instance-column layout of 4.x:
  ``IMU2``/``IMU3`` become ``IMU`` rows with ``I`` = 1/2 (the ``IMU`` rows get ``I`` = 0 when
  they have no ``I``), likewise ``BAR2``/``BAR3`` → ``BARO``, ``MAG2``/``MAG3`` → ``MAG``,
  ``GPS2`` → ``GPS``, ``GPA2`` → ``GPA`` (``FOLDS``). Columns one instance lacks are NaN.
* **Units and names.** Copter 3.x's RATE outputs, rates and throttle, CTUN's ``ThrOut`` and
  MODE's ``Mode`` come in 4.x's units and names, and Copter 3.1's RCIN / RCOU channels
  ``Chan1``... as ``C1``... (``_as_4x``).
* Rows are sorted by ``TimeUS`` within a table (stable: log order and then instance at equal
  times), the index is a fresh RangeIndex, NaN values are kept, tables without rows dropped.

``LogTables.notes`` says, one line each, what was normalised and what could not be read
(damage the ``.bin`` reader skipped, text lines that are not messages).

:func:`arming_time_us` and :func:`disarm_time_us` find the armed phase of such tables, with
the rule that gave it (EV events, ARM messages, or the motor outputs of a log that starts
at arming).
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tlm_sim import ardupilot as AP

__all__ = [
    "FOLDS",
    "LogReadError",
    "LogTables",
    "arming_time_us",
    "disarm_time_us",
    "is_text_log",
    "log_end_us",
    "log_start_us",
    "motor_columns",
    "motor_idle_pwm",
    "pwm_range",
    "rates_in_centidegrees",
    "ARMING_DELAY_US",
    "read_log_tables",
    "warn_damage",
]

#: ArduCopter LogEvent ids (EV.Id) of arming and disarming.

#: Numbered-instance messages of older logs → (4.x message, its instance I).
FOLDS: dict[str, tuple[str, int]] = {
    "IMU2": ("IMU", 1), "IMU3": ("IMU", 2),
    "BAR2": ("BARO", 1), "BAR3": ("BARO", 2),
    "MAG2": ("MAG", 1), "MAG3": ("MAG", 2),
    "GPS2": ("GPS", 1),
    "GPA2": ("GPA", 1),
}
#: 4.x messages whose rows carry the instance column ``I`` (folded or not).
_INSTANCED = tuple(sorted({base for base, _ in FOLDS.values()}))
#: name prefix of the stamp-only tables of types not asked for (their times place the
#: messages that have no time column; never returned)
_HELPER = "\0"


class LogReadError(ValueError):
    """A log that cannot be read at all (not a DataFlash log, unreadable): one line naming
    the file."""


@dataclass
class LogTables:
    """A log read by :func:`read_log_tables`.

    Attributes:
        tables: message name → DataFrame (4.x names and layout; ``TimeUS`` in µs since boot
            on every table; rows sorted by it).
        params: parameter values at log start (the first PARM value of each name).
        notes: one line per thing normalised (TimeMS converted, instances folded, times taken
            from log order) or not read (damage skipped, lines that are not messages).
        path: the file read.
        kind: "bin" (DataFlash binary) or "text" (DataFlash text log).
    """

    tables: dict[str, pd.DataFrame]
    params: dict[str, float]
    notes: list[str] = field(default_factory=list)
    path: str = ""
    kind: str = "bin"


# --------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------

def is_text_log(path: str | os.PathLike) -> bool:
    """Whether ``path`` is a DataFlash *text* log: its first 64 KiB are text and hold an
    ``FMT, `` line (Mission Planner's ``.log`` export, or the ``.log`` of firmware that
    logged text)."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(65536)
    except OSError:
        return False
    if b"\x00" in head or b"\xa3\x95" in head:
        return False
    return re.search(rb"(^|\n)FMT, ", head) is not None


def _wanted_sources(names: list[str] | None) -> set[str] | None:
    """Raw message types to read for the normalised ``names`` (IMU → IMU, IMU2, IMU3)."""
    if names is None:
        return None
    want = set()
    for n in names:
        base = FOLDS.get(n, (n, 0))[0]
        want.add(base)
        want.update(k for k, (b, _) in FOLDS.items() if b == base)
    return want


def read_log_tables(path: str | os.PathLike, names: list[str] | tuple[str, ...] | None = None
                    ) -> LogTables:
    """Read an ArduPilot log (``.bin``, or a DataFlash text ``.log``) into normalised tables.

    Args:
        path: the log. A text log is recognised by its content (:func:`is_text_log`), so the
            suffix does not matter.
        names: normalised message names to return (``["IMU", "GPS"]``: ``IMU`` brings the
            log's ``IMU2``/``IMU3`` folded in; asking for ``IMU2`` means ``IMU``); None = every
            message type with rows.
    Returns:
        :class:`LogTables` (see the module docstring for the normalisation).
    Raises:
        FileNotFoundError: no such file.
        LogReadError: not a DataFlash log, or it cannot be read.
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(2, "no such log", str(p))
    wanted = None if names is None else list(dict.fromkeys(names))
    if is_text_log(p):
        raw, order, params, notes = _read_text(p, _wanted_sources(wanted))
        kind = "text"
    else:
        raw, order, params, notes = _read_binary(p, _wanted_sources(wanted))
        kind = "bin"
    tables = _normalise(raw, order, notes)
    if wanted is not None:
        keep = {FOLDS.get(n, (n, 0))[0] for n in wanted}
        tables = {n: df for n, df in tables.items() if n in keep}
    return LogTables(tables, params, notes, str(p), kind)


def warn_damage(lt: LogTables) -> None:
    """Re-issue the reader's damage notes (``damage: ...``: a cut-off or corrupt log) as the
    ``BinLogWarning``s ``read_bin`` gives, for the commands that print them as one
    ``tlm: warning:`` line (``tlm process``, ``tlm crosscheck``, ``tlm detect``); ``tlm info``
    lists them itself."""
    from tlm_sim.flightlog.binreader import BinLogWarning

    for n in lt.notes:
        if n.startswith("damage: "):
            warnings.warn(n.removeprefix("damage: "), BinLogWarning, stacklevel=2)


def _stamp(df: pd.DataFrame) -> tuple[np.ndarray | None, str | None]:
    """Boot time [µs] of each row of a raw table and the column it came from, or (None,
    None) for a message without a time column."""
    cols = df.columns
    if "TimeUS" in cols:
        return pd.to_numeric(df["TimeUS"], errors="coerce").to_numpy(np.float64), "TimeUS"
    if "TimeMS" in cols and "Week" in cols and "T" in cols:
        # Copter 3.x GPS: TimeMS is the GPS time of week, T the boot time [ms]
        return pd.to_numeric(df["T"], errors="coerce").to_numpy(np.float64) * 1000.0, "T"
    if "TimeMS" in cols:
        return pd.to_numeric(df["TimeMS"], errors="coerce").to_numpy(np.float64) * 1000.0, \
            "TimeMS"
    return None, None


def _order_times(stamps: list[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """(order keys, times) of every stamped message, sorted by order, NaN times left out."""
    if not stamps:
        return np.zeros(0, np.int64), np.zeros(0)
    order = np.concatenate([o for o, _ in stamps]).astype(np.int64)
    times = np.concatenate([t for _, t in stamps]).astype(np.float64)
    ok = np.isfinite(times)
    order, times = order[ok], times[ok]
    k = np.argsort(order, kind="stable")
    return order[k], times[k]


def _times_from_order(at: np.ndarray, order: np.ndarray, times: np.ndarray) -> np.ndarray:
    """Time of the last stamped message before each position ``at`` (the first stamp for
    positions before it; 0 when the log has no stamps at all)."""
    if not len(times):
        return np.zeros(len(at))
    k = np.searchsorted(order, at, side="left") - 1
    return times[np.clip(k, 0, None)]


def _stamp_all(raw: dict[str, pd.DataFrame], order: dict[str, np.ndarray],
               notes: list[str]) -> dict[str, np.ndarray]:
    """Boot time [µs] of every row of every raw table (see the module docstring)."""
    stamped: dict[str, np.ndarray] = {}
    how: dict[str, list[str]] = {"TimeMS": [], "T": [], "order": []}
    unstamped = []
    stamps = []
    for name, df in raw.items():
        t, col = _stamp(df)
        if t is None:
            unstamped.append(name)
            continue
        stamped[name] = t
        if col != "TimeUS" and not name.startswith(_HELPER):
            how[col].append(name)
        if name in order:
            stamps.append((order[name], t))
    late = 0
    if unstamped:
        o, t = _order_times(stamps)
        for name in unstamped:
            at = order.get(name, np.zeros(len(raw[name]), np.int64))
            stamped[name] = _times_from_order(at, o, t)
            if len(raw[name]) and not name.startswith(_HELPER):
                how["order"].append(name)
                late += int((at > o[-1]).sum()) if len(o) else 0
    if how["TimeMS"]:
        notes.append(f"TimeUS = TimeMS x 1000 (rows stamped in ms): {', '.join(how['TimeMS'])}")
    if how["T"]:
        notes.append(f"TimeUS = T x 1000 (Copter 3.x GPS: TimeMS is the GPS time of week, T "
                     f"the boot time in ms): {', '.join(how['T'])}")
    if how["order"]:
        notes.append("TimeUS from the last stamped message before each row (log order; the "
                     f"message has no time column): {', '.join(how['order'])}")
    if late:
        notes.append(f"{late} row(s) without a time column come after the last stamped "
                     "message: their time is not known (they take the last stamp)")
    return stamped


def _fold(out: dict[str, pd.DataFrame], notes: list[str]) -> None:
    """Fold numbered instances into their 4.x message (``FOLDS``), in place."""
    folded: dict[str, list[str]] = {}
    for src, (base, inst) in FOLDS.items():
        if src not in out:
            continue
        df = out.pop(src)
        if "I" not in df.columns:
            df.insert(1, "I", np.full(len(df), inst, dtype=np.int64))
        folded.setdefault(base, []).append(src)
        out[base] = df if base not in out else _concat(out[base], df)
    for base in _INSTANCED:
        df = out.get(base)
        if df is not None and "I" not in df.columns:
            df = df.copy()
            df.insert(1, "I", np.zeros(len(df), dtype=np.int64))
            out[base] = df
    for base, srcs in folded.items():
        notes.append(f"{', '.join(srcs)} folded into {base} as instances I = "
                     f"{', '.join(str(FOLDS[s][1]) for s in srcs)} ({base}'s own rows: I = 0)")


def _normalise(raw: dict[str, pd.DataFrame], order: dict[str, np.ndarray],
               notes: list[str]) -> dict[str, pd.DataFrame]:
    """TimeUS on every table, instances folded, rows sorted, empty tables dropped."""
    stamped = _stamp_all(raw, order, notes)
    out: dict[str, pd.DataFrame] = {}
    for name, df in raw.items():
        if not len(df) or name.startswith(_HELPER):
            continue
        t = _as_time(stamped[name])
        if "TimeUS" in df.columns:
            df = df.copy()
            df["TimeUS"] = t
        else:
            df.insert(0, "TimeUS", t)
        out[name] = df
    _fold(out, notes)
    for name, df in out.items():
        t = df["TimeUS"].to_numpy()
        if len(t) > 1 and (np.diff(t) < 0).any():
            df = df.iloc[np.argsort(t, kind="stable")]
        out[name] = df.reset_index(drop=True)
    _as_4x(out, notes)
    return out


#: Copter 3.x's rate-controller output range (RATE ROut/POut/YOut; 4.x logs them in +-1) and
#: throttle range (RATE AOut, CTUN ThrOut; 4.x: 0..1)
COPTER3_OUTPUT = 4500.0
COPTER3_THROTTLE = 1000.0
#: RATE-per-gyro regression slope above which RATE's rates are in centidegrees per second
#: (between the slopes of 1 and 100 the two units give, on a log scale)
CENTI_SLOPE = 10.0


def _as_4x(tables: dict[str, pd.DataFrame], notes: list[str]) -> None:
    """Copter 3.x's RATE, CTUN and MODE as 4.x logs them: rate outputs from +-4500 to +-1 and
    the throttle from 0..1000 to 0..1 (an AOut above 1.5 tells), the rates from centidegrees
    to degrees per second (RATE's roll rate 100 times IMU 0's gyro), CTUN's ThrOut as ThO,
    MODE's mode number as ModeNum where only Mode has it, Copter 3.1's RCIN and RCOU channels
    ``Chan1``... as ``C1``..."""
    for name in ("RCIN", "RCOU"):
        df = tables.get(name)
        chans = {} if df is None else {c: "C" + c[4:] for c in df.columns
                                        if re.fullmatch(r"Chan\d+", c) and "C" + c[4:] not in df}
        if chans:
            tables[name] = df.rename(columns=chans)
            notes.append(f"{name} Chan1... as C1... (Copter 3.1's channel names)")
    mode = tables.get("MODE")
    if mode is not None and "ModeNum" not in mode and "Mode" in mode:
        tables["MODE"] = mode.assign(ModeNum=pd.to_numeric(mode["Mode"], errors="coerce"))
        notes.append("MODE ModeNum = Mode (an old firmware's mode number)")
    rate = tables.get("RATE")
    if rate is not None and "AOut" in rate and np.nanmax(
            pd.to_numeric(rate["AOut"], errors="coerce").to_numpy(float), initial=0.0) > 1.5:
        rate = rate.copy()
        for col in ("ROut", "POut", "YOut"):
            if col in rate:
                rate[col] = pd.to_numeric(rate[col], errors="coerce") / COPTER3_OUTPUT
        rate["AOut"] = pd.to_numeric(rate["AOut"], errors="coerce") / COPTER3_THROTTLE
        tables["RATE"] = rate
        notes.append("RATE ROut/POut/YOut / 4500 and AOut / 1000 (Copter 3.x output units)")
    if rate is not None and rates_in_centidegrees(rate, tables.get("IMU")):
        rate = tables["RATE"].copy()
        cols = [c for c in ("RDes", "R", "PDes", "P", "YDes", "Y") if c in rate]
        for col in cols:
            rate[col] = pd.to_numeric(rate[col], errors="coerce") * 0.01
        tables["RATE"] = rate
        notes.append(f"RATE {'/'.join(cols)} x 0.01 (Copter 3.x: centidegrees per second)")
    ctun = tables.get("CTUN")
    if ctun is not None and "ThrOut" in ctun and "ThO" not in ctun:
        ctun = ctun.copy()
        ctun["ThO"] = pd.to_numeric(ctun["ThrOut"], errors="coerce") / COPTER3_THROTTLE
        tables["CTUN"] = ctun
        notes.append("CTUN ThO = ThrOut / 1000 (Copter 3.x)")


def rates_in_centidegrees(rate: pd.DataFrame, imu: pd.DataFrame | None) -> bool:
    """Whether RATE's rates are in centidegrees per second (Copter 3.x): its roll rate R
    against IMU 0's roll gyro, a regression over the whole log, steeper than
    :data:`CENTI_SLOPE`; False when either is missing."""
    if imu is None or len(rate) < 10 or len(imu) < 10 or "R" not in rate or "GyrX" not in imu:
        return False
    if "I" in imu:
        imu = imu[imu["I"] == 0]
    g = np.degrees(np.interp(rate.TimeUS.to_numpy(float), imu.TimeUS.to_numpy(float),
                             pd.to_numeric(imu.GyrX, errors="coerce").to_numpy(float)))
    r = pd.to_numeric(rate.R, errors="coerce").to_numpy(float)
    ok = np.isfinite(g) & np.isfinite(r)
    if ok.sum() < 10 or not np.any(g[ok]):
        return False
    return abs(float(np.dot(r[ok], g[ok]) / max(np.dot(g[ok], g[ok]), 1e-12))) > CENTI_SLOPE


def _as_time(t: np.ndarray) -> np.ndarray:
    """µs as int64 (a NaN stamp, from a damaged row, takes 0)."""
    return np.where(np.isfinite(t), np.round(t), 0).astype(np.int64)


def _concat(a: pd.DataFrame, b: pd.DataFrame) -> pd.DataFrame:
    """Rows of ``a`` then ``b`` (instance tables of one message); columns of ``a`` first."""
    if "I" not in a.columns:
        a = a.copy()
        a.insert(1, "I", np.zeros(len(a), dtype=np.int64))
    df = pd.concat([a, b], ignore_index=True, sort=False)
    return df.sort_values("TimeUS", kind="stable").reset_index(drop=True)


def _params(parm: pd.DataFrame | None) -> dict[str, float]:
    if parm is None or not len(parm) or not {"Name", "Value"} <= set(parm.columns):
        return {}
    first = parm.drop_duplicates("Name", keep="first")
    out = {}
    for n, v in zip(first["Name"], first["Value"], strict=True):
        try:
            out[str(n)] = float(v)
        except (TypeError, ValueError):
            continue
    return out


# --- binary ----------------------------------------------------------------------------------

def _read_binary(p: Path, want: set[str] | None
                 ) -> tuple[dict[str, pd.DataFrame], dict[str, np.ndarray], dict[str, float],
                            list[str]]:
    """Raw tables of a ``.bin`` (tlm_sim.flightlog.binreader), the byte offset of every row,
    the parameters and the reader's damage notes."""
    from tlm_sim.flightlog.binreader import (
        BinLogWarning,
        _decode_index,
        _index,
        _present,
        _raw_column,
    )

    notes: list[str] = []
    try:
        with warnings.catch_warnings(record=True) as caught, \
                contextlib.redirect_stdout(io.StringIO()):
            warnings.simplefilter("always", BinLogWarning)
            ix = _index(p)
    except ValueError as e:  # BinLogError names the file
        raise LogReadError(str(e)) from None
    except OSError as e:
        raise LogReadError(f"{p}: cannot read: {e.strerror or e}") from None
    for w in caught:
        if issubclass(w.category, BinLogWarning):
            notes.append(f"damage: {w.message}")
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    present = _present(ix)
    if not present:
        raise LogReadError(f"{p}: not an ArduPilot DataFlash log (no messages found)")
    names = [n for n in present if want is None or n in want or n == "PARM"]
    raw: dict[str, pd.DataFrame] = {}
    order: dict[str, np.ndarray] = {}
    with np.errstate(invalid="ignore", over="ignore"):
        for n in names:
            f = ix.by_name[n]
            raw[n] = _decode_index(ix, f)
            order[n] = np.asarray(ix.offsets[f.type], dtype=np.int64)
        params = _params(raw.get("PARM"))
        if want is not None and "PARM" not in want:
            raw.pop("PARM", None)
            order.pop("PARM", None)
        # stamps of the types not decoded, for the messages that take their time from log order
        if want is not None and any(_stamp(df)[0] is None for df in raw.values()):
            for n in present:
                if n in raw:
                    continue
                f = ix.by_name[n]
                for col in ("TimeUS", "TimeMS"):
                    v = _raw_column(ix, n, col)
                    if v is not None and v.dtype.kind in "iu":
                        t = v.astype(np.float64) * (1.0 if col == "TimeUS" else 1000.0)
                        if col == "TimeMS" and {"Week", "T"} <= set(f.columns):
                            t = _raw_column(ix, n, "T").astype(np.float64) * 1000.0
                        raw[_HELPER + n] = pd.DataFrame({"TimeUS": t})
                        order[_HELPER + n] = np.asarray(ix.offsets[f.type], dtype=np.int64)
                        break
    return raw, order, params, notes


# --- text ------------------------------------------------------------------------------------

_INT_CHARS = set("bBhHiIqQM")
_SCALED = set("cCeEL")
_FLOAT = set("fdg")
_STR = set("nNZ")


def _mode_numbers() -> dict[str, int]:
    """Mode name (as a text log writes it: upper case, ``_`` for spaces) -> ModeNum."""
    return {v.upper().replace(" ", "_"): k for k, v in AP.MODE_NAMES.items()}


def _number(text: str) -> float:
    t = text.strip()
    if not t:
        return math.nan
    t = t.replace("∞", "inf")
    try:
        return float(t)
    except ValueError:
        return math.nan


def _text_column(values: list[str], char: str, modes: dict[str, int]) -> Any:
    if char in _STR or char == "a":
        return np.asarray([v.strip() for v in values], dtype=object)
    if char == "M":
        vals = [float(v) if v.strip().lstrip("-").isdigit()
                else modes.get(v.strip().upper().replace(" ", "_"), math.nan) for v in values]
        arr = np.asarray(vals, dtype=np.float64)
    else:
        arr = np.asarray([_number(v) for v in values], dtype=np.float64)
    if char in _INT_CHARS and np.isfinite(arr).all() and (arr == np.round(arr)).all():
        return arr.astype(np.int64)
    return arr


def _read_text(p: Path, want: set[str] | None
               ) -> tuple[dict[str, pd.DataFrame], dict[str, np.ndarray], dict[str, float],
                          list[str]]:
    """Raw tables of a DataFlash text log, the line number of every row, the parameters and
    notes on the lines that are not messages."""
    try:
        fh = open(p, encoding="utf-8", errors="replace", newline="")
    except OSError as e:
        raise LogReadError(f"{p}: cannot read: {e.strerror or e}") from None
    with fh:
        lines = _TextLines()
        for lineno, line in enumerate(fh, 1):
            lines.add(lineno, line.rstrip("\r\n"))
    if "FMT" not in lines.rows:
        raise LogReadError(f"{p}: not an ArduPilot DataFlash log (no FMT message)")
    raw, order = _text_tables(lines)
    params = _params(raw.get("PARM"))
    skipped = lines.skipped
    notes = [f"text log: {len(skipped)} line(s) that are not messages skipped (the first: "
             f"line {skipped[0][0]} {skipped[0][1][:40]!r})"] if skipped else []
    notes += [f"text log: {k} {n} line(s) with the wrong number of fields skipped"
              for n, k in lines.bad.items()]
    if want is not None:
        _keep_wanted(raw, order, want)
    return raw, order, params, notes


class _TextLines:
    """The lines of a DataFlash text log sorted by message: each message's formats (from its
    FMT line), its rows of fields and their line numbers, the lines that are no message and
    the count of lines per message with the wrong number of fields."""

    def __init__(self) -> None:
        self.formats: dict[str, tuple[str, list[str]]] = {}
        self.rows: dict[str, list[list[str]]] = {}
        self.lines_at: dict[str, list[int]] = {}
        self.skipped: list[tuple[int, str]] = []
        self.bad: dict[str, int] = {}

    def add(self, lineno: int, line: str) -> None:
        """Take line ``lineno`` (without its line end)."""
        if not line.strip():
            return
        parts = [s.strip() for s in line.split(",")]
        name = parts[0]
        if name == "FMT" and len(parts) >= 5:
            fname, fmt = parts[3], parts[4]
            cols = [c for c in parts[5:] if c]
            if re.fullmatch(r"[A-Za-z0-9_]{1,16}", fname) and len(cols) == len(fmt):
                self.formats[fname] = (fmt, cols)
            self._row("FMT", parts[1:5] + [",".join(cols)], lineno)
            return
        spec = self.formats.get(name)
        if spec is None:
            self.skipped.append((lineno, line))
            return
        fields = _text_fields(spec[0], parts[1:])
        if fields is None:
            self.bad[name] = self.bad.get(name, 0) + 1
        else:
            self._row(name, fields, lineno)

    def _row(self, name: str, fields: list[str], lineno: int) -> None:
        self.rows.setdefault(name, []).append(fields)
        self.lines_at.setdefault(name, []).append(lineno)


def _text_fields(fmt: str, fields: list[str]) -> list[str] | None:
    """A text line's fields for format ``fmt``: a trailing text field that itself holds commas
    joined again; None when the count is wrong."""
    if len(fields) == len(fmt):
        return fields
    if fmt and fmt[-1] in _STR and len(fields) > len(fmt):
        k = len(fmt) - 1
        return fields[:k] + [",".join(fields[k:])]
    if not fmt and fields == [""]:
        return []
    return None


def _text_tables(lines: _TextLines) -> tuple[dict[str, pd.DataFrame], dict[str, np.ndarray]]:
    """The raw tables of a text log's messages and the line number of every row."""
    modes = _mode_numbers()
    raw: dict[str, pd.DataFrame] = {}
    order: dict[str, np.ndarray] = {}
    for name, r in lines.rows.items():
        if name == "FMT":
            cols = ["Type", "Length", "Name", "Format", "Columns"]
            fmt = "BBnNZ"
        else:
            fmt, cols = lines.formats[name]
        data = list(zip(*r, strict=True)) if r and fmt else [[] for _ in fmt]
        raw[name] = pd.DataFrame({c: _text_column(list(v), ch, modes)
                                  for c, ch, v in zip(cols, fmt, data, strict=True)},
                                 index=pd.RangeIndex(len(r)))
        order[name] = np.asarray(lines.lines_at[name], dtype=np.int64)
    return raw, order


def _keep_wanted(raw: dict[str, pd.DataFrame], order: dict[str, np.ndarray],
                 want: set[str]) -> None:
    """Drop the tables not in ``want`` from ``raw`` and ``order``, keeping of each only its
    times as a helper table (``_HELPER + name``)."""
    helpers = {}
    for n in list(raw):
        if n not in want:
            df = raw.pop(n)
            o = order.pop(n)
            t, _ = _stamp(df)
            if t is not None:
                helpers[_HELPER + n] = pd.DataFrame({"TimeUS": t})
                order[_HELPER + n] = o
    raw.update(helpers)


# --------------------------------------------------------------------------------------------
# Arming
# --------------------------------------------------------------------------------------------

#: motors of ArduCopter's FRAME_CLASS values (4.x); a log without it (3.x) is taken as a quad
_FRAME_MOTORS = {1: 4, 2: 6, 3: 8, 4: 8, 5: 6, 7: 3, 10: 4, 12: 12, 14: 10, 15: 12}
#: MOT_SPIN_ARM default of 4.x (fraction of the PWM range)
_SPIN_ARM_DEFAULT = 0.1
#: ArduCopter holds the motors at the minimum for about 2 s after arming before they spin
#: up (both a 3.3 log and the 4.7 SITL logs show 2.0-2.3 s): a motor rise this soon after
#: the log's first row belongs to a log that started at arming [µs]
ARMING_DELAY_US = 3_000_000


def _times(df: pd.DataFrame | None) -> np.ndarray:
    if df is None or not len(df) or "TimeUS" not in df.columns:
        return np.zeros(0, np.int64)
    return df["TimeUS"].to_numpy()


def log_start_us(tables: dict[str, pd.DataFrame]) -> int | None:
    """The first TimeUS of any table [µs since boot]; None when no table has rows."""
    ts = [int(t.min()) for t in map(_times, tables.values()) if len(t)]
    return min(ts) if ts else None


def log_end_us(tables: dict[str, pd.DataFrame]) -> int | None:
    """The last TimeUS of any table [µs since boot]; None when no table has rows."""
    ts = [int(t.max()) for t in map(_times, tables.values()) if len(t)]
    return max(ts) if ts else None


def _first(df: pd.DataFrame | None, col: str, value: int, after: int | None = None
           ) -> int | None:
    """TimeUS of the first row with ``col == value`` (after ``after`` µs, exclusive)."""
    if df is None or not len(df) or col not in df.columns or "TimeUS" not in df.columns:
        return None
    v = pd.to_numeric(df[col], errors="coerce").to_numpy()
    t = df["TimeUS"].to_numpy()
    hit = v == value
    if after is not None:
        hit &= t > after
    return int(t[np.argmax(hit)]) if hit.any() else None


def motor_columns(rcou: pd.DataFrame, params: dict[str, float] | None = None) -> list[str]:
    """The RCOU columns of the motors: the first N output channels (``C1..``, 3.3's
    ``Ch1..``, 3.1's ``Chan1..``), N from ``FRAME_CLASS`` (quad 4, hexa 6, octa 8, tri 3, ...;
    4 when the log has no FRAME_CLASS, as 3.x quads), at most as many as the table has."""
    params = params or {}
    n = _FRAME_MOTORS.get(int(params.get("FRAME_CLASS", 1) or 1), 4)
    for prefix in ("C", "Ch", "Chan"):
        cols = [f"{prefix}{k}" for k in range(1, n + 1) if f"{prefix}{k}" in rcou.columns]
        if cols:
            return cols
    return []


def pwm_range(params: dict[str, float]) -> tuple[float, float]:
    """(PWM min, PWM max) of the motor outputs [µs]: MOT_PWM_MIN/MAX when set (> 0), else
    RC3_MIN/RC3_MAX (the throttle channel, as ArduCopter falls back to), else 1000/2000."""
    lo = params.get("MOT_PWM_MIN", 0.0) or 0.0
    hi = params.get("MOT_PWM_MAX", 0.0) or 0.0
    if not (lo > 0 and hi > lo):
        lo = params.get("RC3_MIN", 1000.0) or 1000.0
        hi = params.get("RC3_MAX", 2000.0) or 2000.0
    if not hi > lo:
        lo, hi = 1000.0, 2000.0
    return float(lo), float(hi)


def _spin_arm(params: dict[str, float]) -> float:
    """Armed idle spin as a fraction of the PWM range: MOT_SPIN_ARM (4.x), else
    MOT_SPIN_ARMED / 1000 (3.x: on the 0-1000 throttle scale), else 0.1 (4.x default)."""
    if "MOT_SPIN_ARM" in params:
        return float(params["MOT_SPIN_ARM"])
    if "MOT_SPIN_ARMED" in params:
        return float(params["MOT_SPIN_ARMED"]) / 1000.0
    return _SPIN_ARM_DEFAULT


def motor_idle_pwm(params: dict[str, float] | None = None) -> tuple[float, float]:
    """(armed-idle output, arming threshold) [µs PWM] of the motor outputs.

    idle = PWM min + spin × (PWM max - PWM min), spin = MOT_SPIN_ARM (see ``_spin_arm``);
    a disarmed copter outputs the PWM minimum (or less), an armed one at least the idle
    output, so the threshold sits halfway: PWM min + max(spin / 2, 0.01) × range (at
    least 1 % of the range above the minimum, for MOT_SPIN_ARM 0).
    """
    params = params or {}
    lo, hi = pwm_range(params)
    spin = min(max(_spin_arm(params), 0.0), 1.0)
    return lo + spin * (hi - lo), lo + max(spin / 2, 0.01) * (hi - lo)


def _rcou_arming(tables: dict[str, pd.DataFrame], params: dict[str, float]
                 ) -> tuple[int | None, str]:
    rcou = tables.get("RCOU")
    if rcou is None or not len(rcou) or "TimeUS" not in rcou.columns:
        return None, "never armed"
    cols = motor_columns(rcou, params)
    if not cols:
        return None, "never armed"
    idle, thr = motor_idle_pwm(params)
    out = rcou[cols].apply(pd.to_numeric, errors="coerce").to_numpy(np.float64)
    above = (out >= thr).any(axis=1)
    if not above.any():
        return None, "never armed"
    k = int(np.argmax(above))
    what = (f"{'/'.join(cols)} >= {thr:.0f} us, half the armed idle {idle:.0f} us above the "
            f"PWM minimum")
    start = log_start_us(tables)
    t = int(rcou["TimeUS"].iloc[k])
    if k == 0:
        return start, f"log start (the first RCOU row is already armed: {what})"
    if start is not None and t - start <= ARMING_DELAY_US:
        return start, (f"log start (the motors rise {(t - start) * 1e-6:.1f} s after it, "
                       f"within the arming delay: {what})")
    return t, f"RCOU (motor output rises: {what})"


def arming_time_us(tables: dict[str, pd.DataFrame], params: dict[str, float] | None = None
                   ) -> tuple[int | None, str]:
    """When the vehicle armed [µs since boot], and the rule that said so.

    ``tables``: normalised tables (:func:`read_log_tables`; ``TimeUS`` on each). The rules,
    first that applies:

    1. the first ``EV`` row with ``Id`` 10 (ARMED) → source ``"EV 10"``;
    2. the first ``ARM`` row with ``ArmState`` 1 (4.x) → ``"ARM ArmState 1"``;
    3. the motor outputs, for a log that starts at arming (``LOG_DISARMED 0``, the vehicles'
       default: no arming event is logged): the first ``RCOU`` row where any motor channel
       (:func:`motor_columns`: C1..C4 of a quad, as many as ``FRAME_CLASS`` has) reaches the
       arming threshold of :func:`motor_idle_pwm` [µs PWM] — halfway between the PWM minimum
       (``MOT_PWM_MIN``/``MOT_PWM_MAX``, else ``RC3_MIN``/``RC3_MAX``, else 1000/2000 µs) and
       the armed idle output (``MOT_SPIN_ARM`` × range above the minimum) → ``"RCOU ..."``;
       when the first RCOU row is already there, or the rise comes within
       ``ARMING_DELAY_US`` (3 s: ArduCopter holds the motors ~2 s after arming) of the log's
       first row, the log's first row (the earliest TimeUS of any table) →
       ``"log start ..."``;
    4. else ``(None, "never armed")``.

    ``params``: the log's parameters (``LogTables.params``); only rule 3 uses them.
    """
    t = _first(tables.get("EV"), "Id", AP.EV_ARMED)
    if t is not None:
        return t, "EV 10"
    t = _first(tables.get("ARM"), "ArmState", 1)
    if t is not None:
        return t, "ARM ArmState 1"
    return _rcou_arming(tables, params or {})


def disarm_time_us(tables: dict[str, pd.DataFrame], params: dict[str, float] | None = None,
                   armed_us: int | None = None) -> tuple[int | None, str]:
    """When the vehicle disarmed after arming [µs since boot], and the rule that said so.

    ``armed_us``: the arming time (default: :func:`arming_time_us`). The rules, first that
    applies: the first ``EV`` with ``Id`` 11 (DISARMED) after it → ``"EV 11"``; the first
    ``ARM`` row with ``ArmState`` 0 after it → ``"ARM ArmState 0"``; the log's last row (the
    latest TimeUS of any table) → ``"log end"``. ``(None, "never armed")`` when the vehicle
    never armed.
    """
    if armed_us is None:
        armed_us, _ = arming_time_us(tables, params)
    if armed_us is None:
        return None, "never armed"
    t = _first(tables.get("EV"), "Id", AP.EV_DISARMED, after=armed_us)
    if t is not None:
        return t, "EV 11"
    t = _first(tables.get("ARM"), "ArmState", 0, after=armed_us)
    if t is not None:
        return t, "ARM ArmState 0"
    return log_end_us(tables), "log end"
