"""The text ArduCopter writes (``MSG``) for the events a tlm flight logs.

The flight loop logs events as numbers (``ERR`` subsystem/code, ``EV`` ids, ``MODE``); the
firmware's text for each follows from them and from the flight's state at that moment, so it
is rendered here once the flight is over instead of being carried through the numba loop.
:func:`event_texts` gives ``(TimeUS, text)`` lines in time order, with the wording of
ArduCopter 4.7-dev as the reference SITL logs show it (``shared/reference/sitl``), e.g.
``ERR 25/1`` -> "Potential Thrust Loss (1)", ``ERR 6/1`` -> "Battery 1 is low 10.20V used
977 mAh" and "Battery Failsafe". ``tlm_sim.flightlog.binwriter`` writes them into the ``.bin``'s
``MSG`` table.

The pre-arm and arming texts and EKF3's lifecycle messages come from the flight's text log
(``FlightLog.meta["texts"]``, rows the flight loop writes when a check fails or a lane changes
state, :mod:`tlm_sim.control.arming`): :func:`logged_texts`.

Each rule is one entry of :data:`ERR_TEXTS` or :data:`EV_TEXTS`: a subsystem/code (or event
id) and a function of the flight's tables and the event's time that returns the lines. Texts
that no ERR/EV row implies come from a logged column's changes (:data:`STATE_TEXTS`), e.g.
``XKFS.MI`` -> "EKF3 IMU0 switching to compass 1", ``MISE`` -> "Reached command #5",
"Mission: 6 WP". :func:`startup_texts` are the lines the logger writes when the log starts and
:func:`rc_switch_texts` the RC aux switch announcements (they need the parameters).

:func:`text_kind` masks the numbers of a text ("Reached command #N"): the kinds that
``tlm crosscheck`` compares between a tlm flight and a SITL log.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Mapping, Sequence

import numpy as np
import pandas as pd

from tlm_sim import ardupilot as AP

__all__ = ["ARM_CHECK_TEXTS", "ERR_TEXTS", "EV_TEXTS", "STATE_TEXTS", "event_texts",
           "gps_detected", "ground_impacts", "logged_texts", "mission_texts",
           "rc_switch_changes", "rc_switch_texts", "startup_texts", "text_kind"]

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
    """ArduCopter names the motor with the highest 0.5 s-filtered output (1-based) as the one
    that lost thrust: the weak motor, saturated at full output (here: the highest RCOU)."""
    row = _at(tables, "RCOU", t_us)
    outputs = [] if row is None else [row[c] for c in (f"C{i}" for i in range(1, 9))
                                      if c in row.index]
    motor = int(np.argmax(outputs)) + 1 if outputs else 1
    return [f"Potential Thrust Loss ({motor})"]


def _battery_low(tables: Tables, t_us: int, _code: int) -> list[str]:
    """AP_BattMonitor's escalation text and Copter's failsafe announcement. The battery state
    only escalates (low, then critical), so a flight's second ERR 6/1 is the critical one; a
    disarm at the same time (EV 11: landed, or Terminate) reads "Battery Failsafe -
    Disarming"."""
    row = _at(tables, "BAT", t_us)
    volt, used = (0.0, 0.0) if row is None else (float(row["Volt"]), float(row["CurrTot"]))
    err = tables["ERR"]
    earlier = int(((err["Subsys"] == AP.ERR_FAILSAFE_BATT) & (err["ECode"] == AP.ERR_CODE_FAILSAFE)
                   & (err["TimeUS"] < t_us)).sum())
    level = "low" if earlier == 0 else "critical"
    ev = tables.get("EV")
    disarm = ev is not None and bool(((ev["Id"] == AP.EV_DISARMED) & (ev["TimeUS"] == t_us)).any())
    return [f"Battery 1 is {level} {volt:.2f}V used {used:.0f} mAh",
            "Battery Failsafe - Disarming" if disarm else "Battery Failsafe"]


#: SIM height above its pre-arming level below which the vehicle touches the ground [m]
GROUND_CONTACT_M = 0.02
#: SITL prints an impact only this long after the last one it printed [us]
IMPACT_HOLDOFF_US = 1_000_000


def ground_impacts(tables: Tables) -> list[tuple[int, str]]:
    """SITL's "SIM Hit ground at %f m/s" (SIM_Aircraft, on touching the ground more than 1 s
    after the last impact it printed), from the SIM truth: a row on the ground after one
    above it, after arming; the speed is the descent rate over the last two rows in the air
    (10 Hz), the time where that rate meets the ground."""
    sim, ev = tables.get("SIM"), tables.get("EV")
    if sim is None or ev is None or len(sim) < 3:
        return []
    armed = ev["TimeUS"][ev["Id"] == AP.EV_ARMED]
    if not len(armed):
        return []
    t = sim["TimeUS"].to_numpy(np.float64)
    alt = sim["Alt"].to_numpy(np.float64)
    before = alt[t < float(armed.iloc[0])]
    h = alt - float(np.median(before if len(before) else alt[:1]))
    on = h <= GROUND_CONTACT_M
    out: list[tuple[int, str]] = []
    last = -np.inf
    for k in np.flatnonzero(on[2:] & ~on[1:-1]) + 2:
        if t[k] <= float(armed.iloc[0]) or t[k] - last <= IMPACT_HOLDOFF_US:
            continue
        v = (h[k - 2] - h[k - 1]) / ((t[k - 1] - t[k - 2]) * 1e-6)
        t_hit = t[k - 1] + (h[k - 1] / v * 1e6 if v > 0.0 else 0.0)
        t_hit = min(t_hit, t[k])
        out.append((int(t_hit), f"SIM Hit ground at {max(v, 0.0):.6f} m/s"))
        last = t_hit
    return out


def _fixed(*lines: str) -> Render:
    return lambda _tables, _t, _code: list(lines)


def _lane_switch(_tables: Tables, _t_us: int, code: int) -> list[str]:
    return [f"EKF3 lane switch {code}", f"EKF primary changed:{code}"]


#: (ERR Subsys, ECode) -> renderer; ECode None matches every code of the subsystem.
ERR_TEXTS: dict[tuple[int, int | None], Render] = {
    (AP.ERR_FAILSAFE_RADIO, AP.ERR_CODE_FAILSAFE): _fixed("Radio Failsafe"),
    (AP.ERR_FAILSAFE_RADIO, AP.ERR_CODE_RESOLVED): _fixed("Radio Failsafe Cleared"),
    (AP.ERR_FAILSAFE_BATT, AP.ERR_CODE_FAILSAFE): _battery_low,
    (AP.ERR_GPS, AP.ERR_CODE_GPS_GLITCH): _fixed("GPS Glitch or Compass error"),
    (AP.ERR_GPS, AP.ERR_CODE_RESOLVED): _fixed("Glitch cleared"),
    (AP.ERR_EKF_PRIMARY, None): _lane_switch,
    (AP.ERR_THRUST_LOSS_CHECK, AP.ERR_CODE_FAILSAFE): _lost_motor,
    (AP.ERR_FAILSAFE_VIBE, AP.ERR_CODE_FAILSAFE): _fixed("Vibration compensation ON"),
    (AP.ERR_FAILSAFE_VIBE, AP.ERR_CODE_RESOLVED): _fixed("Vibration compensation OFF"),
}

#: EV Id -> text.
EV_TEXTS: dict[int, str] = {
    AP.EV_ARMED: "Arming motors",
    AP.EV_DISARMED: "Disarming motors",
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


#: the items whose completion ArduCopter announces: NAV_WAYPOINT (verify_nav_wp) and
#: NAV_LOITER_TIME (verify_loiter_time), once their hold time is over
REACHED_CMDS = (AP.MAV_CMD_NAV_WAYPOINT, AP.MAV_CMD_NAV_LOITER_TIME)


def mission_texts(tables: Tables) -> list[tuple[int, str]]:
    """ArduCopter's mission progress from the MISE rows (one per item started): "Reached
    command #k" when a waypoint or loiter k is done (ModeAuto::verify_nav_wp,
    verify_loiter_time: after its hold time, at the start of the next item), then "Mission:
    k+1 <type>" (AP_Mission::start_command, for DO_CHANGE_SPEED items too)."""
    mise = tables.get("MISE")
    if mise is None or not len(mise):
        return []
    out: list[tuple[int, str]] = []
    prev_num, prev_id = -1, -1
    for t, num, cid in zip(mise["TimeUS"], mise["CNum"], mise["CId"], strict=True):
        if prev_id in REACHED_CMDS and int(num) == prev_num + 1:
            out.append((int(t), f"Reached command #{prev_num}"))
        out.append((int(t), f"Mission: {int(num)} {AP.MAV_CMD_TYPES.get(int(cid), str(cid))}"))
        prev_num, prev_id = int(num), int(cid)
    return out


def field_elevation(tables: Tables) -> list[tuple[int, str]]:
    """AP_Baro's "Field Elevation Set: <m>m" once the EKF origin is first known while
    disarmed (the first ORGN Type 0 row: the baro takes the origin's altitude as its field
    elevation)."""
    orgn = tables.get("ORGN")
    if orgn is None or not len(orgn):
        return []
    origin = orgn[orgn["Type"] == 0]
    if not len(origin):
        return []
    row = origin.iloc[0]
    return [(int(row["TimeUS"]), f"Field Elevation Set: {float(row['Alt']):.0f}m")]


#: Texts from the changes of a logged value: functions of the flight's tables returning
#: ``(TimeUS, text)`` lines.
STATE_TEXTS: tuple[Callable[[Tables], list[tuple[int, str]]], ...] = (
    ground_impacts, _compass_switches, mission_texts, field_elevation)

#: RC aux functions (RCn_OPTION) and their names as RC_Channel announces them: the ones
#: tlm's parameter set uses (copter.parm's RC7_OPTION 7); others are not announced
AUX_FUNCTION_NAMES: dict[int, str] = {7: "SaveWaypoint"}
#: RC_Channel's three-position switch thresholds [us]
AUX_SWITCH_LOW_US, AUX_SWITCH_HIGH_US = 1200, 1800
RC_CHANNELS = 14


def _switch_position(pwm: float) -> str | None:
    """RC_Channel::read_3pos_switch: LOW below 1200 us, HIGH above 1800 us, else MIDDLE; None
    when the channel reads no valid pulse (<= 900 or >= 2200 us)."""
    if pwm <= 900 or pwm >= 2200:
        return None
    if pwm < AUX_SWITCH_LOW_US:
        return "LOW"
    return "HIGH" if pwm > AUX_SWITCH_HIGH_US else "MIDDLE"


def rc_switch_changes(tables: Tables, params: Mapping[str, float] | None
                      ) -> list[tuple[int, int, int, str]]:
    """(TimeUS, channel, RCn_OPTION, position) where an RC aux switch with an announced function
    (:data:`AUX_FUNCTION_NAMES`) is first read and where its position changes, from the RCIN
    rows and the RCn_OPTION parameters (RC_Channel::read_aux: the first read and every change
    run the aux function and announce it)."""
    rcin = tables.get("RCIN")
    if rcin is None or not len(rcin) or not params:
        return []
    out: list[tuple[int, int, int, str]] = []
    for ch in range(1, RC_CHANNELS + 1):
        option = int(params.get(f"RC{ch}_OPTION", 0) or 0)
        if option not in AUX_FUNCTION_NAMES or f"C{ch}" not in rcin.columns:
            continue
        last = None
        for t, pwm in zip(rcin["TimeUS"], rcin[f"C{ch}"], strict=True):
            pos = _switch_position(float(pwm))
            if pos is not None and pos != last:
                out.append((int(t), ch, option, pos))
                last = pos
    return sorted(out)


def rc_switch_texts(tables: Tables, params: Mapping[str, float] | None) -> list[tuple[int, str]]:
    """"RC7: SaveWaypoint LOW" for each of :func:`rc_switch_changes`."""
    return [(t, f"RC{ch}: {AUX_FUNCTION_NAMES[option]} {pos}")
            for t, ch, option, pos in rc_switch_changes(tables, params)]


def startup_texts() -> list[str]:
    """The lines ArduPilot's logger writes when a log starts, after the firmware string, for
    what tlm has: the RC protocol of SITL's RC input ("RC Protocol: UDP"), the mission,
    rally-point and fence lists (tlm's mission is loaded before the flight, as the reference
    driver uploaded it: "Flight plan received"; no rally points, no fence)."""
    return ["RC Protocol: UDP", "Flight plan received", "New mission", "New rally",
            "New fence"]


_HEX_ID = re.compile(r"\b(?=[0-9a-f]*\d)(?=[0-9a-f]*[a-f])[0-9a-f]{8,}\b")
_NUMBER = re.compile(r"\d+(?:\.\d+)*")


def text_kind(text: str) -> str:
    """The kind of a MSG text: hexadecimal ids (a git hash, a board id) as ``<id>``, every
    number as ``N`` ("Reached command #12" -> "Reached command #N", "ArduCopter V4.7.0-dev
    (2598e9d4)" -> "ArduCopter VN-dev (<id>)")."""
    return _NUMBER.sub("N", _HEX_ID.sub("<id>", text.strip()))


def event_texts(tables: Tables) -> list[tuple[int, str]]:
    """``(TimeUS, text)`` MSG lines for the ERR and EV events of a flight's tables and for the
    changes of its logged state (:data:`STATE_TEXTS`: ground impacts, compass switches), in
    time order (the order of the events at equal times)."""
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


# ---------------------------------------------------------------- the flight's text log
# (FlightLog.meta["texts"]: rows written in the flight loop by tlm_sim.control.arming)

def _ahrs(row: Sequence[float]) -> str:
    lane = int(row[AP.A_LANE])
    return ("AHRS: EKF3 not started" if lane < 0 else f"AHRS: EKF3 core {lane} unhealthy")


_VARIANCES = ("compass", "position", "velocity", "height")  # by AP.VAR_*
_BATTERY = ("below minimum arming voltage", "low voltage failsafe", "low capacity failsafe",
            "critical voltage failsafe", "critical capacity failsafe")  # by AP.BATT_*

#: what each failing pre-arm / arm check reads (after "Arm: " or "PreArm: "), by its bit
#: (:mod:`tlm_sim.ardupilot` F_*), in ArduCopter's report order; a function takes the text row
ARM_CHECK_TEXTS: dict[int, str | Callable[[Sequence[float]], str]] = {
    AP.F_RC_NOT_FOUND: "RC not found",
    AP.F_THR_LOW: "Throttle below failsafe",
    AP.F_NEED_ALT: "Need Alt Estimate",
    AP.F_BARO: "Baro: not healthy",
    AP.F_ALT_DISPARITY: "Altitude disparity",
    AP.F_GYRO_HEALTH: "Gyros not healthy",
    AP.F_ACC_HEALTH: "Accels not healthy",
    AP.F_ACC_INCONS: "Accels inconsistent",
    AP.F_GYRO_INCONS: "Gyros inconsistent",
    AP.F_EKF_ATTITUDE: "EKF attitude is bad",
    AP.F_COMPASS_HEALTH: "Compass not healthy",
    AP.F_MAG_FIELD: lambda row: (f"Check mag field: {row[AP.A_MAG_FIELD]:4.0f}, max "
                                 f"{AP.MAG_FIELD_MAX:.0f}, min {AP.MAG_FIELD_MIN:.0f}"),
    AP.F_COMPASS_INCONS: "Compasses inconsistent",
    AP.F_GPS_FIX: "GPS 1: Bad fix",
    AP.F_WAIT_HOME: "AHRS: waiting for home",
    AP.F_GPS_AHRS: lambda row: f"GPS and AHRS differ by {row[AP.A_GPS_AHRS]:4.1f}m",
    AP.F_AHRS: _ahrs,
    AP.F_NEED_POS: "Need Position Estimate",
    AP.F_GPS_GLITCH: "GPS glitching",
    AP.F_EKF_VARIANCE: lambda row: f"EKF {_VARIANCES[int(row[AP.A_VARIANCE])]} variance",
    AP.F_HDOP: "High GPS HDOP",
    AP.F_BATTERY: lambda row: f"Battery 1 {_BATTERY[int(row[AP.A_BATTERY])]}",
    AP.F_BATT_FS: "Battery failsafe",
    AP.F_ARM_AHRS: "AHRS not healthy",
    AP.F_ARM_COMPASS: "Compass not healthy",
    AP.F_ARM_LEANING: "Leaning",
}


#: EKF3's lifecycle messages by event bit (:mod:`tlm_sim.ardupilot` EKF_EVT_*): IMU and
#: compass index
_EKF_TEXTS = {AP.EKF_EVT_INIT: "EKF3 IMU{imu} initialised",
              AP.EKF_EVT_TILT: "EKF3 IMU{imu} tilt alignment complete",
              AP.EKF_EVT_YAW: "EKF3 IMU{imu} MAG{mag} initial yaw alignment complete",
              AP.EKF_EVT_ORIGIN: "EKF3 IMU{imu} origin set",
              AP.EKF_EVT_USING_GPS: "EKF3 IMU{imu} is using GPS",
              AP.EKF_EVT_STOPPED: "EKF3 IMU{imu} stopped aiding",
              AP.EKF_EVT_INFLIGHT_YAW: "EKF3 IMU{imu} MAG{mag} in-flight yaw alignment complete"}


def logged_texts(rows: Iterable[Sequence[float]]) -> list[tuple[int, str]]:
    """``(TimeUS, text)`` MSG lines of a flight's text log (``FlightLog.meta["texts"]``): the
    failed arm attempts ("Arm: ..." per failing check), the periodic pre-arm reports
    ("PreArm: ..."), EKF3's lifecycle ("EKF3 IMU0 tilt alignment complete", "origin set",
    "is using GPS", ...), "AHRS: EKF3 active" and "Field Elevation Set: 584m", in time order."""
    out: list[tuple[int, str]] = []
    for row in rows:
        t, kind, mask = int(row[AP.TXT_TIME]), int(row[AP.TXT_KIND]), int(row[AP.TXT_MASK])
        if kind in (AP.KIND_ARM, AP.KIND_PREARM):
            prefix = "Arm: " if kind == AP.KIND_ARM else "PreArm: "
            for bit, text in ARM_CHECK_TEXTS.items():
                if mask & bit:
                    out.append((t, prefix + (text if isinstance(text, str) else text(row))))
        elif kind == AP.KIND_EKF and mask in _EKF_TEXTS:
            out.append((t, _EKF_TEXTS[mask].format(imu=int(row[AP.A_LANE]),
                                                   mag=int(row[AP.A_MAG_FIELD]))))
        elif kind == AP.KIND_AHRS_ACTIVE:
            out.append((t, "AHRS: EKF3 active"))
        elif kind == AP.KIND_FIELD_ELEV:
            out.append((t, f"Field Elevation Set: {row[AP.A_MAG_FIELD]:.0f}m"))
    return sorted(out, key=lambda line: line[0])


#: AP_GPS's messages when it finds the simulated u-blox (SITL's GPS 1 at 230400 baud)
GPS_PROBE_TEXT = "GPS 1: probing for u-blox at 230400 baud"
GPS_DETECT_TEXT = "GPS 1: detected u-blox"


def gps_detected(tables: Tables) -> list[tuple[int, str]]:
    """AP_GPS finding the receiver: "GPS 1: probing for u-blox at 230400 baud" 20 ms before the
    first GPS row, "GPS 1: detected u-blox" at it (every reference log: 9.809 s and 9.829 s)."""
    gps = tables.get("GPS")
    if gps is None or not len(gps):
        return []
    t0 = int(gps["TimeUS"].iloc[0])
    return [(max(t0 - 20_000, 0), GPS_PROBE_TEXT), (t0, GPS_DETECT_TEXT)]


STATE_TEXTS = (*STATE_TEXTS, gps_detected)
