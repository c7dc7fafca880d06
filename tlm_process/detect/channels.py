"""The whole-log detector's input: the evidence a log carries, as channels on one time grid.

A *channel* is one signal the detector reads: a column of a log table (``IMU0.GyrX``, IMU
instance 0's roll rate), or a quantity derived from a few columns of one table (``RATE.RErr``,
the roll-rate error ``R - RDes``). Channels are chosen to be *universal*: they describe how the
vehicle flies and what its sensors and estimator say, never where it flies (no latitude,
longitude, altitude above sea level, heading) or when (no GPS time, no cumulative counters).

Every channel is sampled on one grid of :data:`GRID_HZ` from arming to disarming: the value at
grid time ``t`` is the table's last row at or before ``t`` (``pandas.merge_asof`` backward),
so every sample, and every statistic built on them (:mod:`.features`), uses only rows up to its
time: the detector is causal and could run on board. Before a table's first row a channel is
NaN (XGBoost sends missing values down a learned branch).

Three kinds (how :mod:`.features` summarises them):

* ``level``: the value itself matters (a rate, an innovation, a test ratio, a throttle);
* ``delta``: only its changes matter (the magnetic field strength depends on where on earth
  the vehicle is; how fast it changes does not);
* ``state``: a step signal from events (the flight mode, the last error code of an ERR
  subsystem); absent events mean "none yet" (a log has no ERR table until the first error).

Real logs differ in what they log: Copter 4.0 names its EKF messages ``NKF*`` (read as their
``XKF*`` twins: same columns), logs before 4.2 lack ``RATE.AOutSlew``, a one-IMU board has no
IMU instance 1. :func:`needed_columns` says which log columns each channel needs so ``tlm detect``
(:mod:`.run`) can name what a log lacks.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from tlm_sim import ardupilot as AP

__all__ = ["CHANNELS", "ERR_SUBSYSTEMS", "GRID_HZ", "Channel", "align", "armed_grid",
           "channel_table", "drop_channels", "needed_columns", "source_tables"]

#: Grid rate of the aligned channels [Hz] (RATE, ATT, CTUN and the EKF messages are logged
#: at 10 Hz; IMU at 25 Hz is sampled, its faster content reaches the detector through VIBE).
GRID_HZ: float = 10.0

#: Metres per degree of latitude (WGS-84 mean radius 6371008.8 m x pi / 180).
_M_PER_DEG = 111195.08

#: ERR subsystems the detector follows (ArduPilot's LogErrorSubsystem): 2 radio, 3 compass,
#: 5 radio failsafe, 6 battery failsafe, 7 GPS failsafe, 11 GPS, 12 crash check, 16 EKF
#: check, 17 EKF/inertial-nav failsafe, 18 baro, 24 EKF primary lane, 25 thrust loss,
#: 29 vibration failsafe.
ERR_SUBSYSTEMS: tuple[int, ...] = (
    AP.ERR_RADIO, AP.ERR_COMPASS, AP.ERR_FAILSAFE_RADIO, AP.ERR_FAILSAFE_BATT,
    AP.ERR_FAILSAFE_GPS, AP.ERR_GPS, AP.ERR_CRASH_CHECK, AP.ERR_EKFCHECK,
    AP.ERR_FAILSAFE_EKFINAV, AP.ERR_BARO, AP.ERR_EKF_PRIMARY, AP.ERR_THRUST_LOSS_CHECK,
    AP.ERR_FAILSAFE_VIBE)


@dataclass(frozen=True)
class Channel:
    """One input signal: ``name`` (``GROUP.QUANTITY``; the group is the table, with the
    instance or EKF lane appended: ``IMU1``, ``XKF4L1``), ``kind`` ("level", "delta",
    "state"), ``unit`` and ``needs``: the log columns it is computed from, as
    ``TABLE.COLUMN`` (``TABLE`` alone for event tables whose absence means "no events")."""

    name: str
    kind: str
    unit: str
    needs: tuple[str, ...]

    @property
    def group(self) -> str:
        return self.name.split(".", 1)[0]


# --------------------------------------------------------------------------------------------
# Sources: per table, the channels and how to compute them from the table's rows
# --------------------------------------------------------------------------------------------

Rows = pd.DataFrame
_Compute = Callable[[Rows, Mapping[str, float]], dict[str, np.ndarray]]


@dataclass(frozen=True)
class _Source:
    """A table (one instance or lane of it): ``select`` (column, value) picks the rows,
    ``compute`` returns the channel values per row (name -> array)."""

    table: str
    group: str
    select: tuple[str, int] | None
    channels: tuple[Channel, ...]
    compute: _Compute
    event: bool = False  # absent table = no events yet (ERR, MODE)


def _col(df: Rows, c: str) -> np.ndarray:
    return df[c].to_numpy(np.float64)


def _dt_s(df: Rows) -> np.ndarray:
    """Seconds since the previous row (the first row: NaN)."""
    t = df["TimeUS"].to_numpy(np.float64) * 1e-6
    d = np.diff(t, prepend=np.nan)
    d[d <= 0] = np.nan
    return d


def _plain(cols: Sequence[str]) -> _Compute:
    return lambda df, _p: {c: _col(df, c) for c in cols}


def _gps(df: Rows, _p: Mapping[str, float]) -> dict[str, np.ndarray]:
    out = {c: _col(df, c) for c in ("Status", "NSats", "HDop", "Spd", "VZ")}
    dt = _dt_s(df)
    lat, lng, alt = _col(df, "Lat"), _col(df, "Lng"), _col(df, "Alt")
    dn = np.diff(lat, prepend=np.nan) * _M_PER_DEG
    de = np.diff(lng, prepend=np.nan) * _M_PER_DEG * np.cos(np.radians(lat))
    out["Jump"] = np.hypot(dn, de) / dt - out["Spd"]  # position step speed minus Spd [m/s]
    out["AltRate"] = np.diff(alt, prepend=np.nan) / dt
    crs = _col(df, "GCrs")
    turn = (np.diff(crs, prepend=np.nan) + 180.0) % 360.0 - 180.0
    out["Turn"] = np.abs(turn) / dt
    return out


def _imu(df: Rows, _p: Mapping[str, float]) -> dict[str, np.ndarray]:
    return {c: _col(df, c) for c in ("GyrX", "GyrY", "GyrZ", "AccX", "AccY", "AccZ",
                                     "GH", "AH")}


def _vibe(df: Rows, _p: Mapping[str, float]) -> dict[str, np.ndarray]:
    out = {c: _col(df, c) for c in ("VibeX", "VibeY", "VibeZ")}
    out["ClipRate"] = np.diff(_col(df, "Clip"), prepend=np.nan) / _dt_s(df)
    return out


def _rate(df: Rows, _p: Mapping[str, float]) -> dict[str, np.ndarray]:
    out = {c: _col(df, c) for c in ("RDes", "R", "ROut", "PDes", "P", "POut", "YDes", "Y",
                                    "YOut", "ADes", "A", "AOut")}
    for ax in ("R", "P", "Y", "A"):
        out[f"{ax}Err"] = out[ax] - out[f"{ax}Des"]
    return out


def _rate_slew(df: Rows, _p: Mapping[str, float]) -> dict[str, np.ndarray]:
    return {"AOutSlew": _col(df, "AOutSlew")}


def _att(df: Rows, _p: Mapping[str, float]) -> dict[str, np.ndarray]:
    roll, pitch = _col(df, "Roll"), _col(df, "Pitch")
    yaw_err = (_col(df, "DesYaw") - _col(df, "Yaw") + 180.0) % 360.0 - 180.0
    return {"Roll": roll, "Pitch": pitch, "RollErr": _col(df, "DesRoll") - roll,
            "PitchErr": _col(df, "DesPitch") - pitch, "YawErr": yaw_err}


def _baro(df: Rows, _p: Mapping[str, float]) -> dict[str, np.ndarray]:
    return {c: _col(df, c) for c in ("Alt", "CRt", "H")}


def _mag(df: Rows, _p: Mapping[str, float]) -> dict[str, np.ndarray]:
    norm = np.sqrt(_col(df, "MagX") ** 2 + _col(df, "MagY") ** 2 + _col(df, "MagZ") ** 2)
    return {"Norm": norm, "Health": _col(df, "Health")}


def _bat(df: Rows, _p: Mapping[str, float]) -> dict[str, np.ndarray]:
    """Voltage per cell: the cell count is the one a full pack's first reading implies (4.2 V
    a cell, rounded up), so 3S and 6S vehicles read alike."""
    volt = _col(df, "Volt")
    first = volt[np.isfinite(volt) & (volt > 0.5)]
    cells = max(1.0, float(np.ceil(first[0] / 4.25))) if len(first) else np.nan
    return {"VoltCell": volt / cells}


def _xkf3(df: Rows, _p: Mapping[str, float]) -> dict[str, np.ndarray]:
    """The EKF's innovations without a direction that depends on the route or the place:
    horizontal velocity and position innovations as magnitudes (IVH, IPH), vertical ones
    signed (IVD, IPD: down), the magnetometer innovation's magnitude (IMag) and the yaw
    innovation's size (IYAW)."""
    return {"IVH": np.hypot(_col(df, "IVN"), _col(df, "IVE")), "IVD": _col(df, "IVD"),
            "IPH": np.hypot(_col(df, "IPN"), _col(df, "IPE")), "IPD": _col(df, "IPD"),
            "IMag": np.sqrt(_col(df, "IMX") ** 2 + _col(df, "IMY") ** 2
                            + _col(df, "IMZ") ** 2),
            "IYAW": np.abs(_col(df, "IYAW"))}


def _xkf4(df: Rows, _p: Mapping[str, float]) -> dict[str, np.ndarray]:
    """Test ratios of velocity, position, height and magnetometer (SV, SP, SH, SM), the
    primary lane (PI) and the EKF's timeout bits as 0/1 (TS bit 0 position, 1 velocity,
    2 height, 3 magnetometer). Not the airspeed and drag timeout bits (4, 5: a copter without
    an airspeed sensor sets them always in SITL, never in tlm), nor the fault, solution and
    GPS-check status words (FS, SS, GPS) or SVT and errRP: tlm's EKF does not produce them
    (constant 0), so a model trained on tlm could only learn them as noise."""
    ts = df["TS"].to_numpy(np.int64) if "TS" in df.columns else np.zeros(len(df), np.int64)
    out = {c: _col(df, c) for c in ("SV", "SP", "SH", "SM", "PI")}
    for bit, name in enumerate(("Pos", "Vel", "Hgt", "Mag")):
        out[f"TS{name}"] = ((ts >> bit) & 1).astype(np.float64)
    return out


def _rcou(df: Rows, p: Mapping[str, float]) -> dict[str, np.ndarray]:
    """Motor outputs as fractions of the PWM range (MOT_PWM_MIN..MAX,
    :func:`tlm_process.logread.pwm_range`; the motors: :func:`~tlm_process.logread.motor_columns`
    by FRAME_CLASS): their mean, their spread, and the largest excess and deficit of one
    motor against the mean (a lost or weak motor: the controller drives it up, or its
    opposite down)."""
    from tlm_process.logread import motor_columns, pwm_range

    lo, hi = pwm_range(dict(p))
    cols = motor_columns(df, dict(p))
    m = (df[cols].to_numpy(np.float64) - lo) / (hi - lo)
    mean = m.mean(axis=1)
    dev = m - mean[:, None]
    return {"Mean": mean, "Spread": m.max(axis=1) - m.min(axis=1),
            "MaxDev": dev.max(axis=1), "MinDev": dev.min(axis=1)}


def _rcin(df: Rows, _p: Mapping[str, float]) -> dict[str, np.ndarray]:
    return {c: _col(df, c) for c in ("C1", "C2", "C3", "C4")}


def _ctun(df: Rows, _p: Mapping[str, float]) -> dict[str, np.ndarray]:
    """Throttle out, and its excess over the learned hover throttle (ThH itself is the
    vehicle's, not the flight's: a heavier copter hovers higher), altitude and climb-rate
    errors, climb rate."""
    alt, crt, tho = _col(df, "Alt"), _col(df, "CRt"), _col(df, "ThO")
    return {"ThO": tho, "ThOverHover": tho - _col(df, "ThH"),
            "AltErr": _col(df, "DAlt") - alt, "CRt": crt, "CRtErr": _col(df, "DCRt") - crt}


def _mode(df: Rows, _p: Mapping[str, float]) -> dict[str, np.ndarray]:
    """Mode number and reason (NaN where the firmware logs none: Rsn is 3.5 and later)."""
    nan = np.full(len(df), np.nan)
    return {c: _col(df, c) if c in df.columns else nan for c in ("ModeNum", "Rsn")}


def _ch(group: str, specs: Sequence[tuple[str, str, str]], needs: Mapping[str, Sequence[str]],
        table: str) -> tuple[Channel, ...]:
    """Channels of ``group``: (quantity, kind, unit) each; ``needs``: quantity -> source
    columns (default: the quantity itself)."""
    return tuple(Channel(f"{group}.{q}", kind, unit,
                         tuple(f"{table}.{c}" for c in needs.get(q, (q,))))
                 for q, kind, unit in specs)


def _sources() -> tuple[_Source, ...]:
    L, D, S = "level", "delta", "state"
    src: list[_Source] = []
    src.append(_Source("GPS", "GPS", ("I", 0), _ch("GPS", [
        ("Status", L, "fix type"), ("NSats", L, "satellites"), ("HDop", L, "-"),
        ("Spd", L, "m/s"), ("VZ", L, "m/s"), ("Jump", L, "m/s"), ("AltRate", L, "m/s"),
        ("Turn", L, "deg/s")], {"Jump": ("Lat", "Lng", "Spd"), "AltRate": ("Alt",),
                                "Turn": ("GCrs",)}, "GPS"), _gps))
    src.append(_Source("GPA", "GPA", ("I", 0), _ch("GPA", [
        ("HAcc", L, "m"), ("VAcc", L, "m"), ("SAcc", L, "m/s")], {}, "GPA"),
        _plain(("HAcc", "VAcc", "SAcc"))))
    for i in (0, 1):
        src.append(_Source("IMU", f"IMU{i}", ("I", i), _ch(f"IMU{i}", [
            ("GyrX", L, "rad/s"), ("GyrY", L, "rad/s"), ("GyrZ", L, "rad/s"),
            ("AccX", L, "m/s/s"), ("AccY", L, "m/s/s"), ("AccZ", L, "m/s/s"),
            ("GH", L, "healthy"), ("AH", L, "healthy")], {}, "IMU"), _imu))
        src.append(_Source("VIBE", f"VIBE{i}", ("IMU", i), _ch(f"VIBE{i}", [
            ("VibeX", L, "m/s/s"), ("VibeY", L, "m/s/s"), ("VibeZ", L, "m/s/s"),
            ("ClipRate", L, "clips/s")], {"ClipRate": ("Clip",)}, "VIBE"), _vibe))
    rate_q = [(q, L, "deg/s") for q in ("RDes", "R", "ROut", "PDes", "P", "POut", "YDes", "Y",
                                        "YOut")]
    rate_q += [("ADes", L, "m/s/s"), ("A", L, "m/s/s"), ("AOut", L, "-")]
    rate_q += [(f"{a}Err", L, "deg/s" if a != "A" else "m/s/s") for a in "RPYA"]
    src.append(_Source("RATE", "RATE", None, _ch(
        "RATE", rate_q, {f"{a}Err": (a, f"{a}Des") for a in "RPYA"}, "RATE"), _rate))
    src.append(_Source("RATE", "RATE", None, _ch("RATE", [("AOutSlew", L, "-")], {}, "RATE"),
                       _rate_slew))
    src.append(_Source("ATT", "ATT", None, _ch("ATT", [
        ("Roll", L, "deg"), ("Pitch", L, "deg"), ("RollErr", L, "deg"),
        ("PitchErr", L, "deg"), ("YawErr", L, "deg")],
        {"RollErr": ("DesRoll", "Roll"), "PitchErr": ("DesPitch", "Pitch"),
         "YawErr": ("DesYaw", "Yaw")}, "ATT"), _att))
    for i in (0, 1):
        src.append(_Source("BARO", f"BARO{i}", ("I", i), _ch(f"BARO{i}", [
            ("Alt", D, "m"), ("CRt", L, "m/s"), ("H", L, "healthy")], {}, "BARO"), _baro))
        src.append(_Source("MAG", f"MAG{i}", ("I", i), _ch(f"MAG{i}", [
            ("Norm", D, "mGauss"), ("Health", L, "healthy")],
            {"Norm": ("MagX", "MagY", "MagZ")}, "MAG"), _mag))
    src.append(_Source("BAT", "BAT", ("Inst", 0), _ch("BAT", [("VoltCell", L, "V")],
                                                      {"VoltCell": ("Volt",)}, "BAT"), _bat))
    src.append(_Source("XKF3", "XKF3L0", ("C", 0), _ch("XKF3L0", [
        ("IVH", L, "m/s"), ("IVD", L, "m/s"), ("IPH", L, "m"), ("IPD", L, "m"),
        ("IMag", L, "mGauss"), ("IYAW", L, "deg")],
        {"IVH": ("IVN", "IVE"), "IPH": ("IPN", "IPE"), "IMag": ("IMX", "IMY", "IMZ")},
        "XKF3"), _xkf3))
    src.append(_Source("XKF4", "XKF4L0", ("C", 0), _ch("XKF4L0", [
        ("SV", L, "-"), ("SP", L, "-"), ("SH", L, "-"), ("SM", L, "-"), ("PI", L, "lane"),
        ("TSPos", L, "timeout"), ("TSVel", L, "timeout"), ("TSHgt", L, "timeout"),
        ("TSMag", L, "timeout")], {f"TS{b}": ("TS",) for b in ("Pos", "Vel", "Hgt", "Mag")},
        "XKF4"), _xkf4))
    src.append(_Source("XKF4", "XKF4L1", ("C", 1), _ch("XKF4L1", [
        (q, L, "-") for q in ("SV", "SP", "SH", "SM")], {}, "XKF4"),
        _plain(("SV", "SP", "SH", "SM"))))
    src.append(_Source("XKF1", "XKF1L0", ("C", 0), _ch("XKF1L0", [
        ("GX", L, "deg/s"), ("GY", L, "deg/s"), ("GZ", L, "deg/s"), ("VD", L, "m/s")],
        {}, "XKF1"), _plain(("GX", "GY", "GZ", "VD"))))
    src.append(_Source("RCOU", "RCOU", None, _ch("RCOU", [
        ("Mean", L, "-"), ("Spread", L, "-"), ("MaxDev", L, "-"), ("MinDev", L, "-")],
        {q: ("C1", "C2", "C3", "C4") for q in ("Mean", "Spread", "MaxDev", "MinDev")},
        "RCOU"), _rcou))
    src.append(_Source("RCIN", "RCIN", None, _ch("RCIN", [
        (c, L, "us") for c in ("C1", "C2", "C3", "C4")], {}, "RCIN"), _rcin))
    src.append(_Source("CTUN", "CTUN", None, _ch("CTUN", [
        ("ThO", L, "-"), ("ThOverHover", L, "-"), ("AltErr", L, "m"), ("CRt", L, "cm/s"),
        ("CRtErr", L, "cm/s")], {"ThOverHover": ("ThO", "ThH"), "AltErr": ("DAlt", "Alt"),
                                 "CRtErr": ("DCRt", "CRt")},
        "CTUN"), _ctun))
    src.append(_Source("MODE", "MODE", None, (
        Channel("MODE.ModeNum", S, "mode", ("MODE",)),
        Channel("MODE.Rsn", S, "reason", ("MODE",))), _mode, event=True))
    src.append(_Source("ERR", "ERR", None, tuple(
        Channel(f"ERR.S{s}", S, "ECode", ("ERR",)) for s in ERR_SUBSYSTEMS), _err,
        event=True))
    return tuple(src)


def _err(df: Rows, _p: Mapping[str, float]) -> dict[str, np.ndarray]:
    """Per followed subsystem, its last error code (0 before its first ERR row): a step."""
    if not {"Subsys", "ECode"} <= set(df.columns):
        return {f"S{s}": np.zeros(len(df)) for s in ERR_SUBSYSTEMS}
    sub, code = _col(df, "Subsys"), _col(df, "ECode")
    out = {}
    for s in ERR_SUBSYSTEMS:
        v = np.where(sub == s, code, np.nan)
        out[f"S{s}"] = pd.Series(v).ffill().fillna(0.0).to_numpy()
    return out


_SOURCES = _sources()
#: Every channel, in the detector's column order.
CHANNELS: tuple[Channel, ...] = tuple(c for s in _SOURCES for c in s.channels)
_BY_NAME = {c.name: c for c in CHANNELS}


def source_tables() -> tuple[str, ...]:
    """The log tables the channels read, plus EV and ARM (the armed span: arming_time_us
    reads them, and RCOU, which is a channel source)."""
    return tuple(dict.fromkeys([s.table for s in _SOURCES] + ["EV", "ARM"]))


def drop_channels(drop: Sequence[str]) -> tuple[list[str], list[str]]:
    """(channels kept, entries of ``drop`` that match nothing). A ``drop`` entry removes
    the channels it names: a channel (``IMU1.GyrX``), a group (``IMU1``, ``XKF4L1``), a table
    (``XKF3``: every lane) or a log column (``RATE.AOutSlew``, ``GPS.GCrs``: every channel
    computed from it)."""
    kept: list[str] = []
    hit = dict.fromkeys(drop, False)
    for c in CHANNELS:
        gone = False
        for d in drop:
            if (d == c.name or d == c.group or d in c.needs
                    or any(n.split(".", 1)[0] == d for n in c.needs)):
                hit[d] = gone = True
        if not gone:
            kept.append(c.name)
    unknown = [d for d, h in hit.items() if not h]
    return kept, unknown


def needed_columns(channels: Sequence[str]) -> dict[str, list[str]]:
    """Log column (``TABLE.COLUMN``, or ``TABLE`` for an event table) -> the channels among
    ``channels`` that need it."""
    out: dict[str, list[str]] = {}
    for name in channels:
        for n in _BY_NAME[name].needs:
            out.setdefault(n, []).append(name)
    return out


def _lacking(src: _Source, df: pd.DataFrame | None, wanted: set[str]) -> list[str]:
    """The columns of ``src``'s ``wanted`` channels that ``df`` lacks (all, without the table
    or its instance); the columns of channels not wanted (dropped from the model) do not
    count."""
    need = dict.fromkeys(n for c in src.channels if c.name in wanted for n in c.needs)
    if src.event:
        return []
    if df is None or not len(df):
        return list(need)
    if src.select is not None:
        col, val = src.select
        if col in df.columns:
            if not (df[col] == val).any():
                return list(need)
        elif val != 0:
            return list(need)
    return [n for n in need if n.split(".", 1)[1] not in df.columns]


def _instance_rows(df: pd.DataFrame, select: tuple[str, int] | None) -> pd.DataFrame:
    if select is None:
        return df
    col, val = select
    if col not in df.columns:  # a table without an instance column is instance 0
        return df if val == 0 else df.iloc[:0]
    return df[df[col] == val]


def armed_grid(t0_us: int, t1_us: int, hz: float = GRID_HZ) -> np.ndarray:
    """Grid times [µs since boot] from ``t0_us`` to ``t1_us`` (inclusive of t0) every
    1/``hz`` s."""
    step = 1e6 / hz
    n = max(1, int((t1_us - t0_us) // step) + 1)
    return (t0_us + np.arange(n) * step).astype(np.int64)


def channel_table(tables: Mapping[str, pd.DataFrame], params: Mapping[str, float],
                  channels: Sequence[str], grid_us: np.ndarray
                  ) -> tuple[pd.DataFrame, list[str]]:
    """The ``channels`` of a log on ``grid_us`` (µs since boot): a DataFrame with ``TimeUS``
    and one float column per channel, and the log columns (``TABLE.COLUMN``) the log lacks
    for them (those channels are NaN throughout)."""
    want = set(channels)
    grid = pd.DataFrame({"TimeUS": np.asarray(grid_us, dtype=np.int64)})
    cols: dict[str, np.ndarray] = {}
    lacking: list[str] = []
    for src in _SOURCES:
        names = [c.name for c in src.channels if c.name in want]
        if not names:
            continue
        df = tables.get(src.table)
        miss = _lacking(src, df, want)
        if miss:
            lacking += [m for m in miss if m not in lacking]
            for n in names:
                cols[n] = np.full(len(grid), np.nan)
            continue
        rows = _instance_rows(df, src.select) if df is not None else None
        if rows is None or not len(rows):  # an event table with no rows: nothing happened
            vals = _event_defaults(src, len(grid))
            cols.update({n: vals[n] for n in names})
            continue
        rows = rows.sort_values("TimeUS", kind="stable")
        absent = {n.partition(".")[2] for c in src.channels for n in c.needs} - set(
            rows.columns) - {""}
        if absent:  # columns only dropped channels read: NaN, the source computes them all
            rows = rows.assign(**dict.fromkeys(sorted(absent), np.nan))
        computed = src.compute(rows.reset_index(drop=True), params)
        frame = pd.DataFrame({f"{src.group}.{q}": v for q, v in computed.items()})
        frame.insert(0, "TimeUS", rows["TimeUS"].to_numpy(np.int64))
        frame = frame.drop_duplicates("TimeUS", keep="last")
        merged = pd.merge_asof(grid, frame, on="TimeUS", direction="backward")
        defaults = _event_defaults(src, len(grid)) if src.event else {}
        for n in names:
            v = merged[n].to_numpy(np.float64)
            if n in defaults:
                v = np.where(np.isnan(v), defaults[n], v)
            cols[n] = v
    out = pd.DataFrame({n: cols[n] for n in channels})
    out.insert(0, "TimeUS", grid["TimeUS"].to_numpy())
    return out, lacking


def _event_defaults(src: _Source, n: int) -> dict[str, np.ndarray]:
    """Values of an event source's channels before its first row: ERR codes 0 (no error);
    the mode NaN (unknown)."""
    if src.table == "ERR":
        return {c.name: np.zeros(n) for c in src.channels}
    return {c.name: np.full(n, np.nan) for c in src.channels}


def align(tables: Mapping[str, pd.DataFrame]) -> dict[str, pd.DataFrame]:
    """The tables with Copter 4.0's EKF2 messages read as their EKF3 twins (``NKF1`` ->
    ``XKF1``, ... same columns) where the log has no ``XKF*``, and Copter 3.x's RC channel
    columns (``Ch1``, 3.1's ``Chan1``) named as 4.x names them (``C1``)."""
    out = dict(tables)
    for k in ("1", "3", "4"):
        if f"XKF{k}" not in out and f"NKF{k}" in out:
            out[f"XKF{k}"] = out[f"NKF{k}"]
    for name in ("RCOU", "RCIN"):
        df = out.get(name)
        if df is not None and "C1" not in df.columns:
            for prefix in ("Ch", "Chan"):
                if f"{prefix}1" in df.columns:
                    ren = {c: "C" + c[len(prefix):] for c in df.columns
                           if c.startswith(prefix) and c[len(prefix):].isdigit()}
                    out[name] = df.rename(columns=ren)
                    break
    return out
