"""Monte Carlo scenarios: everything one flight of a generated data set needs, drawn from the
run seed.

Flight ``i`` of a run with seed ``S`` draws from ``numpy.random.SeedSequence(S,
spawn_key=(i, stream))`` (what ``SeedSequence(S).spawn`` gives its i-th child, one level deeper
per stream), so it is the same flight whatever the number of flights, the executor or the
worker count. One stream per aspect keeps them apart: changing the mission mix does not move
any fault time. Streams:

0. **kind**: ``none`` (no fault), ``single`` (one fault), ``paper`` (all four faults in one
   flight, the paper's §3.2 / §4.3 sequence) or ``sequence`` (several faults of
   :attr:`ScenarioConfig.sequence_types` one after the other), by
   :attr:`ScenarioConfig.kinds` shares.
1. **mission**: a built-in shape (1-4, uniform) or a random Algorithm 1 mission around
   :attr:`ScenarioConfig.home` (:func:`tlm_sim.mission.random_loop` + ``make_mission``: six raw
   points on a jittered loop, ~90 interpolated waypoints), by :attr:`ScenarioConfig.missions`
   shares. The altitude profile is drawn for both: uniform in ``alt_range`` per waypoint,
   Savitzky-Golay smoothed (built-in shapes keep their own profile with
   ``builtin_altitudes="keep"``).
2. **faults**: types, order, start times and holds (all rounded to 0.1 s; times in seconds
   since boot, AUTO taken to start at ``auto_start_s``):

   * ``single``: one type by ``fault_weights``, starting U(``single_start_s``) s after AUTO;
   * ``paper``: GPS, accel, engine in a random order (the paper's order with
     ``shuffle=False``) and then RC (its failsafe sends the copter home, so it comes last);
     the first starts U(``gap_s``) s after AUTO, each later one U(``gap_s``) s after the
     previous one ends;
   * ``sequence``: a whole number of faults uniform in ``sequence_len``, distinct types drawn
     from ``sequence_types`` by their ``fault_weights`` (all equal where every weight is 0), in
     a random order, RC last if drawn; timed as ``paper``;

   every hold is U(``hold_s``) s times λ (``lam``, Eq. 5's window factor). A fault whose
   boundary would come after the longest the flight can last is dropped with those after it.
3. **environment**: each parameter of :attr:`ScenarioConfig.ranges` uniform in its range
   (wind speed, direction and turbulence, sensor noise amplitudes; rounded to 0.001).
4. **flight seed**: the seed of all the flight's own noise draws (IMU, GPS, baro, compass,
   gusts), 0 .. 2**31 - 1.
5. **magnitudes**: each fault's parameters, for the types whose record has knobs
   (:func:`magnitude_knobs`, :mod:`tlm_process.fault_types`: GPS glitch offset, partial
   motor multiplier, battery voltage, vibration amplitude, which baro / compass / IMU
   fails, ...), drawn from :attr:`ScenarioConfig.magnitudes` (uniform in a range, or one of
   a list), fault by fault, and turned into SITL parameters by the record's ``params``.
   The paper's four types have no knobs, so their flights draw nothing here and fly the
   type's parameters (the default data set is the same flight for flight as before the
   catalogue: same seed, same flights).
6. **frame**: the airframe, a name of :data:`tlm_sim.frames.FRAMES` (``+``, ``x``, ...) by
   :attr:`ScenarioConfig.frames` shares; it sets ``FRAME_CLASS`` / ``FRAME_TYPE``.
7. **wind**: calm or windy by :attr:`ScenarioConfig.wind`'s ``calm`` share (one uniform
   draw), then speed, direction and turbulence, each uniform in its range (always all
   three draws, so the calm share moves no windy value); a calm flight flies
   ``SIM_WIND_SPD`` 0 and ``SIM_WIND_TURB`` 0 (and no direction), a windy one the three
   values drawn (rounded to 0.001). The environment stream (3) no longer draws these three:
   it draws its parameters in name order and the wind names sort last, so the sensor-noise
   draws are those of the tlm before frames and wind.

8. **vibration**: a real copter's vibration and noise or SITL's quiet airframe, by
   :attr:`ScenarioConfig.vibration`'s ``real`` share (one uniform draw), then every parameter
   of its ``ranges`` uniform (name order, rounded to 0.001; always all draws, so the share
   moves no real flight's values). A real-level flight flies the drawn airframe (they replace
   the environment's SIM_GYRn_RND draws); a quiet one none of them (docs/noise.md).

9. **pilot**: a pilot-flown flight instead of a mission by :attr:`ScenarioConfig.pilot`'s
   ``share`` (one uniform draw; none by default), then its mode, pattern, height and stick
   segments (:mod:`tlm_process.generate.pilot_flights`). Its faults count from the start of
   its pattern instead of ``auto_start_s`` and must end before its descent; its mission
   stream is not drawn (the recipe is the script's draw).

Streams 6 to 9 came last, so every draw of streams 0-5 of a flight is what it was before
(``tests/test_generate_frames.py`` pins it against digests of the earlier sampler).

:func:`fault_preset` names the usual choices of fault types (``--faults`` of ``tlm
generate``, or ``faults:`` in a configuration): ``paper`` (the default: the paper's four
types), ``all``, ``new``, ``single``, or a list of types. Every fault type comes from the
registry (:data:`tlm_sim.faults.FAULT_TYPES` and :mod:`tlm_process.fault_types`): a type
registered there is drawn like the built-in ones.

A :class:`Scenario` holds the outcome as plain data (a mission recipe, the fault schedule's
file form, parameter overrides, the flight seed, the profile), so a flight can be re-flown
from the manifest alone (:meth:`Scenario.realise`).
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from functools import lru_cache
from typing import Any, NamedTuple

import numpy as np

from tlm_process.fault_types import Knob, fault_type_record, fault_type_records
from tlm_process.generate.checks import fraction, known_keys
from tlm_process.generate.checks import shares as _shares
from tlm_process.generate.checks import value_range as _range
from tlm_process.generate.errors import GenerateError
from tlm_process.generate.pilot_flights import draw_pilot, pilot_script, validate_pilot
from tlm_sim.faults import FAULT_TYPES, Fault, FaultSchedule, FaultScheduleError, Trigger
from tlm_sim.flight import max_duration_s, pilot_home_mission
from tlm_sim.frames import FRAMES, FrameError, frame_name
from tlm_sim.geo import HOME_CMAC
from tlm_sim.mission import (
    BUILTIN_IDS,
    Mission,
    MissionError,
    builtin_mission,
    make_mission,
    random_loop,
)
from tlm_sim.params import ParamError, Params
from tlm_sim.profiles import PROFILES, profile_params

__all__ = [
    "DEFAULT_FRAMES",
    "DEFAULT_RANGES",
    "DEFAULT_VIBRATION",
    "DEFAULT_WIND",
    "FRAME_PARAMS",
    "KINDS",
    "PAPER_TYPES",
    "REAL_VIBRATION",
    "fault_params",
    "fault_preset",
    "frame_params",
    "magnitude_knobs",
    "new_types",
    "MISSION_SOURCES",
    "FlightSpec",
    "Scenario",
    "ScenarioConfig",
    "WIND_PARAMS",
    "flight_conditions",
    "mission_from_recipe",
    "sample_scenario",
]

#: Flight kinds, in the order their shares are drawn (appending keeps older draws).
KINDS: tuple[str, ...] = ("none", "single", "paper", "sequence")
#: Mission sources, in the order their shares are drawn.
MISSION_SOURCES: tuple[str, ...] = ("builtin", "random")
#: Faults of a paper-style flight before the RC fault (shuffled unless ``shuffle=False``).
PAPER_FIRST: tuple[str, ...] = ("gps", "accel", "engine")

(_S_KIND, _S_MISSION, _S_FAULTS, _S_ENV, _S_SEED, _S_MAGNITUDE, _S_FRAME, _S_WIND,
 _S_VIBRATION, _S_PILOT) = range(10)

#: The paper's four fault types (labels 1-4).
PAPER_TYPES: tuple[str, ...] = ("gps", "accel", "engine", "rc")


def new_types() -> tuple[str, ...]:
    """Every registered fault type but the paper's four (labels 5-14 and any registered
    since), in label order."""
    return tuple(t for t in FAULT_TYPES if t not in PAPER_TYPES)


def magnitude_knobs() -> dict[str, dict[str, Knob]]:
    """The configurable magnitude knobs of every registered type that has any (fault type ->
    knob -> :class:`~tlm_process.fault_types.Knob`), in label order: what
    :attr:`ScenarioConfig.magnitudes` may set."""
    out = {}
    for r in fault_type_records():
        knobs = {k: v for k, v in r.knobs.items() if v.configurable}
        if knobs:
            out[r.name] = knobs
    return out


#: Default draws of the environment (uniform, per flight): sensor noise amplitudes on top of
#: the simulator's built-in noise (the wind has its own setting, :data:`DEFAULT_WIND`).
DEFAULT_RANGES: dict[str, tuple[float, float]] = {
    "SIM_GYR1_RND": (0.0, 0.5),  # deg/s at full throttle
    "SIM_GYR2_RND": (0.0, 0.5),
    "SIM_BARO_RND": (0.0, 0.2),  # m
    "SIM_BAR2_RND": (0.0, 0.2),  # m (the second barometer has its own noise)
    "SIM_MAG_RND": (0.0, 20.0),  # mGauss
}

#: Default frame shares: both quad frames, half each (hexa and octa only when asked for).
DEFAULT_FRAMES: dict[str, float] = {"+": 0.5, "x": 0.5}
#: The parameters a flight's frame sets (ArduCopter's frame selection).
FRAME_PARAMS: tuple[str, str] = ("FRAME_CLASS", "FRAME_TYPE")

#: The wind setting's ranges by key -> the SITL parameter each draws (in drawing order).
WIND_PARAMS: dict[str, str] = {"speed": "SIM_WIND_SPD", "direction": "SIM_WIND_DIR",
                               "turbulence": "SIM_WIND_TURB"}
#: Default wind: 30 % calm flights (no wind, no turbulence); the others draw speed U(0, 8) m/s
#: at full-strength height (SIM_WIND_T_ALT; the square-root profile gives 0.58 of it at 20
#: m), direction U(0, 360) deg (where it comes from) and turbulence U(0, 2) m/s: the range of
#: SITL's held-back wind flights (up to 8 m/s, turbulence above the reference's 1).
DEFAULT_WIND: dict[str, Any] = {"calm": 0.3, "speed": (0.0, 8.0), "direction": (0.0, 360.0),
                                "turbulence": (0.0, 2.0)}

#: The airframe of a real-level flight (issue 40, docs/noise.md): each parameter uniform in its
#: range. SITL's motor vibration (amplitudes SIM_ACCn_RND 5 m/s^2 and SIM_GYRn_RND 20 deg/s
#: per rotor, the autotest quad's) shaped per axis by the TLM_VIB_* gains: VIBE ~2-20 m/s^2
#: per axis (ArduPilot's guide: below 15 good, below 30 acceptable) and gyro noise ~0.5-7
#: deg/s, the range of real quads (issue 40's table; log171 fitted: accel gains 1.4 / 0.4 /
#: 0.6, gyro 6.5 / 1.0 / 1.4) at hover (command ~0.55), each rotor's going with its speed
#: squared; rotors at 120-250 Hz full command, lagging 30-80 ms, a few per cent apart; the
#: drawn turbulence's gusts correlated over 0.3-1 s. A real airframe is never balanced: its
#: centre of gravity up to 15 mm off the motors' centre and its rotors' reaction torques up to
#: 15 % apart (log171 fitted: 13 mm behind, 4 mm right, -0.13), so the motors run up to
#: ~35 us (pitch, roll) and ~50 us (yaw) apart in a hover. Its rotors' thrust fluctuates by up to
#: 4 % (log171 fitted: 3.2 %), so its attitude tracking error is a real hover's.
REAL_VIBRATION: dict[str, tuple[float, float]] = {
    "SIM_ACC1_RND": (5.0, 5.0), "SIM_ACC2_RND": (5.0, 5.0),
    "SIM_GYR1_RND": (20.0, 20.0), "SIM_GYR2_RND": (20.0, 20.0),
    "SIM_VIB_MOT_MAX": (120.0, 250.0),
    "TLM_ROTOR_TC": (0.03, 0.08), "TLM_VIB_SPREAD": (0.01, 0.05), "TLM_TURB_TC": (0.3, 1.0),
    "TLM_VIB_CMD_REF": (0.55, 0.55),
    "TLM_VIB_ACC_X": (0.3, 3.0), "TLM_VIB_ACC_Y": (0.3, 3.0), "TLM_VIB_ACC_Z": (0.3, 3.0),
    "TLM_VIB_GYR_X": (0.5, 8.0), "TLM_VIB_GYR_Y": (0.5, 8.0), "TLM_VIB_GYR_Z": (0.3, 3.0),
    "TLM_CG_X": (-0.015, 0.015), "TLM_CG_Y": (-0.015, 0.015), "TLM_YAW_ASYM": (-0.15, 0.15),
    "TLM_ROTOR_RND": (0.0, 0.04),
}
#: Default vibration setting: half the flights with a real copter's vibration, half
#: SITL-quiet.
DEFAULT_VIBRATION: dict[str, Any] = {"real": 0.5, "ranges": REAL_VIBRATION}
#: The airframe's vibration gains a vibration ``scale`` multiplies, per flight: a real
#: copter's vibration is not one level (log171's steady LOITER hover: gyro noise x 3.2-5.4
#: deg/s, y 1.6-3.3 in 5 s blocks with the sticks centred; props, payload and battery move it
#: from flight to flight), and a detector trained on one level reads any other as a fault
VIB_GAINS: tuple[str, ...] = tuple(f"TLM_VIB_{s}_{a}" for s in ("ACC", "GYR") for a in "XYZ")


@dataclass(frozen=True)
class ScenarioConfig:
    """What the scenario sampler draws from (all times in seconds, see the module docstring).

    Attributes:
        kinds: share of ``none`` / ``single`` / ``paper`` flights (normalised).
        missions: share of ``builtin`` / ``random`` missions (normalised).
        home: (lat deg, lon deg, alt m AMSL) of random missions.
        n_waypoints: waypoints of a random mission (Algorithm 1 target count).
        alt_range: (low, high) waypoint altitudes, metres above home (paper: 15-25 m).
        builtin_altitudes: ``"redraw"`` (a fresh altitude profile per flight) or ``"keep"``.
        fault_weights: relative weight of each fault type in ``single`` flights.
        auto_start_s: when AUTO starts, s since boot (the switch is at ~20 s in tlm flights).
        gap_s: normal flight before each fault of a ``paper`` flight.
        hold_s: how long a fault is held before λ.
        single_start_s: start of a ``single`` fault after AUTO.
        shuffle: shuffle GPS/accel/engine in ``paper`` flights (RC stays last).
        lam: λ, every hold is multiplied by it (> 0).
        ranges: parameter name -> (low, high), drawn uniformly per flight.
        params: parameter overrides for every flight (ArduPilot names).
        profile: ``current`` or ``paper`` (see :mod:`tlm_sim.profiles`).
        sequence_types: fault types of ``sequence`` flights (default: labels 5-14).
        sequence_len: (low, high) number of faults of a ``sequence`` flight.
        magnitudes: fault type -> knob -> range or list of choices (see
            :func:`magnitude_knobs`; missing knobs keep their defaults).
        frames: share of each frame of :data:`tlm_sim.frames.FRAMES` (``+``, ``x``, ``hexa``,
            ``hexax``, ``octa``; normalised), or a list of names (equal shares). The drawn
            frame sets ``FRAME_CLASS`` / ``FRAME_TYPE``, which ``params`` and ``ranges`` may
            therefore not name. Default :data:`DEFAULT_FRAMES` (``+`` and ``x``, half each).
        wind: ``calm`` (share of flights without wind or turbulence, 0..1) and the windy
            flights' ranges ``speed`` (``SIM_WIND_SPD``, m/s), ``direction``
            (``SIM_WIND_DIR``, deg, where the wind comes from) and ``turbulence``
            (``SIM_WIND_TURB``, m/s), each (low, high) or one number; missing keys take
            :data:`DEFAULT_WIND`'s. A range of one of these three parameters in ``ranges``
            is taken as the wind setting's (so older configurations keep working); ``params``
            may not fix them. ``None``: no wind draw (the three are the simulator's defaults,
            calm, or what ``ranges`` / ``params`` give every flight).
        vibration: ``real`` (share of flights with a real copter's vibration and noise, 0..1)
            and their ``ranges`` (parameter -> (low, high)); missing keys take
            :data:`DEFAULT_VIBRATION`'s (half the flights real, :data:`REAL_VIBRATION`). When
            ``params`` fix any of these parameters (``--params vehicle.parm`` of a ``tlm fit``
            vehicle) and no share is given, no flight draws them (the vehicle has its own);
            a share > 0 with such ``params`` is refused. ``scale`` (low, high), optional:
            every flight multiplies the six vibration gains (:data:`VIB_GAINS`, the vehicle's
            own or the drawn ones) by one factor uniform in it, drawn after the airframe's
            draws (a fitted vehicle's level spread as a real copter's spreads). ``None``: no
            draw (every flight SITL-quiet, or what ``params`` give).
        pilot: ``share`` of pilot-flown flights (0..1, default 0), their ``modes`` and
            ``patterns`` shares and the ranges ``stick``, ``alt``, ``duration``, ``leg_s``,
            ``release_s`` (:data:`~tlm_process.generate.pilot_flights.DEFAULT_PILOT`);
            ``None``: none.
    """

    kinds: Mapping[str, float] = field(
        default_factory=lambda: {"none": 0.2, "single": 0.4, "paper": 0.2, "sequence": 0.2})
    missions: Mapping[str, float] = field(
        default_factory=lambda: {"builtin": 0.5, "random": 0.5})
    home: tuple[float, float, float] = HOME_CMAC
    n_waypoints: int = 90
    alt_range: tuple[float, float] = (15.0, 25.0)
    builtin_altitudes: str = "redraw"
    fault_weights: Mapping[str, float] = field(
        default_factory=lambda: {t: 1.0 for t in FAULT_TYPES})
    auto_start_s: float = 20.0
    gap_s: tuple[float, float] = (15.0, 25.0)
    hold_s: tuple[float, float] = (20.0, 40.0)
    single_start_s: tuple[float, float] = (15.0, 240.0)
    shuffle: bool = True
    lam: float = 1.0
    ranges: Mapping[str, tuple[float, float]] = field(default_factory=lambda: dict(DEFAULT_RANGES))
    params: Mapping[str, float] = field(default_factory=dict)
    profile: str = "current"
    sequence_types: tuple[str, ...] = field(default_factory=new_types)
    sequence_len: tuple[int, int] = (2, 4)
    magnitudes: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    frames: Mapping[str, float] | str | list[str] = field(
        default_factory=lambda: dict(DEFAULT_FRAMES))
    wind: Mapping[str, Any] | None = field(default_factory=dict)
    vibration: Mapping[str, Any] | None = field(default_factory=dict)
    pilot: Mapping[str, Any] | None = field(default_factory=dict)

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "kinds", _shares(self.kinds, KINDS, "kinds"))
        set_(self, "missions", _shares(self.missions, MISSION_SOURCES, "missions"))
        set_(self, "fault_weights", _shares(self.fault_weights, tuple(FAULT_TYPES),
                                            "fault_weights"))
        try:
            home = tuple(float(v) for v in self.home)
        except (TypeError, ValueError):
            raise GenerateError(f"home must be (lat, lon, alt_amsl_m), got {self.home!r}") from None
        if len(home) != 3 or not all(math.isfinite(v) for v in home) or abs(home[0]) > 90 or abs(
                home[1]) > 180:
            raise GenerateError(f"home must be (lat, lon, alt_amsl_m) in degrees/metres, got "
                                f"{self.home!r}")
        set_(self, "home", home)
        if isinstance(self.n_waypoints, bool) or not isinstance(
                self.n_waypoints, int | np.integer) or not 2 <= self.n_waypoints <= 10_000:
            raise GenerateError(f"n_waypoints must be a whole number 2..10000, got "
                                f"{self.n_waypoints!r}")
        set_(self, "n_waypoints", int(self.n_waypoints))
        set_(self, "alt_range", _range(self.alt_range, "alt_range"))
        if self.builtin_altitudes not in ("redraw", "keep"):
            raise GenerateError(f"builtin_altitudes must be 'redraw' or 'keep', got "
                                f"{self.builtin_altitudes!r}")
        for name in ("gap_s", "hold_s", "single_start_s"):
            set_(self, name, _range(getattr(self, name), name))
        if self.hold_s[0] <= 0:
            raise GenerateError(f"hold_s must be > 0 s, got {self.hold_s}")
        a = self.auto_start_s
        if isinstance(a, bool) or not isinstance(a, int | float) or not math.isfinite(a) or a < 0:
            raise GenerateError(f"auto_start_s must be a number >= 0, got {a!r}")
        set_(self, "auto_start_s", float(a))
        lam = self.lam
        if isinstance(lam, bool) or not isinstance(lam, int | float) or not math.isfinite(
                lam) or lam <= 0:
            raise GenerateError(f"lambda must be a finite number > 0, got {lam!r}")
        set_(self, "lam", float(lam))
        set_(self, "shuffle", bool(self.shuffle))
        if self.profile not in PROFILES:
            raise GenerateError(f"unknown profile {self.profile!r}; choose from "
                                f"{', '.join(PROFILES)}")
        frames = _frame_shares(self.frames)
        ranges, params, wind = _environment(self.ranges, self.params, self.wind)
        _check_params(params, ranges, wind, frames)
        set_(self, "frames", frames)
        set_(self, "wind", wind)
        vib = _vibration(self.vibration, params, ranges)
        if vib is not None:  # both ends of the airframe's draws, on every frame
            _check_params(params, vib["ranges"], None, frames)
        set_(self, "vibration", vib)
        set_(self, "ranges", ranges)
        set_(self, "params", {k: float(params[k]) for k in sorted(params)})
        set_(self, "sequence_types", _types(self.sequence_types, "sequence_types"))
        lo, hi = _range(self.sequence_len, "sequence_len", 1.0)
        if lo != int(lo) or hi != int(hi):
            raise GenerateError(f"sequence_len must be whole numbers, got {self.sequence_len}")
        if self.kinds.get("sequence", 0.0) > 0 and int(lo) > len(self.sequence_types):
            raise GenerateError(f"sequence_len starts at {int(lo)} but sequence_types has "
                                f"{len(self.sequence_types)} types")
        set_(self, "sequence_len", (int(lo), int(hi)))
        set_(self, "magnitudes", _magnitudes(self.magnitudes))
        set_(self, "pilot", validate_pilot(self.pilot))
        _check_modelled(self.drawn_types())

    def drawn_types(self) -> set[str]:
        """The fault types these settings can draw (those of the kinds with a share)."""
        drawn = set()
        if self.kinds["single"] > 0:
            drawn |= {t for t, w in self.fault_weights.items() if w > 0}
        if self.kinds["sequence"] > 0:
            drawn |= set(self.sequence_types)
        if self.kinds["paper"] > 0:
            drawn |= set(PAPER_TYPES)
        return drawn

    def with_lambda(self, lam: float) -> ScenarioConfig:
        """The same configuration with λ = ``lam``."""
        return ScenarioConfig(**{**self.to_dict(), "lam": lam})

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON form (:meth:`from_dict` reads it back to an equal configuration)."""
        def plain(v: Any) -> Any:
            if isinstance(v, tuple | list):
                return [plain(x) for x in v]
            if isinstance(v, Mapping):
                return {k: plain(x) for k, x in v.items()}
            return v

        return {f.name: plain(getattr(self, f.name)) for f in fields(self)}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> ScenarioConfig:
        """A configuration from :meth:`to_dict`'s form (or any subset of its keys). A key
        ``faults`` names a :func:`fault_preset`; the other keys override what it sets."""
        if not isinstance(d, Mapping):
            raise GenerateError(f"a scenario configuration must be a mapping, got "
                                f"{type(d).__name__}")
        if "faults" in d:
            rest = {k: v for k, v in d.items() if k != "faults"}
            d = {**fault_preset(d["faults"]), **rest}
        names = {f.name for f in fields(cls)}
        unknown = [k for k in d if k not in names]
        if unknown:
            raise GenerateError(f"unknown scenario setting {unknown[0]!r}; known: "
                                f"{', '.join(sorted(names))}")
        return cls(**dict(d))


def _frame_shares(v: Any) -> dict[str, float]:
    """Validated frame shares in :data:`~tlm_sim.frames.FRAMES` order (a list of names, or one
    name, or ``"+,x"``: equal shares)."""
    if isinstance(v, str):
        v = [x for x in v.split(",") if x.strip()]
    if isinstance(v, list | tuple):
        if not v:
            raise GenerateError(f"frames must name at least one frame of {', '.join(FRAMES)}")
        v = {str(x).strip().lower(): 1.0 for x in v}
    elif isinstance(v, Mapping):
        v = {str(k).strip().lower(): x for k, x in v.items()}
    return _shares(v, tuple(FRAMES), "frames")


def _environment(ranges_in: Any, params_in: Any, wind_in: Any
                 ) -> tuple[dict[str, tuple[float, float]], dict[str, Any], dict[str, Any] | None]:
    """(ranges, params, wind) validated: no parameter both drawn and fixed, no frame parameter
    (the frame sets them), wind ranges given in ``ranges`` moved into the wind setting."""
    if not isinstance(ranges_in, Mapping) or not isinstance(params_in, Mapping):
        raise GenerateError("ranges and params must be mappings by parameter name")
    ranges = {str(k): _range(v, f"range of {k}", -math.inf)
              for k, v in sorted(ranges_in.items())}
    params = {str(k): v for k, v in sorted(params_in.items())}
    clash = sorted(set(ranges) & set(params))
    if clash:
        raise GenerateError(f"{clash[0]} is both drawn (ranges) and fixed (params)")
    framed = [n for n in FRAME_PARAMS if n in ranges or n in params]
    if framed:
        raise GenerateError(f"{framed[0]} is set by each flight's frame: choose frames with "
                            "the frames setting (--frame x, --frame +,x), not with params or "
                            "ranges")
    wind = _wind(wind_in, ranges)
    if wind is not None:
        fixed = [n for n in WIND_PARAMS.values() if n in params]
        if fixed:
            raise GenerateError(f"{fixed[0]} is both drawn (wind) and fixed (params): give the "
                                "wind a one-value range and no calm share (--wind-speed 5 "
                                "--calm-share 0), or draw no wind (wind: null, --no-env) and "
                                "fix it in params")
    return ranges, params, wind


def _wind(w: Any, ranges: dict[str, tuple[float, float]]) -> dict[str, Any] | None:
    """The validated wind setting (see :class:`ScenarioConfig`), None for no wind draw; a
    wind parameter's range in ``ranges`` is moved into it (removed from ``ranges``)."""
    if w is None:
        return None
    if not isinstance(w, Mapping):
        raise GenerateError(f"wind must be a mapping (calm, speed, direction, turbulence) or "
                            f"null for no wind draw, got {w!r}")
    known_keys(w, ("calm", *WIND_PARAMS), "wind")
    calm = fraction(w.get("calm", DEFAULT_WIND["calm"]),
                    "wind: calm (the share of calm flights, --calm-share)")
    out: dict[str, Any] = {"calm": calm}
    for key, name in WIND_PARAMS.items():
        if name in ranges:
            if key in w:
                raise GenerateError(f"{name}: the windy flights' range is given twice (wind "
                                    f"{key} and ranges); give it once")
            v: Any = ranges.pop(name)
        else:
            v = w.get(key, DEFAULT_WIND[key])
        if isinstance(v, int | float) and not isinstance(v, bool):
            v = (v, v)
        out[key] = _range(v, f"wind {key} ({name})", -math.inf if key == "direction" else 0.0)
    return out


def _vibration(v: Any, params: Mapping[str, Any],
               ranges: Mapping[str, tuple[float, float]]) -> dict[str, Any] | None:
    """The validated vibration setting (see :class:`ScenarioConfig`), None for no draw."""
    if v is None:
        return None
    if not isinstance(v, Mapping):
        raise GenerateError(f"vibration must be a mapping (real, ranges) or null for no draw, "
                            f"got {v!r}")
    known_keys(v, ("real", "ranges", "scale"), "vibration")
    scale = None
    if v.get("scale") is not None:
        scale = _range(v["scale"], "vibration: scale (a factor on the vibration gains)", 0.0)
        if scale[0] <= 0.0:
            raise GenerateError(f"vibration: scale must be above 0, got {list(scale)}")
    raw = v.get("ranges", DEFAULT_VIBRATION["ranges"])
    if not isinstance(raw, Mapping):
        raise GenerateError(f"vibration: ranges must be a mapping NAME -> [low, high], got "
                            f"{raw!r}")
    out_ranges: dict[str, tuple[float, float]] = {}
    for name in sorted(raw):
        r = raw[name]
        if isinstance(r, int | float) and not isinstance(r, bool):
            r = (r, r)
        out_ranges[str(name)] = _range(r, f"vibration range of {name}", -math.inf)
    fixed = sorted(n for n in out_ranges if n in params)
    if "real" not in v and fixed:  # the vehicle has its own vibration
        return _with_scale({"real": 0.0, "ranges": out_ranges}, scale, params)
    real = fraction(v.get("real", DEFAULT_VIBRATION["real"]),
                    "vibration: real (the share of real-level flights, --real-share)")
    if real > 0 and fixed:
        raise GenerateError(f"{fixed[0]} is both drawn (real-level vibration, --real-share) "
                            "and fixed (params): give --real-share 0 to fly the vehicle's own "
                            "on every flight")
    drawn_twice = sorted(n for n in out_ranges if n in ranges and not n.startswith("SIM_GYR"))
    if real > 0 and drawn_twice:
        raise GenerateError(f"{drawn_twice[0]} is drawn twice (ranges and the real-level "
                            "vibration); give it once")
    return _with_scale({"real": float(real), "ranges": out_ranges}, scale, params)


def _with_scale(vib: dict[str, Any], scale: tuple[float, float] | None,
                params: Mapping[str, Any]) -> dict[str, Any]:
    """``vib`` with its ``scale`` (only when given, so a setting without one is as before);
    GenerateError when the largest gain a flight can have, times the scale's top, leaves the
    gains' range."""
    if scale is None:
        return vib
    from tlm_sim.params import PARAM_INFO, Params

    defaults = Params.defaults()
    top = max(max(float(params.get(g, defaults[g])),
                  vib["ranges"][g][1] if vib["real"] > 0 and g in vib["ranges"] else 0.0)
              for g in VIB_GAINS)
    limit = min(PARAM_INFO[g].max for g in VIB_GAINS)
    if top * scale[1] > limit:
        raise GenerateError(f"vibration: scale {scale[1]:g} times a gain of {top:g} leaves the "
                            f"gains' range (up to {limit:g})")
    return {**vib, "scale": scale}


def _check_params(params: Mapping[str, Any], ranges: Mapping[str, tuple[float, float]],
                  wind: Mapping[str, Any] | None, frames: Mapping[str, float]) -> None:
    """GenerateError unless every flight's parameters are valid: both ends of every draw, on
    every frame with a share."""
    draws = dict(ranges)
    if wind is not None:
        draws.update({name: wind[key] for key, name in WIND_PARAMS.items()})
    for name, share in frames.items():
        if share <= 0:
            continue
        fp = frame_params(name)
        try:
            Params(fp)
        except ParamError as exc:
            raise GenerateError(f"frame {name!r}: tlm cannot fly it ({exc})") from None
        try:  # names and value ranges, both ends of every draw
            Params({**params, **fp, **{k: lo for k, (lo, _) in draws.items()}})
            Params({**params, **fp, **{k: hi for k, (_, hi) in draws.items()}})
        except ParamError as exc:
            raise GenerateError(f"parameters: {exc}") from None


def frame_params(name: str) -> dict[str, float]:
    """``{"FRAME_CLASS": c, "FRAME_TYPE": t}`` of frame ``name`` of
    :data:`tlm_sim.frames.FRAMES`."""
    f = FRAMES[name]
    return {"FRAME_CLASS": float(f.frame_class), "FRAME_TYPE": float(f.frame_type)}


def flight_conditions(params: Mapping[str, Any]) -> dict[str, Any]:
    """A flight's frame and wind from its parameter overrides (a scenario's ``params``;
    missing names take tlm's defaults, a value that is no number reads NaN):

    ``frame`` (name in :data:`tlm_sim.frames.FRAMES`, None for a combination it lacks),
    ``frame_class``, ``frame_type``, ``calm`` (no mean wind and no turbulence),
    ``wind_spd`` (m/s at full-strength height), ``wind_dir`` (deg, where the wind comes from;
    NaN when calm), ``wind_turb`` (m/s) and ``vibration`` (``"real"`` when the airframe
    vibrates of itself, motor-locked, before any fault: SIM_VIB_MOT_MAX and an
    accelerometer's SIM_ACCn_RND set; else ``"quiet"``)."""
    defaults = Params.defaults()

    def num(name: str) -> float:
        v = params.get(name, defaults[name])
        ok = isinstance(v, int | float) and not isinstance(v, bool)
        return float(v) if ok else math.nan

    cls, typ = num("FRAME_CLASS"), num("FRAME_TYPE")
    try:
        name: str | None = frame_name(cls, typ)
    except FrameError:
        name = None
    spd, turb = num("SIM_WIND_SPD"), num("SIM_WIND_TURB")
    calm = spd == 0 and turb == 0
    real = num("SIM_VIB_MOT_MAX") > 0 and (num("SIM_ACC1_RND") > 0 or num("SIM_ACC2_RND") > 0)
    return {"frame": name, "frame_class": cls, "frame_type": typ, "calm": calm,
            "wind_spd": spd, "wind_dir": math.nan if calm else num("SIM_WIND_DIR"),
            "wind_turb": turb, "vibration": "real" if real else "quiet"}


def _types(v: Any, what: str) -> tuple[str, ...]:
    """Validated fault type names (in FAULT_TYPES order, no repeats), at least one."""
    items = [v] if isinstance(v, str) else v
    try:
        names = [str(x).strip().lower() for x in items]
    except TypeError:
        raise GenerateError(f"{what} must be a list of fault types, got {v!r}") from None
    bad = [n for n in names if n not in FAULT_TYPES]
    if bad:
        raise GenerateError(f"{what}: unknown fault type {bad[0]!r}; choose from "
                            f"{', '.join(FAULT_TYPES)}")
    if not names:
        raise GenerateError(f"{what} must name at least one fault type")
    return tuple(t for t in FAULT_TYPES if t in names)


def _check_modelled(types: set[str]) -> None:
    """GenerateError naming the first type (label order) whose parameters tlm does not model
    (its flights could not fly)."""
    from tlm_sim.params import is_modelled

    for t in FAULT_TYPES:
        if t in types:
            missing = [p for p in FAULT_TYPES[t].params_start if not is_modelled(p)]
            if missing:
                raise GenerateError(f"fault type {t}: tlm does not model {', '.join(missing)} "
                                    "yet; leave it out (--faults TYPE,TYPE,... or "
                                    "fault_weights / sequence_types)")


def fault_preset(name: Any) -> dict[str, Any]:
    """The settings of a named choice of fault types (``tlm generate --faults``):

    * ``paper``: the paper's four types in single-fault and paper-style flights (20 % none,
      40 % single, 40 % paper);
    * ``all``: single faults of every type (labels 1-14), the paper sequence and sequences
      of the new types (20 % none, 40 % single, 20 % paper, 20 % sequence): the defaults;
    * ``new``: the new types only (labels 5-14): 20 % none, 40 % single, 40 % sequence;
    * ``single``: single faults of every type (20 % none, 80 % single);
    * a list of types (``"gps_glitch,battery"`` or a list): single faults and sequences of
      those types (20 % none, 40 % single, 40 % sequence; sequences need two or more).
    """
    if not isinstance(name, str | list | tuple):
        raise GenerateError(f"faults must be paper, all, new, single or a list of types, got "
                            f"{name!r}")
    key = name.strip().lower() if isinstance(name, str) else None
    every = {t: 1.0 for t in FAULT_TYPES}
    if key == "paper":
        return {"kinds": {"none": 0.2, "single": 0.4, "paper": 0.4},
                "fault_weights": {t: 1.0 for t in PAPER_TYPES}}
    if key == "all":
        return {"kinds": {"none": 0.2, "single": 0.4, "paper": 0.2, "sequence": 0.2},
                "fault_weights": every, "sequence_types": list(new_types())}
    if key == "new":
        return {"kinds": {"none": 0.2, "single": 0.4, "sequence": 0.4},
                "fault_weights": {t: 1.0 for t in new_types()},
                "sequence_types": list(new_types())}
    if key == "single":
        return {"kinds": {"none": 0.2, "single": 0.8}, "fault_weights": every}
    types = _types([x for x in name.split(",") if x.strip()] if isinstance(name, str)
                   else name, "faults")
    kinds = {"none": 0.2, "single": 0.4, "sequence": 0.4} if len(types) > 1 else {
        "none": 0.2, "single": 0.8}
    return {"kinds": kinds, "fault_weights": {t: 1.0 for t in types},
            "sequence_types": list(types), "sequence_len": [min(2, len(types)),
                                                            min(4, len(types))]}


def _magnitudes(d: Any) -> dict[str, dict[str, Any]]:
    """Every knob of :func:`magnitude_knobs`: the configured value (validated) or its
    default; ranges as (low, high), choices as lists."""
    if not isinstance(d, Mapping):
        raise GenerateError(f"magnitudes must be a mapping fault type -> knob -> value, got "
                            f"{type(d).__name__}")
    every = magnitude_knobs()
    unknown = [t for t in d if t not in every]
    if unknown:
        raise GenerateError(f"magnitudes: no knobs for {unknown[0]!r}; types with knobs: "
                            f"{', '.join(every)}")
    out: dict[str, dict[str, Any]] = {}
    for t, knobs in every.items():
        given = d.get(t) or {}
        if not isinstance(given, Mapping):
            raise GenerateError(f"magnitudes of {t} must be a mapping knob -> value")
        bad = [k for k in given if k not in knobs]
        if bad:
            raise GenerateError(f"magnitudes of {t}: unknown knob {bad[0]!r}; known: "
                                f"{', '.join(knobs)}")
        out[t] = {}
        for k, (how, limits, default, _, _) in knobs.items():
            v = given.get(k, default)
            what = f"magnitudes {t}.{k}"
            if how == "range":
                if isinstance(v, int | float) and not isinstance(v, bool):
                    v = (v, v)
                lo, hi = _range(v, what, -math.inf)
                if lo < limits[0] or hi > limits[1]:
                    raise GenerateError(f"{what} must lie in [{limits[0]:g}, {limits[1]:g}], "
                                        f"got ({lo:g}, {hi:g})")
                out[t][k] = (lo, hi)
            else:
                vals = [v] if isinstance(v, str | int) else list(v)
                vals = [x.lower() if isinstance(x, str) else x for x in vals]
                if not vals or any(x not in limits for x in vals):
                    raise GenerateError(f"{what} must be one or more of "
                                        f"{', '.join(map(str, limits))}, got {v!r}")
                out[t][k] = vals
    return out


def fault_params(ftype: str, knobs: Mapping[str, Any], lat_deg: float
                 ) -> tuple[dict[str, float], dict[str, float]] | None:
    """(params_start, params_end) of a fault of ``ftype`` with drawn knob values (its record's
    ``params`` at home latitude ``lat_deg`` [deg]; each is cleared to the type's
    ``params_end`` value, else tlm's default), None for a type without knobs (it flies its
    type's parameters)."""
    from tlm_sim.params import Params

    record = fault_type_record(ftype)
    if record is None or record.params is None:
        return None
    start = dict(record.params(knobs, lat_deg))
    ends = FAULT_TYPES[ftype].params_end
    defaults = Params.defaults()
    return start, {n: float(ends[n]) if n in ends else float(defaults[n]) for n in start}


def _draw_magnitudes(rng: np.random.Generator, ftype: str, cfg: ScenarioConfig
                     ) -> dict[str, Any]:
    """One draw of every knob of ``ftype``'s record, in its order: a range uniformly in the
    configured (low, high) (a knob no configuration sets: its default), rounded to the knob's
    decimals; a choice one of the configured values."""
    out: dict[str, Any] = {}
    record = fault_type_record(ftype)
    for k, knob in (record.knobs if record is not None else {}).items():
        v = cfg.magnitudes[ftype][k] if knob.configurable else knob.default
        if knob.how == "range":
            out[k] = round(float(rng.uniform(*v)), knob.decimals)
        else:
            out[k] = v[int(rng.integers(len(v)))]
    return out


class FlightSpec(NamedTuple):
    """The arguments of :func:`tlm_sim.fly` for one flight (``sticks``: the stick script of a
    pilot-flown flight, whose mission gives only the home)."""

    mission: Mission
    schedule: FaultSchedule
    params: Params
    seed: int
    profile: str
    sticks: Any = None


@dataclass(frozen=True)
class Scenario:
    """One flight of a data set, as plain data (JSON-ready through :meth:`to_dict`).

    Attributes:
        flight: flight index in the data set (0-based).
        seed: the flight's seed (all noise draws in flight).
        kind: ``none``, ``single`` or ``paper``.
        mission: recipe, see :func:`mission_from_recipe`.
        faults: the fault schedule in file form (``FaultSchedule.to_dict``), λ applied.
        params: parameter overrides (drawn environment + fixed parameters).
        profile: ArduPilot profile of the flight.
        lam: λ the holds were scaled by.
        mission_sha1: hash of the mission's waypoints, checked when the mission is rebuilt.
        dropped: faults left out because they would start after the flight can end.
        frame: the frame's name (:data:`tlm_sim.frames.FRAMES`); ``params`` holds its
            ``FRAME_CLASS`` / ``FRAME_TYPE`` (records of a tlm before frames: ``+``).
    """

    flight: int
    seed: int
    kind: str
    mission: dict[str, Any]
    faults: dict[str, Any]
    params: dict[str, float]
    profile: str = "current"
    lam: float = 1.0
    mission_sha1: str | None = None
    dropped: int = 0
    frame: str = "+"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Scenario:
        """Read :meth:`to_dict`'s form back."""
        try:
            return cls(**{f.name: d[f.name] for f in fields(cls) if f.name in d})
        except TypeError as exc:
            raise GenerateError(f"not a scenario record: {exc}") from None

    @property
    def fault_types(self) -> list[str]:
        """Fault types of the schedule, in order."""
        return [f["fault"] for f in self.faults.get("faults", [])]

    @property
    def conditions(self) -> dict[str, Any]:
        """The flight's frame and wind (:func:`flight_conditions` of its parameters)."""
        return flight_conditions(self.params)

    def realise(self) -> FlightSpec:
        """Mission, fault schedule, parameters, seed and profile to fly (``tlm_sim.fly``).

        Raises GenerateError when the rebuilt mission's hash differs from ``mission_sha1``
        (the scenario was drawn by a tlm whose mission generator differs), or when ``frame``
        is not the frame of the parameters' ``FRAME_CLASS`` / ``FRAME_TYPE`` (an edited
        record)."""
        flown = self.conditions["frame"]
        if flown != self.frame:
            raise GenerateError(f"flight {self.flight}: frame {self.frame!r}, but its "
                                f"parameters FRAME_CLASS / FRAME_TYPE are those of "
                                f"{flown!r}")
        mission = mission_from_recipe(self.mission)
        if self.mission_sha1 is not None and mission_hash(mission) != self.mission_sha1:
            raise GenerateError(f"flight {self.flight}: the mission rebuilt from its recipe "
                                "differs from the one flown (the data set was made by another "
                                "tlm version)")
        try:
            schedule = FaultSchedule.from_dict(self.faults)
            params = Params(self.params)
        except (FaultScheduleError, ParamError) as exc:
            raise GenerateError(f"flight {self.flight}: {exc}") from None
        sticks = None
        if self.mission.get("source") == "pilot":
            from tlm_sim.mission.sticks import StickScript

            sticks = StickScript(tuple(pilot_script(self.mission["pilot"])[0]))
        return FlightSpec(mission, schedule, params, int(self.seed), self.profile, sticks)


def mission_hash(mission: Mission) -> str:
    """SHA-1 (hex, 16 characters) of a mission's home and waypoints (float64 bytes)."""
    h = hashlib.sha1(np.asarray(mission.home, dtype=np.float64).tobytes())
    h.update(np.ascontiguousarray(mission.waypoints, dtype=np.float64).tobytes())
    return h.hexdigest()[:16]


def mission_from_recipe(recipe: Mapping[str, Any]) -> Mission:
    """Build a mission from its recipe.

    ``{"source": "builtin", "id": k}``: built-in mission k as is; with ``"alt_seed": s`` (and
    ``"alt_range"``) its shape with a fresh altitude profile (``rng.uniform`` per waypoint from
    ``default_rng(s)``, Savitzky-Golay 21/3). ``{"source": "random", "seed": s, "home": [...],
    "n_waypoints": n, "alt_range": [lo, hi]}``: ``random_loop(home, default_rng(s))`` and
    ``make_mission`` drawing the altitudes from the same generator (as the reference driver).
    ``{"source": "pilot", "home": [...], "pilot": draw}``: a pilot-flown flight's placeholder
    at its home (its sticks: :meth:`Scenario.realise`).
    """
    try:
        if recipe.get("source") == "pilot":
            return pilot_home_mission(tuple(float(v) for v in recipe["home"]))
        return _mission_cached(_freeze(recipe))
    except (MissionError, KeyError, TypeError, ValueError) as exc:
        raise GenerateError(f"bad mission recipe {dict(recipe)!r}: {exc}") from None


def _freeze(d: Mapping[str, Any]) -> tuple[tuple[str, Any], ...]:
    return tuple(sorted((k, tuple(v) if isinstance(v, list) else v) for k, v in d.items()))


@lru_cache(maxsize=64)
def _mission_cached(frozen: tuple[tuple[str, Any], ...]) -> Mission:
    r = dict(frozen)
    source = r["source"]
    if source == "builtin":
        base = builtin_mission(int(r["id"]))
        if r.get("alt_seed") is None:
            return base
        rng = np.random.default_rng(int(r["alt_seed"]))
        return make_mission(base.raw_waypoints, base.n_waypoints, tuple(r["alt_range"]),
                            seed=int(r["alt_seed"]), savgol=base.savgol, home=base.home, rng=rng,
                            name=f"builtin-{int(r['id'])}-alt{int(r['alt_seed'])}")
    if source == "random":
        seed = int(r["seed"])
        home = tuple(float(v) for v in r["home"])
        rng = np.random.default_rng(seed)
        raw = random_loop(home, rng)
        return make_mission(raw, int(r["n_waypoints"]), tuple(r["alt_range"]), seed=seed,
                            home=home, rng=rng, name=f"random-{seed}")
    raise ValueError(f"unknown mission source {source!r}")


def _stream(run_seed: int, flight: int, stream: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(run_seed, spawn_key=(flight, stream)))


def _pick(rng: np.random.Generator, shares: Mapping[str, float]) -> str:
    """One name by its share (one uniform draw; names in the mapping's order)."""
    names = list(shares)
    w = np.array([shares[n] for n in names], dtype=np.float64)
    cum = np.cumsum(w) / w.sum()
    i = int(np.searchsorted(cum, rng.random(), side="right"))
    return names[min(i, len(names) - 1)]


def _draw_faults(rng: np.random.Generator, kind: str, cfg: ScenarioConfig,
                 origin: float | None = None) -> list[tuple[str, float, float]]:
    """(type, start s, end s) per fault, holds scaled by λ, rounded to 0.1 s; times count from
    ``origin`` [s] (None: ``auto_start_s``)."""
    if kind == "none":
        return []
    t = cfg.auto_start_s if origin is None else origin
    if kind == "single":
        ftype = _pick(rng, cfg.fault_weights)
        start = round(t + float(rng.uniform(*cfg.single_start_s)), 1)
        hold = round(float(rng.uniform(*cfg.hold_s)) * cfg.lam, 1)
        return [(ftype, start, round(start + max(hold, 0.1), 1))]
    if kind == "sequence":
        order = _draw_sequence(rng, cfg)
    else:
        order = [PAPER_FIRST[i] for i in rng.permutation(len(PAPER_FIRST))] if cfg.shuffle \
            else list(PAPER_FIRST)
        order.append("rc")
    out = []
    for ftype in order:
        start = round(t + float(rng.uniform(*cfg.gap_s)), 1)
        hold = round(float(rng.uniform(*cfg.hold_s)) * cfg.lam, 1)
        t = round(start + max(hold, 0.1), 1)
        out.append((ftype, start, t))
    return out


def _draw_sequence(rng: np.random.Generator, cfg: ScenarioConfig) -> list[str]:
    """Distinct fault types of a ``sequence`` flight in flying order (RC last if drawn)."""
    types = list(cfg.sequence_types)
    w = np.array([cfg.fault_weights.get(t, 0.0) for t in types], dtype=np.float64)
    if w.sum() <= 0:
        w = np.ones(len(types))
    lo, hi = cfg.sequence_len
    n = min(int(rng.integers(lo, hi + 1)), len(types), int(np.count_nonzero(w)))
    picked = [types[i] for i in rng.choice(len(types), size=n, replace=False, p=w / w.sum())]
    return [t for t in picked if t != "rc"] + [t for t in picked if t == "rc"]


def _draw_mission(rng: np.random.Generator, cfg: ScenarioConfig) -> dict[str, Any]:
    source = _pick(rng, cfg.missions)
    if source == "builtin":
        k = int(BUILTIN_IDS[int(rng.integers(len(BUILTIN_IDS)))])
        alt_seed = int(rng.integers(2**31))
        if cfg.builtin_altitudes == "keep":
            return {"source": "builtin", "id": k}
        return {"source": "builtin", "id": k, "alt_seed": alt_seed,
                "alt_range": list(cfg.alt_range)}
    return {"source": "random", "seed": int(rng.integers(2**31)), "home": list(cfg.home),
            "n_waypoints": cfg.n_waypoints, "alt_range": list(cfg.alt_range)}


def sample_scenario(run_seed: int, flight: int, cfg: ScenarioConfig) -> Scenario:
    """Flight ``flight`` of the run seeded ``run_seed`` (see the module docstring).

    Pure: the same arguments give the same scenario in any process.
    """
    for what, v in (("seed", run_seed), ("flight", flight)):
        if isinstance(v, bool) or not isinstance(v, int | np.integer) or v < 0:
            raise GenerateError(f"{what} must be a whole number >= 0, got {v!r}")
    run_seed, flight = int(run_seed), int(flight)
    kind = _pick(_stream(run_seed, flight, _S_KIND), cfg.kinds)
    pilot = None
    if cfg.pilot is not None and cfg.pilot["share"] > 0:
        pilot = draw_pilot(_stream(run_seed, flight, _S_PILOT), cfg.pilot)
    origin = descent = None
    if pilot is None:
        recipe = _draw_mission(_stream(run_seed, flight, _S_MISSION), cfg)
    else:
        recipe = {"source": "pilot", "home": list(cfg.home), "pilot": pilot}
        _, origin, descent = pilot_script(pilot)
    mission = mission_from_recipe(recipe)
    drawn = _draw_faults(_stream(run_seed, flight, _S_FAULTS), kind, cfg, origin)
    env = _stream(run_seed, flight, _S_ENV)
    params = dict(cfg.params)
    for name, (lo, hi) in cfg.ranges.items():
        params[name] = round(float(env.uniform(lo, hi)), 3)
    frame = _pick(_stream(run_seed, flight, _S_FRAME), cfg.frames)
    params.update(frame_params(frame))
    if cfg.wind is not None:
        params.update(_draw_wind(_stream(run_seed, flight, _S_WIND), cfg.wind))
    if cfg.vibration is not None:
        vib_rng = _stream(run_seed, flight, _S_VIBRATION)
        params.update(_draw_vibration(vib_rng, cfg.vibration))
        params.update(_scale_vibration(vib_rng, cfg.vibration, params))
    params = dict(sorted(params.items()))
    seed_ss = np.random.SeedSequence(run_seed, spawn_key=(flight, _S_SEED))
    seed = int(seed_ss.generate_state(1, np.uint32)[0] & 0x7FFFFFFF)
    # drop faults that could not happen: past the longest the flight can last (whole seconds)
    limit = (math.floor(descent) if descent is not None else
             math.floor(max_duration_s(mission, profile_params(cfg.profile, params))))
    kept = drawn[:next((k for k, d in enumerate(drawn) if d[2] > limit), len(drawn))]
    mag = _stream(run_seed, flight, _S_MAGNITUDE)
    faults = []
    for t, s, e in kept:
        p = fault_params(t, _draw_magnitudes(mag, t, cfg), mission.home[0])
        try:
            faults.append(Fault(t, Trigger("time", s), Trigger("time", e),
                                params_start=p[0] if p else None,
                                params_end=p[1] if p else None))
        except FaultScheduleError as exc:
            raise GenerateError(f"flight {flight}: {exc}") from None
    schedule = FaultSchedule(tuple(faults))
    return Scenario(flight=flight, seed=seed, kind=kind, mission=recipe,
                    faults=schedule.to_dict(), params=params, profile=cfg.profile,
                    lam=cfg.lam, mission_sha1=mission_hash(mission),
                    dropped=len(drawn) - len(kept), frame=frame)


def _draw_vibration(rng: np.random.Generator, vib: Mapping[str, Any]) -> dict[str, float]:
    """The airframe of one flight (stream 8): with the ``real`` share every parameter of the
    ``ranges`` uniform (name order, rounded to 0.001), else none. All draws are made either
    way."""
    real = float(rng.random()) < vib["real"]
    drawn = {name: round(float(rng.uniform(lo, hi)), 3)
             for name, (lo, hi) in sorted(vib["ranges"].items())}
    return drawn if real else {}


def _scale_vibration(rng: np.random.Generator, vib: Mapping[str, Any],
                     params: Mapping[str, float]) -> dict[str, float]:
    """The flight's vibration gains times one factor uniform in the setting's ``scale`` (the
    next draw of stream 8, after the airframe's; the products rounded to 1e-6), the gains
    ``params`` lack at tlm's default; nothing without a scale."""
    if vib.get("scale") is None:
        return {}
    from tlm_sim.params import Params

    lo, hi = vib["scale"]
    factor = float(rng.uniform(lo, hi))
    defaults = Params.defaults()
    return {g: round(factor * float(params.get(g, defaults[g])), 6) for g in VIB_GAINS}


def _draw_wind(rng: np.random.Generator, wind: Mapping[str, Any]) -> dict[str, float]:
    """The wind parameters of one flight (stream 7): calm (speed and turbulence 0) with the
    ``calm`` share, else speed, direction and turbulence uniform in their ranges (rounded
    to 0.001). All four draws are made either way."""
    calm = float(rng.random()) < wind["calm"]
    drawn = {name: round(float(rng.uniform(*wind[key])), 3) for key, name in WIND_PARAMS.items()}
    if calm:
        return {"SIM_WIND_SPD": 0.0, "SIM_WIND_TURB": 0.0}
    return drawn
