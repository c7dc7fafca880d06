"""ArduPilot DataFlash message schemas (layouts of ArduCopter 4.7-dev) and their value semantics.

Every message tlm reads or writes is described once here, as a literal table: name, format
characters, column names, FMTU unit and multiplier ids, instance field, default logging rate.
The layouts equal the FMT/FMTU messages of the reference SITL logs (ArduCopter V4.7.0-dev,
commit 2598e9d4); ``tests/test_flightlog.py`` checks that against
``shared/reference/sitl/normal_s11.bin``.

Value convention of tlm tables ("DataFrame units")
--------------------------------------------------
A value in a tlm table (DataFrame, CSV, Parquet, simulator log buffer) is what pymavlink shows
for that field: the raw stored number times the *reader scale* of its format character,
``FORMAT_CHARS[c].reader_scale``:

* ``c C e E`` (int16/uint16/int32/uint32 holding ×100): value = raw / 100, e.g. GPS.HDop 1.21,
  GPS.Alt 584.12 m, XKF1.Roll in degrees, BARO.Temp in degC.
* ``L`` (int32 lat/lon ×1e7): value = raw / 1e7, i.e. degrees.
* every other character: value = raw (floats as stored, integers as integers).

FMTU multipliers describe the *raw* number, so the factor that takes a table value to the unit
named by ``UNITS[unit_id]`` is ``MULTS[mult_id] / reader_scale`` (``MessageSchema.si_factor``).
It is 1 for most fields (HDop: 1e-2 / 1e-2; Lat: 1e-7 / 1e-7; floats with mult ``0``) but not
for all: TimeUS (µs, factor 1e-6 → s), GPS.GMS (ms → s), CTUN.CRt (int16 cm/s → m/s, 0.01),
MAG.MagX (mGauss → Gauss, 1e-3), RATE.ADes/A (float cm/s² → m/s², 0.01), BAT.CurrTot
(mAh → Ah, 1e-3). Multiplier ``-`` means "no multiplier" (enums, counts, strings, or values
ArduPilot left unannotated): ``si_factor`` is None and the value is used as is.

Quantisation (what a value can be)
----------------------------------
A table value is always exactly representable by its format character (see
``tlm_sim.flightlog.quantise``): ``f`` → a float32 value, ``c/C/e/E`` → an integer / 100,
``L`` → an integer / 1e7, integers → the integer type's range. Dtypes of table columns are
given by ``FORMAT_CHARS[c].dtype`` (floats as float64).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "FormatChar",
    "FORMAT_CHARS",
    "UNITS",
    "MULTS",
    "MessageSchema",
    "SCHEMAS",
    "LOGGED_MESSAGES",
    "EVENT_MESSAGES",
    "schema_from_fmt",
]


@dataclass(frozen=True)
class FormatChar:
    """One DataFrame/DataFlash format character.

    Attributes:
        char: the ArduPilot format character.
        struct: Python ``struct`` code of the stored (raw) value, little-endian, packed.
        size: bytes in the .bin payload.
        dtype: numpy dtype of the tlm table column (``object`` for strings and arrays).
        reader_scale: factor from raw stored value to table value (pymavlink's scaling).
        lo, hi: range of the raw stored integer (None for floats and strings).
        kind: "int", "scaled" (integer raw, float value), "float", "str" or "array".
    """

    char: str
    struct: str
    size: int
    dtype: np.dtype
    reader_scale: float
    lo: int | None
    hi: int | None
    kind: str


def _fc(char: str, st: str, dtype: str, scale: float, kind: str) -> FormatChar:
    size = struct.calcsize("<" + st)
    lo = hi = None
    if kind in ("int", "scaled"):
        info = np.iinfo(np.dtype("<" + st if st not in ("b", "B") else st))
        lo, hi = int(info.min), int(info.max)
    return FormatChar(char, st, size, np.dtype(dtype), scale, lo, hi, kind)


#: Format characters (``libraries/AP_Logger/LogStructure.h``; reader scaling as pymavlink's
#: ``DFReader.FORMAT_TO_STRUCT``). ``Q`` (uint64) is held as int64 in tables: TimeUS stays far
#: below 2**63. ``M`` (flight mode) is uint8 (pymavlink unpacks it signed; modes are < 128).
FORMAT_CHARS: dict[str, FormatChar] = {
    c.char: c
    for c in (
        _fc("b", "b", "int8", 1.0, "int"),
        _fc("B", "B", "uint8", 1.0, "int"),
        _fc("h", "h", "int16", 1.0, "int"),
        _fc("H", "H", "uint16", 1.0, "int"),
        _fc("i", "i", "int32", 1.0, "int"),
        _fc("I", "I", "uint32", 1.0, "int"),
        _fc("q", "q", "int64", 1.0, "int"),
        _fc("Q", "Q", "int64", 1.0, "int"),
        _fc("M", "B", "uint8", 1.0, "int"),
        _fc("f", "f", "float64", 1.0, "float"),
        _fc("d", "d", "float64", 1.0, "float"),
        _fc("g", "e", "float64", 1.0, "float"),
        _fc("c", "h", "float64", 0.01, "scaled"),
        _fc("C", "H", "float64", 0.01, "scaled"),
        _fc("e", "i", "float64", 0.01, "scaled"),
        _fc("E", "I", "float64", 0.01, "scaled"),
        _fc("L", "i", "float64", 1e-7, "scaled"),
        _fc("n", "4s", "object", 1.0, "str"),
        _fc("N", "16s", "object", 1.0, "str"),
        _fc("Z", "64s", "object", 1.0, "str"),
        _fc("a", "64s", "object", 1.0, "array"),
    )
}
# Q is uint64 on disk but int64 in tables: keep the table range inside int64.
FORMAT_CHARS["Q"] = FormatChar("Q", "Q", 8, np.dtype("int64"), 1.0, 0, 2**63 - 1, "int")

#: FMTU unit ids → unit label (``log_Units``; labels as the UNIT messages of 4.7-dev write them).
UNITS: dict[str, str] = {
    "-": "",
    "?": "UNKNOWN",
    "A": "A",
    "a": "Ah",
    "d": "deg",
    "b": "B",
    "B": "B/s",
    "k": "deg/s",
    "D": "deglatitude",
    "e": "deg/s/s",
    "E": "rad/s",
    "G": "Gauss",
    "h": "degheading",
    "i": "A.s",
    "J": "W.s",
    "l": "l",
    "L": "rad/s/s",
    "m": "m",
    "n": "m/s",
    "o": "m/s/s",
    "O": "degC",
    "%": "%",
    "S": "satellites",
    "s": "s",
    "t": "N.m",
    "q": "rpm",
    "r": "rad",
    "U": "deglongitude",
    "u": "ppm",
    "v": "V",
    "P": "Pa",
    "w": "Ohm",
    "W": "Watt",
    "X": "W.h",
    "y": "l/s",
    "Y": "us",
    "z": "Hz",
    "#": "instance",
}

#: FMTU multiplier ids → factor applied to the *raw stored* value (``log_Multipliers``).
#: ``-`` = 0 means "no multiplier"; ``?`` = 1 means "float, use as is".
MULTS: dict[str, float] = {
    "-": 0.0,
    "?": 1.0,
    "2": 1e2,
    "1": 1e1,
    "0": 1.0,
    "A": 1e-1,
    "B": 1e-2,
    "C": 1e-3,
    "D": 1e-4,
    "E": 1e-5,
    "F": 1e-6,
    "G": 1e-7,
    "I": 1e-9,
    "!": 3.6,
    "/": 3600.0,
}


@dataclass(frozen=True)
class MessageSchema:
    """Layout and semantics of one DataFlash message type.

    Attributes:
        name: message name (≤ 4 characters), e.g. "GPS".
        fmt: ArduPilot format characters, one per field.
        columns: field names in ArduPilot order.
        units: FMTU unit ids, one character per field (see ``UNITS``).
        mults: FMTU multiplier ids, one character per field (see ``MULTS``).
        instance_field: the field carrying the ``#`` (instance) unit, e.g. "I", "IMU", "C";
            None for single-instance messages.
        rate_hz: default logging rate per instance with tlm's LOG_BITMASK (0 = on event).
        instances: instances logged by the reference SITL vehicle (2 IMUs, 3 compasses, ...).
        description: what the message holds.
    """

    name: str
    fmt: str
    columns: tuple[str, ...]
    units: str
    mults: str
    instance_field: str | None = None
    rate_hz: float = 0.0
    instances: int = 1
    description: str = ""
    _index: dict[str, int] = field(init=False, repr=False, compare=False, hash=False)

    def __post_init__(self) -> None:
        n = len(self.fmt)
        if not (len(self.columns) == len(self.units) == len(self.mults) == n):
            raise ValueError(f"{self.name}: fmt/columns/units/mults lengths differ")
        if len(set(self.columns)) != n:
            raise ValueError(f"{self.name}: duplicate column names")
        bad = [c for c in self.fmt if c not in FORMAT_CHARS]
        if bad:
            raise ValueError(f"{self.name}: unknown format characters {bad}")
        if self.instance_field is not None and self.instance_field not in self.columns:
            raise ValueError(f"{self.name}: instance field {self.instance_field!r} not a column")
        object.__setattr__(self, "_index", {c: i for i, c in enumerate(self.columns)})

    # --- layout -------------------------------------------------------------------------
    def struct_format(self) -> str:
        """``struct`` format of the payload (after the 3 header bytes), little-endian packed."""
        return "<" + "".join(FORMAT_CHARS[c].struct for c in self.fmt)

    @property
    def length(self) -> int:
        """Message length in bytes including the 3 header bytes (what FMT.Length holds)."""
        return 3 + sum(FORMAT_CHARS[c].size for c in self.fmt)

    def index(self, column: str) -> int:
        """Position of ``column`` in ``columns`` (and in a simulator log buffer row)."""
        try:
            return self._index[column]
        except KeyError:
            raise KeyError(f"{self.name} has no column {column!r}") from None

    def char(self, column: str) -> str:
        """Format character of ``column``."""
        return self.fmt[self.index(column)]

    @property
    def numeric_columns(self) -> tuple[str, ...]:
        """Columns that hold numbers (every field except n/N/Z strings and ``a`` arrays)."""
        return tuple(
            c for c, f in zip(self.columns, self.fmt, strict=True)
            if FORMAT_CHARS[f].kind not in ("str", "array")
        )

    @property
    def string_columns(self) -> tuple[str, ...]:
        """Columns of format n/N/Z (text)."""
        return tuple(
            c for c, f in zip(self.columns, self.fmt, strict=True) if FORMAT_CHARS[f].kind == "str"
        )

    @property
    def dtypes(self) -> dict[str, np.dtype]:
        """Table dtype of every column (``FORMAT_CHARS[c].dtype``)."""
        return {c: FORMAT_CHARS[f].dtype for c, f in zip(self.columns, self.fmt, strict=True)}

    # --- value semantics ----------------------------------------------------------------
    def scale(self, column: str) -> float:
        """Reader scale of ``column``: table value = raw stored value × scale.

        0.01 for c/C/e/E, 1e-7 for L, 1 otherwise (pymavlink's scaling).
        """
        return FORMAT_CHARS[self.char(column)].reader_scale

    def unit(self, column: str) -> str:
        """Unit label of ``column`` (after ``si_factor``), "" when dimensionless/unknown."""
        return UNITS[self.units[self.index(column)]]

    def multiplier(self, column: str) -> float:
        """FMTU multiplier of the *raw stored* value of ``column`` (0 = none)."""
        return MULTS[self.mults[self.index(column)]]

    def si_factor(self, column: str) -> float | None:
        """Factor taking a table value of ``column`` to ``unit(column)``.

        ``MULTS[mult] / scale(column)``, e.g. 1e-6 for TimeUS (µs → s), 1 for GPS.HDop and
        GPS.Lat, 0.01 for CTUN.CRt (cm/s → m/s). None where the multiplier id is ``-``.
        """
        m = self.mults[self.index(column)]
        if m == "-":
            return None
        return MULTS[m] / self.scale(column)

    def max_rows(self, duration_s: float, instances: int | None = None, margin: float = 1.1) -> int:
        """Rows to preallocate for ``duration_s`` of flight at ``rate_hz`` (≥ 64 for events)."""
        n = self.instances if instances is None else instances
        return max(64, int(np.ceil(duration_s * self.rate_hz * n * margin)) + 16)


def _schema(
    name: str,
    fmt: str,
    columns: str,
    units: str,
    mults: str,
    *,
    instance_field: str | None,
    rate_hz: float,
    instances: int,
    description: str,
) -> MessageSchema:
    return MessageSchema(
        name=name,
        fmt=fmt,
        columns=tuple(columns.split(",")),
        units=units,
        mults=mults,
        instance_field=instance_field,
        rate_hz=rate_hz,
        instances=instances,
        description=description,
    )


def schema_from_fmt(
    name: str, fmt: str, columns: str | tuple[str, ...], units: str | None = None,
    mults: str | None = None,
) -> MessageSchema:
    """Schema of a message described only by its FMT (and optionally FMTU) message."""
    cols = tuple(columns.split(",")) if isinstance(columns, str) else tuple(columns)
    units = units if units is not None else "-" * len(fmt)
    mults = mults if mults is not None else "-" * len(fmt)
    inst = cols[units.index("#")] if "#" in units else None
    return MessageSchema(name, fmt, cols, units, mults, instance_field=inst)


# Layouts of ArduCopter V4.7.0-dev (2598e9d4), from its LogStructure.h tables; rates with
# LOG_BITMASK 176126, LOG_FILE_RATEMAX 50, SIM_GPS1_HZ 5 (shared/reference/sitl/README.md).
_SCHEMA_LIST: tuple[MessageSchema, ...] = (
    # --- self-description ------------------------------------------------------------------
    _schema(
        "FMT", "BBnNZ",
        "Type,Length,Name,Format,Columns",
        "-b---", "-----",
        instance_field=None, rate_hz=0, instances=1,
        description="Message format: type id, length incl. header, name, format chars, columns.",
    ),
    _schema(
        "UNIT", "QbZ",
        "TimeUS,Id,Label",
        "s--", "F--",
        instance_field=None, rate_hz=0, instances=1,
        description="Unit id (character code) and its label; written once at log start.",
    ),
    _schema(
        "MULT", "Qbd",
        "TimeUS,Id,Mult",
        "s--", "F--",
        instance_field=None, rate_hz=0, instances=1,
        description="Multiplier id (character code) and its factor; written once at log start.",
    ),
    _schema(
        "FMTU", "QBNN",
        "TimeUS,FmtType,UnitIds,MultIds",
        "s---", "F---",
        instance_field=None, rate_hz=0, instances=1,
        description="Unit and multiplier ids (one char per field) of message type FmtType.",
    ),
    _schema(
        "PARM", "QNff",
        "TimeUS,Name,Value,Default",
        "s---", "F---",
        instance_field=None, rate_hz=0, instances=1,
        description="Parameter value (and default): all at log start, then one per change.",
    ),
    _schema(
        "MSG", "QZ",
        "TimeUS,Message",
        "s-", "F-",
        instance_field=None, rate_hz=0, instances=1,
        description="Text message (STATUSTEXT), e.g. firmware string, 'Radio Failsafe'.",
    ),
    _schema(
        "CMD", "QHHHffffLLfB",
        "TimeUS,CTot,CNum,CId,Prm1,Prm2,Prm3,Prm4,Lat,Lng,Alt,Frame",
        "s-------DUm-", "F-------GG0-",
        instance_field=None, rate_hz=0, instances=1,
        description="Mission item: total, index, MAV_CMD id, params 1-4, lat/lon (deg), "
        "alt (m), MAV_FRAME.",
    ),
    _schema(
        "VER", "QBHBBBBIZHBBII",
        "TimeUS,BT,BST,Maj,Min,Pat,FWT,GH,FWS,APJ,BU,FV,IMI,ICI",
        "s-------------", "F-------------",
        instance_field=None, rate_hz=0, instances=1,
        description="Firmware version: board type/subtype, major/minor/patch, firmware type, "
        "git hash, firmware string, APJ board id, build type (2 = Copter), filter version, "
        "IOMCU mcu id, IOMCU cpu id.",
    ),
    # --- events ----------------------------------------------------------------------------
    _schema(
        "MODE", "QMBB",
        "TimeUS,Mode,ModeNum,Rsn",
        "s---", "F---",
        instance_field=None, rate_hz=0, instances=1,
        description="Flight-mode change: mode number (twice) and ModeReason.",
    ),
    _schema(
        "EV", "QB",
        "TimeUS,Id",
        "s-", "F-",
        instance_field=None, rate_hz=0, instances=1,
        description="Event id (10 ARMED, 11 DISARMED, 18 LAND_COMPLETE, ...).",
    ),
    _schema(
        "ERR", "QBB",
        "TimeUS,Subsys,ECode",
        "s--", "F--",
        instance_field=None, rate_hz=0, instances=1,
        description="Error/failsafe: subsystem and code (e.g. 5/1 radio failsafe, 5/0 cleared).",
    ),
    # --- sensors ---------------------------------------------------------------------------
    _schema(
        "GPS", "QBBIHBcLLeffffB",
        "TimeUS,I,Status,GMS,GWk,NSats,HDop,Lat,Lng,Alt,Spd,GCrs,VZ,Yaw,U",
        "s#-s-S-DUmnhnh-", "F--C-0BGGB000--",
        instance_field="I", rate_hz=5, instances=1,
        description="GPS fix: status (6 locked in SITL, 1 no fix), GPS time (ms, week), sats, "
        "HDop, lat/lon (deg), alt AMSL (m), ground speed (m/s), course (deg), VZ (m/s, down+), "
        "yaw, in-use flag.",
    ),
    _schema(
        "GPA", "QBCCCCfBIHeHH",
        "TimeUS,I,VDop,HAcc,VAcc,SAcc,YAcc,VV,SMS,Delta,AEl,RTCMFU,RTCMFD",
        "s#-mmnd-ssm--", "F-BBBB0-CCB--",
        instance_field="I", rate_hz=5, instances=1,
        description="GPS accuracy: VDop, horizontal/vertical/speed/yaw accuracy, velocity-valid "
        "flag, sample time (ms), sample interval (ms), ellipsoid altitude (m), RTCM counters.",
    ),
    _schema(
        "IMU", "QBffffffIIfBBHH",
        "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,EG,EA,T,GH,AH,GHz,AHz",
        "s#EEEooo--O--zz", "F-000000-----00",
        instance_field="I", rate_hz=25, instances=2,
        description="Filtered IMU sample per instance: gyro (rad/s, FRD body), accel (m/s^2, FRD, "
        "about -9.8 on z at rest), error counts, temperature (degC), health, sensor rates (Hz).",
    ),
    _schema(
        "VIBE", "QBfffI",
        "TimeUS,IMU,VibeX,VibeY,VibeZ,Clip",
        "s#ooo-", "F-000-",
        instance_field="IMU", rate_hz=10, instances=2,
        description="Vibration per IMU: RMS of high-passed accel per axis (m/s^2), cumulative "
        "clip count.",
    ),
    _schema(
        "BARO", "QBfffcfIffBf",
        "TimeUS,I,Alt,AltAMSL,Press,Temp,CRt,SMS,Offset,GndTemp,H,CPress",
        "s#mmPOnsmO-P", "F-000B0C?0-0",
        instance_field="I", rate_hz=10, instances=2,
        description="Barometer per instance: altitude over ground calibration (m), AMSL (m), "
        "pressure (Pa), temperature (degC), climb rate (m/s), sample time (ms), offset (m), "
        "ground temperature, health, compensated pressure (Pa).",
    ),
    _schema(
        "MAG", "QBhhhhhhhhhBI",
        "TimeUS,I,MagX,MagY,MagZ,OfsX,OfsY,OfsZ,MOX,MOY,MOZ,Health,S",
        "s#GGGGGGGGG-s", "F-CCCCCCCCC-F",
        instance_field="I", rate_hz=10, instances=3,
        description="Compass per instance: field, offsets and motor offsets (mGauss, body), "
        "health, last sample time (us).",
    ),
    _schema(
        "RCIN", "QHHHHHHHHHHHHHH",
        "TimeUS,C1,C2,C3,C4,C5,C6,C7,C8,C9,C10,C11,C12,C13,C14",
        "sYYYYYYYYYYYYYY", "F--------------",
        instance_field=None, rate_hz=10, instances=1,
        description="RC input channels 1-14 (PWM us).",
    ),
    _schema(
        "RCOU", "QHHHHHHHHHHHHHH",
        "TimeUS,C1,C2,C3,C4,C5,C6,C7,C8,C9,C10,C11,C12,C13,C14",
        "sYYYYYYYYYYYYYY", "F--------------",
        instance_field=None, rate_hz=10, instances=1,
        description="Servo outputs 1-14 (PWM us); C1..C4 are motors 1..4.",
    ),
    # --- attitude / rate control -------------------------------------------------------------
    _schema(
        "RATE", "Qfffffffffffff",
        "TimeUS,RDes,R,ROut,PDes,P,POut,YDes,Y,YOut,ADes,A,AOut,AOutSlew",
        "skk-kk-kk-oo--", "F?????????BB--",
        instance_field=None, rate_hz=10, instances=1,
        description="Rate controller: desired/achieved body rates (deg/s) and PID outputs for "
        "roll, pitch, yaw; vertical accel desired/achieved (cm/s^2, up+), throttle out (0-1), "
        "throttle slew rate.",
    ),
    _schema(
        "ATT", "QffffffB",
        "TimeUS,DesRoll,Roll,DesPitch,Pitch,DesYaw,Yaw,AEKF",
        "sddddhh-", "F000000-",
        instance_field=None, rate_hz=10, instances=1,
        description="Attitude: desired and estimated roll, pitch (deg), yaw (deg 0-360), "
        "active EKF type (3 = EKF3).",
    ),
    # --- EKF3 ------------------------------------------------------------------------------
    _schema(
        "XKF1", "QBccCfffffffccce",
        "TimeUS,C,Roll,Pitch,Yaw,VN,VE,VD,dPD,PN,PE,PD,GX,GY,GZ,OH",
        "s#ddhnnnnmmmkkkm", "F-BBB0000000BBBB",
        instance_field="C", rate_hz=10, instances=2,
        description="EKF3 lane state: roll, pitch, yaw (deg), NED velocity (m/s), dPD (m/s), "
        "NED position from origin (m), gyro bias (deg/s), origin height (m WGS-84).",
    ),
    _schema(
        "XKF4", "QBcccccfffHBIHb",
        "TimeUS,C,SV,SP,SH,SM,SVT,errRP,OFN,OFE,FS,TS,SS,GPS,PI",
        "s#------mm-----", "F-------??-----",
        instance_field="C", rate_hz=10, instances=2,
        description="EKF3 lane health: velocity/position/height/mag/airspeed test ratios, "
        "roll-pitch error, origin offsets (m), fault/timeout/solution bit masks, GPS check "
        "status, primary lane index.",
    ),
    _schema(
        "XKFS", "QBBBBBBBBB",
        "TimeUS,C,MI,BI,GI,AI,SS,GPS_GTA,GPS_CHK_WAIT,MAG_FUSION",
        "s#--------", "F---------",
        instance_field="C", rate_hz=10, instances=2,
        description="EKF3 lane sensor selection: compass, baro, GPS and airspeed index the lane "
        "uses, source set, GPS good to align, waiting for GPS checks, magnetometer fusion (0 "
        "none, 1 yaw on the ground, 2 in flight).",
    ),
    _schema(
        "XKF2", "QBccccchhhhhhfff",
        "TimeUS,C,AX,AY,AZ,VWN,VWE,MN,ME,MD,MX,MY,MZ,IDX,IDY,IS",
        "s#---nnGGGGGGoor", "F----BBCCCCCC000",
        instance_field="C", rate_hz=10, instances=2,
        description="EKF3 lane states: accel bias (m/s^2, body), wind NE (m/s), earth magnetic "
        "field NED and body magnetic field (mGauss), drag innovations (m/s^2) and sideslip "
        "innovation (rad).",
    ),
    _schema(
        "XKF3", "QBcccccchhhccff",
        "TimeUS,C,IVN,IVE,IVD,IPN,IPE,IPD,IMX,IMY,IMZ,IYAW,IVT,RErr,ErSc",
        "s#nnnmmmGGGd?--", "F-BBBBBBCCCBB00",
        instance_field="C", rate_hz=10, instances=2,
        description="EKF3 lane innovations (predicted minus measured) of the last fusion: "
        "velocity NED (m/s), position NED (m, D from the height sensor), magnetometer body "
        "(mGauss), yaw (deg), airspeed (m/s); the lane's relative error and error score.",
    ),
    _schema(
        "XKF5", "QBBhhhcccCCfff",
        "TimeUS,C,NI,FIX,FIY,AFI,HAGL,offset,RI,rng,Herr,eAng,eVel,ePos",
        "s#----m???mrnm", "F-----BBBBB000",
        instance_field="C", rate_hz=10, instances=1,
        description="EKF3 primary lane only: optical-flow test ratio and innovations, height "
        "above ground and terrain state (m), range-finder innovation and range (m), terrain "
        "height error (m), output-observer tracking errors: angle (rad), velocity (m/s), "
        "position (m).",
    ),
    _schema(
        "XKQ", "QBffff",
        "TimeUS,C,Q1,Q2,Q3,Q4",
        "s#????", "F-????",
        instance_field="C", rate_hz=10, instances=2,
        description="EKF3 lane attitude quaternion (Q1 scalar; body -> NED).",
    ),
    _schema(
        "XKV1", "QBffffffffffff",
        "TimeUS,C,V00,V01,V02,V03,V04,V05,V06,V07,V08,V09,V10,V11",
        "s#------------", "F-------------",
        instance_field="C", rate_hz=2, instances=1,
        description="EKF3 primary lane only, every 0.5 s: covariance diagonal of states 0-11 "
        "(quaternion, velocity NED, position NED, delta-angle bias x, y).",
    ),
    _schema(
        "XKV2", "QBffffffffffff",
        "TimeUS,C,V12,V13,V14,V15,V16,V17,V18,V19,V20,V21,V22,V23",
        "s#------------", "F-------------",
        instance_field="C", rate_hz=2, instances=1,
        description="EKF3 primary lane only, every 0.5 s: covariance diagonal of states 12-23 "
        "(delta-angle bias z, delta-velocity bias, earth and body magnetic field, wind NE).",
    ),
    # --- navigation / position control ----------------------------------------------------------
    _schema(
        "CTUN", "Qffffffefffhh",
        "TimeUS,ThI,ABst,ThO,ThH,DAlt,Alt,BAlt,DSAlt,SAlt,TAlt,DCRt,CRt",
        "s----mmmmmmnn", "F----00B000BB",
        instance_field=None, rate_hz=10, instances=1,
        description="Throttle/altitude control: throttle in, angle boost, throttle out, hover "
        "throttle, desired/estimated/baro altitude (m), rangefinder alts, terrain alt, "
        "desired/actual climb rate (cm/s).",
    ),
    _schema(
        "PSCN", "Qfffffffff",
        "TimeUS,DPN,TPN,PN,DVN,TVN,VN,DAN,TAN,AN",
        "smmmnnnooo", "F000000000",
        instance_field=None, rate_hz=10, instances=1,
        description="Position controller north: desired/target/estimated position (m), "
        "velocity (m/s), acceleration (m/s^2).",
    ),
    _schema(
        "PSCE", "Qfffffffff",
        "TimeUS,DPE,TPE,PE,DVE,TVE,VE,DAE,TAE,AE",
        "smmmnnnooo", "F000000000",
        instance_field=None, rate_hz=10, instances=1,
        description="Position controller east: desired/target/estimated position (m), "
        "velocity (m/s), acceleration (m/s^2).",
    ),
    _schema(
        "PSCD", "Qfffffffff",
        "TimeUS,DPD,TPD,PD,DVD,TVD,VD,DAD,TAD,AD",
        "smmmnnnooo", "F000000000",
        instance_field=None, rate_hz=10, instances=1,
        description="Position controller down: desired/target/estimated position (m, down+), "
        "velocity (m/s), acceleration (m/s^2).",
    ),
    _schema(
        "POS", "QLLfff",
        "TimeUS,Lat,Lng,Alt,RelHomeAlt,RelOriginAlt",
        "sDUmmm", "FGG000",
        instance_field=None, rate_hz=10, instances=1,
        description="AHRS/EKF position: lat/lon (deg), alt AMSL (m), alt above home and "
        "above EKF origin (m).",
    ),
    # --- power ------------------------------------------------------------------------------
    _schema(
        "BAT", "QBfffffcfBBB",
        "TimeUS,Inst,Volt,VoltR,Curr,CurrTot,EnrgTot,Temp,Res,RemPct,H,SH",
        "s#vvAaXOw%-%", "F-000C0?0000",
        instance_field="Inst", rate_hz=10, instances=1,
        description="Battery: voltage, resting voltage (V), current (A), consumed (mAh), "
        "energy (Wh), temperature (degC), resistance (Ohm), remaining (%), health, "
        "state of health (%).",
    ),
    _schema(
        "MOTB", "QfffffB",
        "TimeUS,LiftMax,BatVolt,ThLimit,ThrAvMx,ThrOut,FailFlags",
        "s------", "F------",
        instance_field=None, rate_hz=10, instances=1,
        description="Motor/battery: max lift, battery voltage ratio, throttle limit, "
        "average max throttle, throttle out, failure flags.",
    ),
    # --- simulator truth --------------------------------------------------------------------
    _schema(
        "SIM", "QccCfLLffff",
        "TimeUS,Roll,Pitch,Yaw,Alt,Lat,Lng,Q1,Q2,Q3,Q4",
        "sddhmDU----", "FBBB0GG0000",
        instance_field=None, rate_hz=10, instances=1,
        description="Simulator truth: roll, pitch, yaw (deg), alt AMSL (m), lat/lon (deg), "
        "attitude quaternion.",
    ),
    # --- the AHRS's second attitude solution and EKF3's yaw estimator ------------------------
    _schema(
        "DCM", "Qffffffff",
        "TimeUS,Roll,Pitch,Yaw,ErrRP,ErrYaw,VWN,VWE,VWD",
        "sddddhnnn", "F00000000",
        instance_field=None, rate_hz=10, instances=1,
        description="DCM attitude estimator: roll, pitch (deg), yaw (deg 0-360), low-passed "
        "roll/pitch and heading errors, wind NED (m/s; 0 on a copter).",
    ),
    _schema(
        "AHR2", "QccCfLLffff",
        "TimeUS,Roll,Pitch,Yaw,Alt,Lat,Lng,Q1,Q2,Q3,Q4",
        "sddhmDU----", "FBBB0GG----",
        instance_field=None, rate_hz=10, instances=1,
        description="The AHRS's secondary solution (DCM while EKF3 is active): roll, pitch, "
        "yaw (deg), alt AMSL (m), lat/lon (deg), attitude quaternion.",
    ),
    _schema(
        "XKY0", "QBffffffffffff",
        "TimeUS,C,YC,YCS,Y0,Y1,Y2,Y3,Y4,W0,W1,W2,W3,W4",
        "s#hdhhhhh-----", "F-000000000000",
        instance_field="C", rate_hz=10, instances=2,
        description="EKF3 GSF yaw estimator per lane: composite yaw (deg), sqrt of the yaw "
        "variance in deg (as the firmware computes it), the five models' yaws (deg) and "
        "weights.",
    ),
    _schema(
        "XKY1", "QBffffffffff",
        "TimeUS,C,IVN0,IVN1,IVN2,IVN3,IVN4,IVE0,IVE1,IVE2,IVE3,IVE4",
        "s#nnnnnnnnnn", "F-0000000000",
        instance_field="C", rate_hz=10, instances=2,
        description="EKF3 GSF yaw estimator per lane: the five models' GPS velocity "
        "innovations north and east (m/s).",
    ),
    _schema(
        "SIM2", "QdddfffffI",
        "TimeUS,PN,PE,PD,VN,VE,VD,As,ASpdU,UFC",
        "s?????????", "F?????????",
        instance_field=None, rate_hz=50, instances=1,
        description="Simulator truth: NED position relative to home (m), NED velocity (m/s), "
        "pitot airspeed (m/s), achieved simulation speed-up, times the simulation paused for "
        "serial output (50 Hz with LOG_FILE_RATEMAX 50).",
    ),
    # --- vehicle evidence (issue 21) ---------------------------------------------------------
    _schema(
        "ARM", "QBIBB",
        "TimeUS,ArmState,ArmChecks,Forced,Method",
        "s----", "F----",
        instance_field=None, rate_hz=0, instances=1,
        description="Arming or disarming: new armed state, arming checks enabled (ARMING_CHECK; "
        "0 on disarming), forced, AP_Arming::Method (1 MAVLink, 12 crash, 13 landed, "
        "14 mission exit, ...).",
    ),
    _schema(
        "ORGN", "QBLLe",
        "TimeUS,Type,Lat,Lng,Alt",
        "s#DUm", "F-GGB",
        instance_field="Type", rate_hz=0, instances=2,
        description="EKF origin (Type 0) and AHRS home (Type 1): lat/lon (deg), alt AMSL (m); "
        "written when either is set (origin, home at arming).",
    ),
    _schema(
        "LDET", "QHI",
        "TimeUS,Flags,Count",
        "s--", "F--",
        instance_field=None, rate_hz=0, instances=1,
        description="Land detector: condition flags (Copter::LandDetectorLoggingFlag) and its "
        "pass count (main-loop ticks); on change, at most 50 Hz.",
    ),
    _schema(
        "AUXF", "QHBBHB",
        "TimeUS,function,pos,source,index,result",
        "s#----", "F-----",
        instance_field="function", rate_hz=0, instances=1,
        description="RC aux function run: RCn_OPTION, switch position (0 low, 1 middle, "
        "2 high), source (1 RC), channel index (0-based), result (1 success).",
    ),
    _schema(
        "ANG", "Qfffffff",
        "TimeUS,DesRoll,Roll,DesPitch,Pitch,DesYaw,Yaw,Dt",
        "sddddhhs", "F0000000",
        instance_field=None, rate_hz=10, instances=1,
        description="Attitude controller: ATT's targets and attitude (deg) with the main-loop "
        "interval Dt (s); written in a .bin from ATT.",
    ),
    _schema(
        "MISE", "QHHHffffLLfB",
        "TimeUS,CTot,CNum,CId,Prm1,Prm2,Prm3,Prm4,Lat,Lng,Alt,Frame",
        "s-------DUm-", "F-------GG0-",
        instance_field=None, rate_hz=0, instances=1,
        description="Mission item started (as CMD): total, index, MAV_CMD id, params 1-4, "
        "lat/lon (deg), alt (m), MAV_FRAME.",
    ),
)

#: Every schema tlm knows, by message name.
SCHEMAS: dict[str, MessageSchema] = {s.name: s for s in _SCHEMA_LIST}

#: Messages the numba simulator fills (float64 buffer [max_rows, len(columns)] each).
LOGGED_MESSAGES: tuple[str, ...] = (
    "GPS", "GPA", "IMU", "RATE", "VIBE", "ATT", "BARO", "MAG", "RCIN", "RCOU", "MODE", "EV",
    "ERR", "XKF1", "XKF4", "CTUN", "BAT", "POS", "SIM", "PSCN", "PSCE", "PSCD", "XKFS",
    "XKF2", "XKF3", "XKF5", "XKQ", "XKV1", "XKV2",
    "DCM", "AHR2", "XKY0", "XKY1",
    "ARM", "ORGN", "LDET", "MOTB", "MISE", "SIM2",
)

#: On-event messages (``rate_hz == 0``) that carry flight events.
EVENT_MESSAGES: tuple[str, ...] = ("MODE", "EV", "ERR", "MSG")
