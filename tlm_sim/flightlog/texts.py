"""The text ArduCopter writes (``MSG``) for the events a tlm flight logs.

The flight loop logs events as numbers (``ERR`` subsystem/code, ``EV`` ids, ``MODE``); the
firmware's text for each follows from them and from the flight's state at that moment, so it
is rendered here once the flight is over instead of being carried through the numba loop.
:func:`event_texts` gives ``(TimeUS, text)`` lines in time order, with the wording of
ArduCopter 4.7-dev as the reference SITL logs show it (``shared/reference/sitl``), e.g.
``ERR 25/1`` -> "Potential Thrust Loss (1)", ``ERR 6/1`` -> "Battery 1 is low 10.20V used
977 mAh" and "Battery Failsafe". ``tlm_sim.flightlog.binwriter`` writes them into the ``.bin``'s
``MSG`` table.

Each rule is one entry of :data:`ERR_TEXTS` or :data:`EV_TEXTS`: a subsystem/code (or event
id) and a function of the flight's tables and the event's time that returns the lines. Texts
that no ERR/EV row implies come from a logged column's changes (:data:`STATE_TEXTS`), e.g.
``XKFS.MI`` -> "EKF3 IMU0 switching to compass 1".
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
import pandas as pd

__all__ = ["ERR_TEXTS", "EV_TEXTS", "STATE_TEXTS", "event_texts"]

Tables = Mapping[str, pd.DataFrame]
Render = Callable[[Tables, int, int], list[str]]


def _at(tables: Tables, name: str, t_us: int) -> pd.Series | None:
    """The last row of table ``name`` at or before ``t_us`` (the first row if none is)."""
    df = tables.get(name)
    if df is None or not len(df):
        return None
    i = int(np.searchsorted(df["TimeUS"].to_numpy(), t_us, side="right")) - 1
    return df.iloc[max(i, 0)]


def _lost_motor(tables: Tables, t_us: int, _code: int) -> list[str]:
    """ArduCopter names the motor with the highest output (1-based) as the one that lost
    thrust (motors saturated at full output on the weak motor's side)."""
    row = _at(tables, "RCOU", t_us)
    motor = 1 if row is None else int(np.argmax([row[f"C{i}"] for i in range(1, 5)])) + 1
    return [f"Potential Thrust Loss ({motor})"]


def _battery_low(tables: Tables, t_us: int, _code: int) -> list[str]:
    row = _at(tables, "BAT", t_us)
    volt, used = (0.0, 0.0) if row is None else (float(row["Volt"]), float(row["CurrTot"]))
    return [f"Battery 1 is low {volt:.2f}V used {used:.0f} mAh", "Battery Failsafe"]


def _fixed(*lines: str) -> Render:
    return lambda _tables, _t, _code: list(lines)


def _lane_switch(_tables: Tables, _t_us: int, code: int) -> list[str]:
    return [f"EKF3 lane switch {code}", f"EKF primary changed:{code}"]


#: (ERR Subsys, ECode) -> renderer; ECode None matches every code of the subsystem.
ERR_TEXTS: dict[tuple[int, int | None], Render] = {
    (5, 1): _fixed("Radio Failsafe"),
    (5, 0): _fixed("Radio Failsafe Cleared"),
    (6, 1): _battery_low,
    (11, 2): _fixed("GPS Glitch or Compass error"),
    (11, 0): _fixed("Glitch cleared"),
    (24, None): _lane_switch,
    (25, 1): _lost_motor,
    (29, 1): _fixed("Vibration compensation ON"),
    (29, 0): _fixed("Vibration compensation OFF"),
}

#: EV Id -> text.
EV_TEXTS: dict[int, str] = {
    10: "Arming motors",
    11: "Disarming motors",
}


def _compass_switches(tables: Tables) -> list[tuple[int, str]]:
    """EKF3's text for each lane's change of compass: where a core's ``XKFS.MI`` changes (the
    first 10 Hz row after the change; the core index C stands for EKF3's IMU index, the same
    with the default EK3_IMU_MASK)."""
    df = tables.get("XKFS")
    if df is None or not len(df):
        return []
    out: list[tuple[int, str]] = []
    for core, rows in df.groupby("C", sort=True):
        mi = rows["MI"].to_numpy()
        t_us = rows["TimeUS"].to_numpy()
        for i in np.flatnonzero(mi[1:] != mi[:-1]) + 1:
            out.append((int(t_us[i]), f"EKF3 IMU{int(core)} switching to compass {int(mi[i])}"))
    return out


#: Texts from the changes of a logged value: functions of the flight's tables returning
#: ``(TimeUS, text)`` lines.
STATE_TEXTS: tuple[Callable[[Tables], list[tuple[int, str]]], ...] = (_compass_switches,)


def event_texts(tables: Tables) -> list[tuple[int, str]]:
    """``(TimeUS, text)`` MSG lines for the ERR and EV events of a flight's tables, in time
    order (the order of the events at equal times)."""
    out: list[tuple[int, str]] = []
    err = tables.get("ERR")
    if err is not None:
        for t, sub, code in zip(err["TimeUS"], err["Subsys"], err["ECode"], strict=True):
            render = ERR_TEXTS.get((int(sub), int(code))) or ERR_TEXTS.get((int(sub), None))
            if render is not None:
                out += [(int(t), line) for line in render(tables, int(t), int(code))]
    ev = tables.get("EV")
    if ev is not None:
        for t, ev_id in zip(ev["TimeUS"], ev["Id"], strict=True):
            text = EV_TEXTS.get(int(ev_id))
            if text is not None:
                out.append((int(t), text))
    for rule in STATE_TEXTS:
        out += rule(tables)
    return sorted(out, key=lambda line: line[0])
