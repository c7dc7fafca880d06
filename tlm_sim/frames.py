"""Multicopter frames as data: SITL's frame table and ArduCopter's motor matrix in one place.

A frame is a list of motors, each an arm angle (degrees from the nose, positive clockwise seen
from above), a spin (yaw factor +1 = counter-clockwise propeller, -1 = clockwise) and a
motor-test order; motor ``k`` (1-based) is driven by output ``SERVOk`` (RCOU ``Ck``) and is bit
``k - 1`` of ``SIM_ENGINE_FAIL``. The same table gives

* the simulator's motor positions: arm ``r_k = TLM_DIAG (cos theta_k, sin theta_k, 0)`` in body
  FRD (SITL ``Frame::init``, ardupilot-reference.md §1.2) and the reaction torque sign, and
* the autopilot's mixer factors (``AP_MotorsMatrix::add_motor``: roll ``cos(theta + 90 deg)``,
  pitch ``cos(theta)``, yaw ``+-1``, each axis then scaled so its largest magnitude is 0.5).

A flight's frame is chosen by ``FRAME_CLASS`` / ``FRAME_TYPE`` (:func:`frame_for`); a SITL
model name (``sim_vehicle.py -f x``, ``--model +``) maps to the same entries
(:func:`frame_for_model`). Layouts from sitl-faults.md §6.3; SITL's ``+`` and ``x`` tables
are identical to the autopilot's PLUS and X tables, and so are the hexa and octa entries here.

==========  ======  ===========  ==========  ========================================
name        motors  FRAME_CLASS  FRAME_TYPE  motor 1 (bit 0 of SIM_ENGINE_FAIL)
==========  ======  ===========  ==========  ========================================
``+``       4       1 (QUAD)     0 (PLUS)    right arm, CCW
``x``       4       1 (QUAD)     1 (X)       front-right arm, CCW
``hexa``    6       2 (HEXA)     0 (PLUS)    front arm, CW
``hexax``   6       2 (HEXA)     1 (X)       right arm, CW
``octa``    8       3 (OCTA)     0 (PLUS)    front arm, CW
==========  ======  ===========  ==========  ========================================
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = [
    "FRAMES",
    "MAX_MOTORS",
    "FrameError",
    "FrameLayout",
    "Motor",
    "frame_for",
    "frame_for_model",
    "frame_name",
]

#: the most motors a frame of the table has (the width of the per-motor state slots)
MAX_MOTORS: int = 8

#: yaw factors of AP_MOTORS_MATRIX_YAW_FACTOR_CCW / _CW
CCW, CW = 1.0, -1.0

#: ArduCopter's FRAME_CLASS and FRAME_TYPE names (as the firmware's "Frame: CLASS/TYPE" text)
CLASS_NAMES: dict[int, str] = {1: "QUAD", 2: "HEXA", 3: "OCTA"}
TYPE_NAMES: dict[int, str] = {0: "PLUS", 1: "X"}


class FrameError(ValueError):
    """No frame of the table matches the request."""


@dataclass(frozen=True)
class Motor:
    """One motor: arm angle [deg] from the nose, clockwise seen from above; yaw factor (+1
    counter-clockwise propeller, -1 clockwise); motor-test order (1 = first)."""

    angle_deg: float
    yaw_factor: float
    test_order: int


def _clean(v: float) -> float:
    """Round-off of cos/sin at multiples of 90 deg (6e-17) set to exactly 0."""
    return 0.0 if abs(v) < 1e-12 else v


@dataclass(frozen=True)
class FrameLayout:
    """A frame of the table: its name, the autopilot's FRAME_CLASS / FRAME_TYPE and motors."""

    name: str
    frame_class: int
    frame_type: int
    motors: tuple[Motor, ...]

    @property
    def n_motors(self) -> int:
        return len(self.motors)

    @property
    def label(self) -> str:
        """The firmware's frame text, e.g. ``QUAD/X`` (logged as MSG ``Frame: QUAD/X``)."""
        return f"{CLASS_NAMES[self.frame_class]}/{TYPE_NAMES[self.frame_type]}"

    def arm_unit(self) -> tuple[tuple[float, float], ...]:
        """Unit arm direction (x forward, y right) of each motor, body FRD."""
        out = []
        for m in self.motors:
            a = math.radians(m.angle_deg)
            out.append((_clean(math.cos(a)), _clean(math.sin(a))))
        return tuple(out)

    def mixer_factors(self) -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]]:
        """The autopilot's (roll, pitch, yaw) factor of each motor, each axis normalised so
        its largest magnitude is 0.5 (``normalise_rpy_factors``); rounded to 1e-12 so that
        equal factors are equal (the X frame's cos 45 deg and cos 135 deg differ in the last
        bit)."""
        roll = [_clean(math.cos(math.radians(m.angle_deg + 90.0))) for m in self.motors]
        pitch = [_clean(math.cos(math.radians(m.angle_deg))) for m in self.motors]
        yaw = [m.yaw_factor for m in self.motors]

        def norm(v: list[float]) -> tuple[float, ...]:
            top = max(abs(f) for f in v)
            return tuple(round(0.5 * f / top, 12) + 0.0 if top > 0 else 0.0 for f in v)

        return norm(roll), norm(pitch), norm(yaw)


def _frame(name: str, cls: int, typ: int, *motors: tuple[float, float, int]) -> FrameLayout:
    return FrameLayout(name, cls, typ, tuple(Motor(a, y, o) for a, y, o in motors))


#: The frame table, by SITL model name (sitl-faults.md §6.3).
FRAMES: dict[str, FrameLayout] = {f.name: f for f in (
    _frame("+", 1, 0, (90, CCW, 2), (-90, CCW, 4), (0, CW, 1), (180, CW, 3)),
    _frame("x", 1, 1, (45, CCW, 1), (-135, CCW, 3), (-45, CW, 4), (135, CW, 2)),
    _frame("hexa", 2, 0, (0, CW, 1), (180, CCW, 4), (-120, CW, 5), (60, CCW, 2),
           (-60, CCW, 6), (120, CW, 3)),
    _frame("hexax", 2, 1, (90, CW, 2), (-90, CCW, 5), (-30, CW, 6), (150, CCW, 3),
           (30, CCW, 1), (-150, CW, 4)),
    _frame("octa", 3, 0, (0, CW, 1), (180, CW, 5), (45, CCW, 2), (135, CCW, 4),
           (-45, CCW, 8), (-135, CCW, 6), (-90, CW, 7), (90, CW, 3)),
)}

#: SITL model names that name a table entry (``sim_vehicle.py -f``), searched in this order;
#: the first whose name the requested model starts with wins (``hexax`` before ``hexa``).
_MODEL_PREFIXES: tuple[tuple[str, str], ...] = (
    ("+", "+"), ("quad", "+"), ("copter", "+"), ("x", "x"), ("hexax", "hexax"),
    ("hexa", "hexa"), ("octa-quad", ""), ("octa", "octa"),
)


def frame_for(frame_class: float, frame_type: float) -> FrameLayout:
    """The frame of ``FRAME_CLASS`` / ``FRAME_TYPE`` (raises :class:`FrameError` if tlm has
    none: the message lists those it has)."""
    for f in FRAMES.values():
        if f.frame_class == frame_class and f.frame_type == frame_type:
            return f
    have = ", ".join(f"{f.frame_class}/{f.frame_type} ({f.name})" for f in FRAMES.values())
    raise FrameError(f"FRAME_CLASS {frame_class:g} with FRAME_TYPE {frame_type:g} is not a frame "
                     f"tlm simulates; it has (FRAME_CLASS/FRAME_TYPE): {have}")


def frame_for_model(model: str) -> FrameLayout:
    """The frame of a SITL model name (case-insensitive; ``x``, ``+``, ``quad``, ``hexa``,
    ...; the first table name the model starts with, as SITL looks it up)."""
    m = model.strip().lower()
    for prefix, name in _MODEL_PREFIXES:
        if m.startswith(prefix):
            if not name:
                break
            return FRAMES[name]
    raise FrameError(f"SITL model {model!r} is not a frame tlm simulates; it has: "
                     f"{', '.join(FRAMES)}")


def frame_name(frame_class: float, frame_type: float) -> str:
    """The table name (``+``, ``x``, ...) of ``FRAME_CLASS`` / ``FRAME_TYPE``."""
    return frame_for(frame_class, frame_type).name
