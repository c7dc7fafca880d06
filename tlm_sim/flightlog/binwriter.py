"""Write a FlightLog as an ArduPilot DataFlash ``.bin`` log that ArduPilot's tools open.

The file follows ArduPilot's log start sequence (``ardupilot-reference.md`` §5.5): FMT for
FMT (type 128) and for every message type in the file, UNIT and MULT for every unit and
multiplier id, FMTU for every type, then one time-ordered stream: PARM for every parameter
(value and tlm default), VER and MSG lines naming ArduCopter (so pymavlink and Mission
Planner decode flight modes as Copter modes), the mission as CMD items, then the flight's
tables merged by TimeUS, with in-flight parameter changes as PARM messages and fault starts
and ends as MSG lines at the times they took effect.

Layouts, format characters and scaling come from the same ``MessageSchema`` the tables use
(``tlm_sim.flightlog.schema``), and each column goes to its raw stored form through
``quantise.column_to_raw``; reading the file back (``read_bin``) gives the tables exactly.

Packing is vectorised: each table becomes one numpy structured array (3 header bytes +
fields, packed little-endian), and all messages are scattered into one byte buffer in
(TimeUS, type order, row) order with index arithmetic. No Python per message.

A FlightLog read from a ``.bin`` (``FlightLog.from_bin``) carries its own PARM, MSG, CMD and
VER tables; they are written as they are instead of generated, so a reference log survives a
read → write → read round trip. FMT, FMTU, UNIT and MULT are always regenerated.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tlm_sim.ardupilot import FMT_TYPE, HEAD1, HEAD2

from .quantise import column_to_raw, quantise_frame
from .schema import FORMAT_CHARS, MULTS, SCHEMAS, UNITS, MessageSchema
from .texts import event_texts, logged_texts, rc_switch_changes, rc_switch_texts, startup_texts

__all__ = [
    "FIRMWARE_STRING", "FRAME_STRING", "encode_bin", "fault_messages", "frame_string",
    "merge_order", "message_stream", "message_types", "msg_table", "write_bin",
]

#: Firmware string of the VER/MSG lines: names ArduCopter (pymavlink's vehicle detection) and
#: the reference logs' firmware, marked as tlm.
FIRMWARE_STRING = "ArduCopter V4.7.0-dev (tlm)"
#: The firmware's frame line of the default frame (others: :func:`frame_string`).
FRAME_STRING = "Frame: QUAD/PLUS"
#: Written fresh on every file (the tables of these in a FlightLog are ignored).
_SELF_DESCRIPTION = ("FMT", "UNIT", "MULT", "FMTU")
#: Start-up messages written before the data at the same timestamp (AUXF: the RC aux switches'
#: runs, generated from RCIN and the parameters, at their own times).
_STARTUP = ("PARM", "VER", "MSG", "CMD", "AUXF")
#: AUXF fields: AuxSwitchPos of a position name, AuxFuncTrigger::Source::RC, success
_AUX_POS = {"LOW": 0, "MIDDLE": 1, "HIGH": 2}
_AUX_SOURCE_RC, _AUX_RESULT_OK = 1, 1

# the columns of tlm_sim.mission.Mission.items (ITEM_FIELDS there)
_ITEM_FIELDS = ("CId", "Prm1", "Prm2", "Prm3", "Prm4", "Lat", "Lng", "Alt", "Frame")


def _raw_dtype(schema: MessageSchema) -> np.dtype:
    """Packed structured dtype of one message: header (2 bytes), type id, then the fields."""
    fields: list[tuple[Any, ...]] = [("h1", "u1"), ("h2", "u1"), ("type", "u1")]
    for k, c in enumerate(schema.fmt):
        fc = FORMAT_CHARS[c]
        if fc.kind == "str":
            fields.append((f"f{k}", f"S{fc.size}"))
        elif fc.kind == "array":
            fields.append((f"f{k}", "<i2", (32,)))
        else:
            st = fc.struct
            fields.append((f"f{k}", st if st in ("b", "B") else "<" + st))
    dt = np.dtype(fields)
    if dt.itemsize != schema.length:
        raise ValueError(f"{schema.name}: packed size {dt.itemsize} != length {schema.length}")
    return dt


def _pack(schema: MessageSchema, type_id: int, columns: Mapping[str, Any], n: int) -> np.ndarray:
    """``[n, schema.length]`` uint8 rows of complete messages from table-valued columns."""
    rec = np.zeros(n, dtype=_raw_dtype(schema))
    rec["h1"], rec["h2"], rec["type"] = HEAD1, HEAD2, type_id
    for k, (col, c) in enumerate(zip(schema.columns, schema.fmt, strict=True)):
        if n:
            rec[f"f{k}"] = column_to_raw(np.asarray(columns[col]) if FORMAT_CHARS[c].kind
                                         not in ("str", "array") else list(columns[col]), c)
    return rec.view(np.uint8).reshape(n, schema.length)


def _param_defaults() -> Mapping[str, float]:
    from tlm_sim.params import Params

    return Params.defaults()


def _parm_frame(log: Any, t0_us: int) -> pd.DataFrame:
    """PARM rows: every parameter at ``t0_us``, then each in-flight change at its time."""
    params = log.params or {}
    defaults = _param_defaults()
    names = sorted(params)
    values = [float(params[n]) for n in names]
    times = [t0_us] * len(names)
    initial = {}
    for ch in (log.meta or {}).get("param_changes") or ():
        t = ch.get("time_us")
        if t is None:
            continue
        name = str(ch["name"])
        initial.setdefault(name, params.get(name, float(ch["value"])))
        names.append(name)
        values.append(float(ch["value"]))
        times.append(int(t))
    # the start-of-log value of a parameter changed in flight is its value before the change
    for k, n in enumerate(names[: len(params)]):
        if n in initial:
            values[k] = float(initial[n])
    return pd.DataFrame({
        "TimeUS": np.asarray(times, dtype=np.int64),
        "Name": names,
        "Value": values,
        "Default": [float(defaults.get(n, v)) for n, v in zip(names, values, strict=True)],
    })


def fault_messages(faults: Sequence[Mapping[str, Any]]) -> list[tuple[int, str]]:
    """(TimeUS, text) MSG lines marking each fault record's start and end.

    Text: ``"tlm: fault gps (label 1) start"`` / ``... end``; a fault that never ended has no
    end line.
    """
    out = []
    for f in faults:
        name, label = f.get("type", "fault"), f.get("label", "?")
        for edge in ("start", "end"):
            t = f.get(f"{edge}_time_us")
            if t is not None:
                out.append((int(t), f"tlm: fault {name} (label {label}) {edge}"))
    return out


def frame_string(params: Mapping[str, float] | None) -> str:
    """ArduCopter's boot line naming the frame of FRAME_CLASS / FRAME_TYPE (``Frame: QUAD/X``);
    the default quad "+" when the parameters do not name one of tlm's frames."""
    from tlm_sim.frames import FrameError, frame_for

    p = params or {}
    try:
        return "Frame: " + frame_for(p.get("FRAME_CLASS", 1.0), p.get("FRAME_TYPE", 0.0)).label
    except FrameError:
        return FRAME_STRING


def _msg_frame(log: Any, t0_us: int) -> pd.DataFrame:
    """MSG rows: at ``t0_us`` the firmware string, the logger's start-up lines
    (:func:`tlm_sim.flightlog.texts.startup_texts`), the frame and the tlm flight identity; then
    the RC switch announcements, the fault lines and the firmware's text for the flight's events
    (:func:`tlm_sim.flightlog.texts.event_texts`) in time order."""
    meta = log.meta or {}
    lines = [(t0_us, FIRMWARE_STRING), *((t0_us, m) for m in startup_texts()),
             (t0_us, frame_string(log.params))]
    ident = [f"{k} {meta[k]}" for k in ("mission", "seed", "profile") if meta.get(k) is not None]
    if ident:
        lines.append((t0_us, "tlm: " + ", ".join(ident)))
    lines += sorted(rc_switch_texts(log.tables, log.params) + fault_messages(log.faults or ())
                    + event_texts(log.tables) + logged_texts(meta.get("texts") or ()),
                    key=lambda line: line[0])
    return pd.DataFrame({"TimeUS": [t for t, _ in lines], "Message": [m for _, m in lines]})


def _t0(log: Any) -> int:
    """The log's first TimeUS (where the start-up messages go)."""
    t_first = [int(df["TimeUS"].min()) for df in log.tables.values()
               if len(df) and "TimeUS" in df.columns]
    return min(t_first) if t_first else 0


def msg_table(log: Any) -> pd.DataFrame:
    """The MSG rows a ``.bin`` of ``log`` holds: its own MSG table (a log read from a ``.bin``)
    or the generated one (:func:`_msg_frame`)."""
    if "MSG" in log.tables:
        return log.tables["MSG"]
    return _msg_frame(log, _t0(log))


def message_types(log: Any) -> dict[str, int]:
    """Message name -> rows for every type a ``.bin`` of ``log`` holds rows of (the
    self-description FMT, UNIT, MULT, FMTU included), without writing it."""
    preamble, timed = message_stream(log)
    return {s.name: len(df) for _, s, df in (*preamble, *timed) if len(df)}


def _auxf_frame(log: Any) -> pd.DataFrame | None:
    """AUXF rows: each RC aux switch's run, when first read and on each change
    (:func:`tlm_sim.flightlog.texts.rc_switch_changes`, the same events as the "RC7:
    SaveWaypoint LOW" text)."""
    runs = rc_switch_changes(log.tables, log.params)
    if not runs:
        return None
    return pd.DataFrame({
        "TimeUS": [t for t, *_ in runs], "function": [o for _, _, o, _ in runs],
        "pos": [_AUX_POS[p] for *_, p in runs], "source": _AUX_SOURCE_RC,
        "index": [ch - 1 for _, ch, _, _ in runs], "result": _AUX_RESULT_OK,
    })


def _ver_frame(t0_us: int) -> pd.DataFrame:
    return pd.DataFrame({
        "TimeUS": [t0_us], "BT": [3], "BST": [65535], "Maj": [4], "Min": [7], "Pat": [0],
        "FWT": [0], "GH": [0], "FWS": [FIRMWARE_STRING], "APJ": [0], "BU": [2], "FV": [2],
        "IMI": [0], "ICI": [0],
    })


def _mission_items(mission: Any) -> np.ndarray | None:
    """The items (:meth:`tlm_sim.mission.Mission.items`) of a Mission or its JSON form (a
    FlightLog read back from disk); None if there is none or it is not a valid mission."""
    if mission is None:
        return None
    from tlm_sim.mission import Mission, MissionError  # (flightlog does not need missions)

    if not isinstance(mission, Mission):
        if not isinstance(mission, Mapping):
            return None
        try:
            mission = Mission.from_dict(mission)
        except MissionError:
            return None
    return mission.items()


def _cmd_frame(mission: Any, t0_us: int) -> pd.DataFrame | None:
    """CMD rows as ArduCopter logs an uploaded mission: home, takeoff, the waypoints' items
    (with their DO_CHANGE_SPEED items), RTL or the final LAND."""
    items = _mission_items(mission)
    if items is None:
        return None
    n = len(items)
    col = {name: items[:, j] for j, name in enumerate(_ITEM_FIELDS)}
    return pd.DataFrame({
        "TimeUS": np.full(n, t0_us, dtype=np.int64), "CTot": np.full(n, n), "CNum": np.arange(n),
        "CId": col["CId"].astype(np.int64), "Prm1": col["Prm1"], "Prm2": col["Prm2"],
        "Prm3": col["Prm3"], "Prm4": col["Prm4"], "Lat": col["Lat"], "Lng": col["Lng"],
        "Alt": col["Alt"], "Frame": col["Frame"].astype(np.int64),
    })


def _tables_to_write(log: Any) -> dict[str, tuple[MessageSchema, pd.DataFrame]]:
    """The log's tables plus generated start-up tables (PARM, VER, MSG, CMD) where absent."""
    out: dict[str, tuple[MessageSchema, pd.DataFrame]] = {}
    t0 = _t0(log)
    generated = {
        "PARM": lambda: _parm_frame(log, t0) if log.params else None,
        "VER": lambda: _ver_frame(t0),
        "MSG": lambda: _msg_frame(log, t0),
        "CMD": lambda: _cmd_frame(log.mission, t0),
        "AUXF": lambda: _auxf_frame(log),
    }
    for name in _STARTUP:
        if name in log.tables:
            continue
        df = generated[name]()
        if df is not None and len(df):
            out[name] = (SCHEMAS[name], quantise_frame(df, SCHEMAS[name]))
    for name, df in log.tables.items():
        if name in _SELF_DESCRIPTION or not len(df):
            continue
        out[name] = (log.schemas[name], df)
    if "ANG" not in log.tables and "ATT" in out:
        out["ANG"] = (SCHEMAS["ANG"], _ang_frame(out["ATT"][1], log.params))
    return out


def _ang_frame(att: pd.DataFrame, params: Mapping[str, float] | None) -> pd.DataFrame:
    """ANG rows: ArduCopter logs the attitude controller's targets and attitude with the
    main-loop interval beside ATT, row for row (the same values); Dt [s] is the loop period
    1 / SCHED_LOOP_RATE (SITL logs its measured interval, 0.002499 s at 400 Hz)."""
    df = att[["TimeUS", "DesRoll", "Roll", "DesPitch", "Pitch", "DesYaw", "Yaw"]].copy()
    df["Dt"] = 1.0 / float((params or {}).get("SCHED_LOOP_RATE", 400.0))
    return quantise_frame(df, SCHEMAS["ANG"])


def _self_description(
    schemas: Sequence[tuple[int, MessageSchema]],
) -> list[tuple[MessageSchema, pd.DataFrame]]:
    """FMT, UNIT, MULT, FMTU tables describing ``(type id, schema)`` pairs."""
    fmt_schema = SCHEMAS["FMT"]
    pairs = [(FMT_TYPE, fmt_schema), *schemas]
    fmt = pd.DataFrame({
        "Type": [t for t, _ in pairs], "Length": [s.length for _, s in pairs],
        "Name": [s.name for _, s in pairs], "Format": [s.fmt for _, s in pairs],
        "Columns": [",".join(s.columns) for _, s in pairs],
    })
    unit = pd.DataFrame({"TimeUS": 0, "Id": [ord(k) for k in UNITS],
                         "Label": list(UNITS.values())})
    mult = pd.DataFrame({"TimeUS": 0, "Id": [ord(k) for k in MULTS],
                         "Mult": list(MULTS.values())})
    fmtu = pd.DataFrame({
        "TimeUS": 0, "FmtType": [t for t, _ in pairs],
        "UnitIds": [s.units for _, s in pairs], "MultIds": [s.mults for _, s in pairs],
    })
    return [(SCHEMAS[n], quantise_frame(df, SCHEMAS[n]))
            for n, df in (("FMT", fmt), ("UNIT", unit), ("MULT", mult), ("FMTU", fmtu))]


def _type_ids(names: Sequence[str]) -> dict[str, int]:
    """Type ids for the messages (any ids are valid; readers use FMT): 1, 2, ... skipping 128."""
    own = [n for n in (*_SELF_DESCRIPTION[1:], *names) if n != "FMT"]
    ids = [k for k in range(1, 255) if k != FMT_TYPE]
    if len(own) > len(ids):
        raise ValueError(f"too many message types for one .bin ({len(own)} > {len(ids)})")
    return dict(zip(own, ids, strict=False))


def message_stream(
    log: Any,
) -> tuple[list[tuple[int, MessageSchema, pd.DataFrame]], list[tuple[int, MessageSchema,
                                                                     pd.DataFrame]]]:
    """The messages of ``log`` as (type id, schema, table) lists: (preamble, timed).

    The preamble (FMT, UNIT, MULT, FMTU) is written first in that order; the timed tables are
    merged by ``merge_order``. Shared by the ``.bin`` writer and the Mission Planner text log.
    """
    tables = _tables_to_write(log)
    ids = _type_ids(list(tables))
    described = [(ids[n], SCHEMAS[n]) for n in _SELF_DESCRIPTION[1:]]
    described += [(ids[n], s) for n, (s, _) in tables.items()]
    for _, s in described:
        if len(s.name) > 4 or len(s.fmt) > 16 or len(",".join(s.columns)) > 64:
            raise ValueError(f"{s.name}: name/format/columns too long for a DataFlash FMT")
    preamble = [
        (FMT_TYPE if schema.name == "FMT" else ids[schema.name], schema, df)
        for schema, df in _self_description(described)
    ]
    timed = [(ids[n], schema, df) for n, (schema, df) in tables.items()]
    return preamble, timed


def merge_order(tables: Sequence[pd.DataFrame]) -> np.ndarray:
    """Stream position of every row of ``tables`` (concatenated): by TimeUS, then table
    order (start-up tables first), then row. Returns the permutation (``np.lexsort``)."""
    times = np.concatenate([
        df["TimeUS"].to_numpy(np.int64) if "TimeUS" in df.columns else np.zeros(len(df), np.int64)
        for df in tables
    ])
    prio = np.concatenate([np.full(len(df), k) for k, df in enumerate(tables)])
    return np.lexsort((np.arange(len(times)), prio, times))


def encode_bin(log: Any) -> bytes:
    """The DataFlash bytes of ``log`` (a FlightLog): see the module docstring for the layout."""
    preamble, timed = message_stream(log)
    head = b"".join(_pack(s, t, df, len(df)).tobytes() for t, s, df in preamble)
    timed = [(t, s, df) for t, s, df in timed if len(df)]
    if not timed:
        return head
    rows = [_pack(s, t, df, len(df)) for t, s, df in timed]
    order = merge_order([df for _, _, df in timed])
    lengths = np.concatenate([np.full(len(r), r.shape[1], dtype=np.int64) for r in rows])
    start = np.empty(len(lengths), dtype=np.int64)
    start[order] = np.concatenate([[0], np.cumsum(lengths[order])[:-1]])
    out = np.empty(int(lengths.sum()), dtype=np.uint8)
    k = 0
    for r in rows:
        n, width = r.shape
        out[start[k:k + n, None] + np.arange(width)[None, :]] = r
        k += n
    return head + out.tobytes()


def write_bin(log: Any, path: str | os.PathLike) -> Path:
    """Write ``log`` (a FlightLog) as a DataFlash ``.bin`` file; returns the path.

    The file is written to a temporary name and renamed, so a reader never sees half a log.
    """
    p = Path(path)
    data = encode_bin(log)
    tmp = p.with_name(p.name + ".part")
    tmp.write_bytes(data)
    os.replace(tmp, p)
    return p
