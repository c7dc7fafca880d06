"""Fit tlm's vehicle to one log's steady segment by flying it (``tlm fit``, issue 40).

The vehicle starts from the log's own parameters (its PARM: controller gains, motor and
battery settings, frame), those tlm models. Then tlm flies a hover (:func:`hover_mission`)
and measures it as it measures the log (:func:`tlm_process.fit.stats.segment_stats`), and
adjusts, a few flights in turn:

* ``TLM_HOVER_THR`` (the frame model's hover thrust fraction) to the log's hover throttle;
* the accelerometers' vibration per axis (``TLM_VIB_ACC_X/Y/Z`` on ``SIM_ACCn_RND``
  :data:`ACC_AMP`, motor-locked at ``SIM_VIB_MOT_MAX``) to IMU 0's accel standard deviation
  per axis;
* the gyros' per axis (``TLM_VIB_GYR_X/Y/Z`` on ``SIM_GYRn_RND`` :data:`GYR_AMP`) to the gyro
  standard deviation per axis;
* the gusts (``SIM_WIND_TURB``, correlated over ``TLM_TURB_TC`` :data:`TURB_TC`) to the mean
  of the ATT roll and pitch standard deviations (:func:`attitude_std`);
* the centre of gravity (``TLM_CG_X`` / ``_Y``) and the rotors' unequal reaction torque
  (``TLM_YAW_ASYM``) to how unequally the log's motors run: its mean motor outputs projected
  on the frame's pitch, roll and yaw factors (:func:`tlm_process.fit.stats.motor_asymmetry`;
  a real airframe is never balanced, and a detector trained on a balanced one calls the log's
  unequal motors a fault).

* with a log that has VIBE (Copter 3.4 on): the rotor frequency (``SIM_VIB_MOT_MAX``) to
  how the log's VIBE stands to its logged accel noise (:func:`_rotor_step`). VIBE measures the
  vibration at the sensor's own rate, the logged IMU rows see it through the 20 Hz INS filter
  (about (20 Hz / f)^2 at a rotor frequency f), so their ratio grows with f squared; fitting
  the accel noise alone at an assumed frequency leaves VIBE tens of per cent off, and a
  detector that reads VIBE calls the difference a fault.

A statistic is the flight's own motion and the sensor's noise together; the motion (the
statistic of a first flight without vibration or gusts, the *floor*) is taken out in
quadrature when a gain is scaled. The rate-tracking error is not fitted: it follows from the
gyro noise and the gusts through tlm's controllers, and the report compares it too; the gusts
are the same on every axis, so roll and pitch are fitted as one. A log's rotor
frequency is not in its 25-50 Hz IMU rows: without VIBE ``SIM_VIB_MOT_MAX`` is
:data:`ROTOR_HZ`, the rotors' speed lags their commands by :data:`ROTOR_TC`, they turn
:data:`MOT_SPREAD` apart and their vibration goes with their command squared about
:data:`CMD_REF` (a SITL log's own SIM_* parameters are its simulator's, not its vehicle's, and
are not taken, but for the pack it flew: :func:`log_battery`).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from tlm_process.fit.stats import ASYM_NAMES, STAT_NAMES, motor_asymmetry, segment_stats

__all__ = ["ACC_AMP", "ALT_HOLD", "CMD_REF", "FIT_SEEDS", "FIT_STATS", "GYR_AMP", "MOT_SPREAD",
           "ROTOR_HZ", "ROTOR_HZ_RANGE", "ROTOR_TC", "TURB_TC", "VIBE_STATS", "FitError",
           "FitResult", "althold_hover_script", "attitude_std", "copter33_params", "fit_steps",
           "fit_vehicle", "fitted_stats", "fly_hover", "fly_hover_stats", "hover_mission",
           "hover_window", "log_battery", "log_vehicle_params", "tracking_error_std"]

#: accelerometer vibration amplitude per motor [m/s^2] the per-axis gains scale (SITL's
#: autotest quad's SIM_ACCn_RND)
ACC_AMP = 5.0
#: gyro vibration amplitude [deg/s at full throttle] the per-axis gains scale (the autotest's)
GYR_AMP = 20.0
#: rotor frequency at full command [Hz] when the log does not set SIM_VIB_MOT_MAX: ~65 Hz at
#: hover, where a 10-inch-propeller quad's rotors turn, and low enough for the rotor content to
#: pass the 20 Hz INS filters into the logged IMU rows as real logs show it (at SITL's
#: autotest 350 Hz almost none does)
ROTOR_HZ = 150.0
#: the rotor frequencies [Hz at full command] a fit from VIBE keeps to
ROTOR_HZ_RANGE = (50.0, 500.0)
#: flights that find the rotor frequency before the calibrations (a log with VIBE)
ROTOR_START_FLIGHTS = 3
#: VIBE per axis, fitted (through the rotor frequency) where the log has it
VIBE_STATS = ("vibe_x", "vibe_y", "vibe_z")
#: rotor speed time constant [s] the vibration follows (``TLM_ROTOR_TC``): a motor, its ESC
#: and its propeller answer a command change in tens of milliseconds; without it the rate
#: controller's answer to the gyro vibration modulates the vibration's own frequency and
#: rectifies it into a wandering gyro offset that tilts the EKF's attitude by degrees
#: (tests/test_noise_structure.py)
ROTOR_TC = 0.05
#: spread of the rotors' speeds in the vibration (``TLM_VIB_SPREAD``): a few per cent, as
#: a real copter's rotors turn apart; their vibrations then beat within seconds, so one hover's
#: statistics scatter by 1-3 % between seeds instead of 8-18 % (rotors turning alike drift in
#: and out of phase over tens of seconds)
MOT_SPREAD = 0.03
#: motor command at which the vibration amplitudes apply, each rotor's going with its command
#: squared (``TLM_VIB_CMD_REF``): about a hover's, so the gains are the hover's, and on the
#: ground at idle the vibration is a tenth (real rotors' imbalance forces go with rpm squared;
#: SITL's accel vibration is as strong at idle, which on a real-level airframe upsets the
#: EKF and the land detector after touchdown)
CMD_REF = 0.55
#: correlation time [s] of the fitted gusts (``TLM_TURB_TC``): a real hover's lean angle follows
#: the air over seconds (log171: most of the roll's variance below 2 Hz, the desired roll
#: carrying it), where SITL's own gusts decorrelate in 41 ms
TURB_TC = 1.0
#: the gusts' standard deviation the fit starts from [m/s] (``SIM_WIND_TURB``)
TURB_START = 0.5
#: the rotors' thrust fluctuation of the fit's calibration flights (``TLM_ROTOR_RND``, a
#: fraction of each rotor's thrust; correlation time TLM_ROTOR_RND_TC's default 1 s)
ROTOR_RND_CAL = 0.02
#: the roll / pitch statistics the gyro gains and the rotors' fluctuation share: (gyro std,
#: rate tracking error std) per axis, with the gyro gain of that axis
SHARED_STATS = (("TLM_VIB_GYR_X", "gyr_x_std_dps", "rate_roll_err_std_dps"),
                ("TLM_VIB_GYR_Y", "gyr_y_std_dps", "rate_pitch_err_std_dps"))
#: the attitude statistic of each axis (the gusts are fitted to their mean)
AXIS_ATTITUDE = {"TLM_VIB_GYR_X": "roll_std_deg", "TLM_VIB_GYR_Y": "pitch_std_deg"}
#: flights (seeds) each fitting step averages
FIT_SEEDS = 2
#: steps before the fitting ones (the floor and the two calibrations), counted for ``progress``
#: whether or not the calibrations are flown
SETUP_STEPS = 3
#: fitting steps averaged for the result (the second half of them) when there are at least
#: this many; fewer: the step with the smallest largest error
TAIL_MIN = 3
#: exponent of the excess ratio a gain follows per fitting flight (< 1: damped)
DAMPING = 0.8
#: statistics the fit drives to the log's (the others are compared, not fitted)
FIT_STATS = ("hover_thr", "acc_x_std", "acc_y_std", "acc_z_std",
             "gyr_x_std_dps", "gyr_y_std_dps", "gyr_z_std_dps")
#: the balance knobs: the motor asymmetry each is fitted to, the slope the fit starts from
#: [us per unit] and the largest value it gives. A 1 cm centre-of-gravity offset makes
#: ~20-25 us of pitch or roll output on the default quad (roll's sign is opposite:
#: ArduPilot's roll factor is negative on the right); TLM_YAW_ASYM 0.1 makes -35 us of yaw
#: output (the clockwise rotors work harder)
ASYM_KNOBS: dict[str, tuple[str, float, float]] = {
    "TLM_CG_X": ("mot_pitch_us", 2000.0, 0.05),
    "TLM_CG_Y": ("mot_roll_us", -2000.0, 0.05),
    "TLM_YAW_ASYM": ("mot_yaw_us", -350.0, 0.5)}
#: ArduCopter's ALT_HOLD mode number: a segment flown in it is fitted with ALT_HOLD hovers
ALT_HOLD = 2
#: hover flown per fit flight [s], and what of it is measured (after settling)
HOVER_S = 60
SETTLE_S = 8.0
#: and before its end (the copter turns for its RTL there) [s]
END_S = 4.0


class FitError(RuntimeError):
    """A fit that cannot go on: a hover of the vehicle being fitted did not hold."""


@dataclass
class FitResult:
    """``params``: the fitted parameters (the log's that tlm models, and the fitted ones);
    ``log``: the log's statistics; ``tlm``: tlm's with ``params`` (the best fitting step's,
    a mean over its flights);
    ``history``: each flight's statistics and knobs; ``dropped``: the log's parameters tlm
    could not take, with why."""

    params: dict[str, float]
    log: dict[str, float]
    tlm: dict[str, float]
    history: list[dict[str, float]] = field(default_factory=list)
    dropped: dict[str, str] = field(default_factory=dict)


def hover_mission(alt_m: float = 10.0, hold_s: int = HOVER_S):
    """A hover: take off to ``alt_m``, hold ``hold_s`` seconds a few metres off home, RTL."""
    from tlm_sim.geo import HOME_CMAC
    from tlm_sim.mission import Mission

    lat, lon = HOME_CMAC[0], HOME_CMAC[1]
    wp = np.array([[lat, lon, alt_m], [lat + 2e-5, lon, alt_m]])
    return Mission(wp, hold_s=np.array([0.0, float(hold_s)]), name="hover")


#: Copter 3.3's attitude-controller parameters and their 3.4+ names (Copter 3.4.0 release notes:
#: RATE_ became ATC_RAT_, STB_ became ATC_ANG_); a 3.3 rate controller filtered only the D
#: term's input (RATE_*_FILT_HZ: ATC_RAT_*_FLTD), the yaw one all of it (ATC_RAT_YAW_FLTE)
COPTER33_NAMES: dict[str, str] = {
    **{f"RATE_{a}_{t}": f"ATC_RAT_{a}_{t}" for a in ("RLL", "PIT", "YAW")
       for t in ("P", "I", "D", "IMAX")},
    "RATE_RLL_FILT_HZ": "ATC_RAT_RLL_FLTD", "RATE_PIT_FILT_HZ": "ATC_RAT_PIT_FLTD",
    "RATE_YAW_FILT_HZ": "ATC_RAT_YAW_FLTE",
    **{f"STB_{a}_P": f"ATC_ANG_{a}_P" for a in ("RLL", "PIT", "YAW")},
    # the motors' battery compensation (MOT_THST_BAT_* became MOT_BAT_VOLT_*) and the battery
    # failsafe (FS_BATT_*: 0 off, 1 land, 2 RTL, as BATT_FS_LOW_ACT)
    "MOT_THST_BAT_MAX": "MOT_BAT_VOLT_MAX", "MOT_THST_BAT_MIN": "MOT_BAT_VOLT_MIN",
    "FS_BATT_VOLTAGE": "BATT_LOW_VOLT", "FS_BATT_MAH": "BATT_LOW_MAH",
    "FS_BATT_ENABLE": "BATT_FS_LOW_ACT",
}
#: a fully charged LiPo cell [V], and the charge a cell is taken to have at arming (the
#: cell count is the arming voltage over it, rounded)
CELL_FULL_V = 4.2
CELL_AT_ARMING_V = 4.1
#: Copter 3.3's rate-controller output range: IMAX was in it, 3.4+ has 0..1
COPTER33_OUTPUT = 4500.0


def copter33_params(values: Mapping[str, float]) -> dict[str, float]:
    """``values`` with Copter 3.3's attitude-controller, motor-battery and battery-failsafe
    parameters under their later names and scales (a log that has the 3.4+ names is returned
    unchanged). Copter 3.4 moved them
    "automatically, scales adjusted": the rate P and D (and I, in the same output units) 10 %
    lower on X, V and H quads and 27 % higher on other frames, IMAX from the 4500 output range
    to 0..1 (ArduCopter release notes 3.4.0-rc1, item 5). ``FRAME`` (3.x: 0 +, 1 X, 2 V, 3 H)
    picks the factor."""
    out = dict(values)
    if "RATE_RLL_P" not in out or "ATC_RAT_RLL_P" in out:
        return out
    frame = int(out.get("FRAME", out.get("FRAME_TYPE", 1)))
    factor = 0.9 if frame in (1, 2, 3) else 1.27
    for old, new in COPTER33_NAMES.items():
        if old not in out:
            continue
        v = float(out.pop(old))
        if old.endswith(("_P", "_I", "_D")) and old.startswith("RATE_"):
            v *= factor
        elif old.endswith("_IMAX"):
            v /= COPTER33_OUTPUT
        out[new] = v
    return out


def log_battery(tables: Mapping[str, Any], log_params: Mapping[str, float]) -> dict[str, float]:
    """The log's battery for tlm to fly: the cell count from the voltage at arming (BAT.Volt,
    or Copter 3.x's CURR.Volt in V or cV) as ``SIM_BATT_VOLTAGE`` and the frame's full-pack
    ``TLM_MAX_VOLT`` (cells x :data:`CELL_FULL_V`, so a full pack gives the same thrust scale),
    and ``BATT_CAPACITY`` as the simulated pack's ``SIM_BATT_CAP_AH`` (a simulator's log: its own
    ``SIM_BATT_CAP_AH``, which SITL and tlm leave at 0, a pack that never empties). Empty when
    the log has no battery voltage."""
    volts = None
    for name in ("BAT", "CURR"):
        df = tables.get(name)
        if df is not None and len(df) and "Volt" in df:
            v = pd.to_numeric(df["Volt"], errors="coerce").dropna()
            v = v[v > 0]
            if len(v):
                volts = float(v.iloc[: max(len(v) // 20, 1)].median())
                break
    out: dict[str, float] = {}
    if volts is not None:
        if volts > 100.0:  # Copter 3.x CURR.Volt in centivolts
            volts *= 0.01
        cells = max(round(volts / CELL_AT_ARMING_V), 1)
        out["SIM_BATT_VOLTAGE"] = out["TLM_MAX_VOLT"] = round(cells * CELL_FULL_V, 2)
    cap = float(log_params.get("BATT_CAPACITY", 0.0) or 0.0)
    if "SIM_BATT_CAP_AH" in log_params:
        # a simulator's log (SITL's, tlm's): the pack it flew, 0 = never empty, whatever the
        # autopilot's BATT_CAPACITY says (3300 mAh at SITL's defaults)
        out["SIM_BATT_CAP_AH"] = float(log_params["SIM_BATT_CAP_AH"])
    elif cap > 0:
        out["SIM_BATT_CAP_AH"] = cap * 1e-3
    return out


def log_vehicle_params(log_params: Mapping[str, float]) -> tuple[dict[str, float], dict[str, str]]:
    """The log's parameters tlm models, where they differ from tlm's defaults, each checked
    alone (a value out of tlm's range is dropped, with why); Copter 3.3's attitude controller
    under its 3.4+ names (:func:`copter33_params`), renamed ones under their present names
    (:data:`tlm_sim.params.ALIASES`: ``ACRO_RP_P`` x 45 is ``ACRO_RP_RATE``); Copter 3.x's
    ``FRAME`` becomes ``FRAME_CLASS`` 1 (quad) and ``FRAME_TYPE``."""
    from tlm_sim.params import ALIASES, PARAM_INFO, ParamError, Params

    defaults = Params.defaults()
    values = copter33_params(log_params)
    for old, alias in ALIASES.items():  # older names (ACRO_RP_P, ...) under the current ones
        if old in values and alias.target not in values:
            values[alias.target] = alias.convert(float(values.pop(old)))
    if "FRAME" in values and "FRAME_CLASS" not in values:
        values["FRAME_CLASS"], values["FRAME_TYPE"] = 1.0, float(values.pop("FRAME"))
    keep: dict[str, float] = {}
    dropped: dict[str, str] = {}
    for name, v in values.items():
        info = PARAM_INFO.get(name)
        if info is None or not info.modelled or name.startswith(("SIM_", "TLM_")):
            continue
        if math.isclose(defaults[name], v, rel_tol=1e-6, abs_tol=1e-9):
            continue
        try:
            Params({**keep, name: v})
        except ParamError as exc:
            dropped[name] = str(exc)
            continue
        keep[name] = float(v)
    return keep, dropped


def fly_hover(params: Mapping[str, float], seed: int = 1, hold_s: int = HOVER_S,
              mode: int | None = None) -> tuple[Any, float, float]:
    """A hover flown with ``params``: (the flight log, t0_us, t1_us), the window from
    :data:`SETTLE_S` after it reaches the hold point to :data:`END_S` before the hold of
    ``hold_s`` ends (:func:`hover_window`). ``mode`` :data:`ALT_HOLD`: the hover is a pilot's
    in ALT_HOLD, sticks centred at 10 m (:func:`althold_hover_script`), which does not hold
    its position; any other: the AUTO hold of :func:`hover_mission`."""
    from tlm_sim import fly
    from tlm_sim.params import Params

    if mode == ALT_HOLD:
        from tlm_sim.mission.sticks import StickScript

        rows, origin, descent = althold_hover_script(hold_s)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            log = fly(None, params=Params(dict(params)), seed=seed,
                      sticks=StickScript.from_dict({"sticks": rows}))
        return log, (origin + SETTLE_S) * 1e6, (descent - END_S) * 1e6
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        log = fly(hover_mission(hold_s=hold_s), params=Params(dict(params)), seed=seed)
    t0, t1 = hover_window(log.tables)
    t1 = min(t1, t0 + hold_s * 1e6) - END_S * 1e6  # the hold ends hold_s after arriving
    return log, t0 + SETTLE_S * 1e6, t1


def althold_hover_script(hold_s: int = HOVER_S, alt_m: float = 10.0
                         ) -> tuple[list[dict[str, Any]], float, float]:
    """A pilot's ALT_HOLD hover as a stick script (generate's pilot flights: the ground station
    selects the mode, rudder arming, a climb to ``alt_m``, sticks centred ``hold_s`` s, descent,
    landing, rudder disarming): (rows, the hold's start, its end) [s since boot]."""
    from tlm_process.generate.pilot_flights import pilot_script

    return pilot_script({"mode": "ALT_HOLD", "alt": alt_m,
                         "segments": [[0.0, 0.0, 0.0, float(hold_s), 0.0]]})


def fly_hover_stats(params: Mapping[str, float], seed: int = 1,
                    hold_s: int = HOVER_S, mode: int | None = None) -> dict[str, float]:
    """tlm's :data:`STAT_NAMES` and motor asymmetry over a hover flown with ``params``
    (:func:`fly_hover`)."""
    log, t0, t1 = fly_hover(params, seed, hold_s, mode)
    return {**segment_stats(log.tables, t0, t1, unit=1.0),
            **motor_asymmetry(log.tables, t0, t1, log.params)}


def hover_window(tables: Mapping[str, Any], alt_m: float = 10.0) -> tuple[float, float]:
    """(t0_us, t1_us) of the hold of a :func:`hover_mission` flight: the longest run of truth
    (SIM) rows within 3 m of the hold point horizontally and 2 m of its altitude."""
    from tlm_sim.geo import latlon_to_ne

    sim = tables["SIM"]
    wp = hover_mission(alt_m).waypoints[1]
    n, e = latlon_to_ne(sim.Lat.to_numpy(float), sim.Lng.to_numpy(float), wp[0], wp[1])
    ground = float(sim.Alt.iloc[0])
    t = sim.TimeUS.to_numpy(float)
    near = (np.hypot(n, e) < 3.0) & (np.abs(sim.Alt.to_numpy(float) - ground - alt_m) < 2.0)
    best, start = (0, 0), None
    for k, ok in enumerate(np.append(near, False)):
        if ok and start is None:
            start = k
        elif not ok and start is not None:
            if k - start > best[1] - best[0]:
                best = (start, k)
            start = None
    if t[best[1] - 1] - t[best[0]] < (SETTLE_S + END_S + 10.0) * 1e6:
        raise FitError("tlm's hover flight did not hold its position (too much noise?)")
    return float(t[best[0]]), float(t[best[1] - 1])


def _gain(gain: float, target: float, got: float, floor: float) -> float:
    """A vibration gain moved towards the one at which sqrt(floor^2 + (gain x v)^2) meets
    target (the statistic's excess over the floor taken as proportional to the gain), damped
    (the excess's exponent :data:`DAMPING`, at most x4 per flight) and within the gain's range;
    where the flight's statistic hardly exceeds the floor, by the ratio of the statistics."""
    if not (math.isfinite(target) and math.isfinite(got)):
        return gain
    want = max(target**2 - floor**2, (0.1 * target) ** 2)
    have = got**2 - floor**2
    if have > (0.1 * got) ** 2:
        step = min(max((want / have) ** (0.5 * DAMPING), 0.25), 4.0)
    else:
        # the flight's statistic is (nearly) all the floor's: the other knobs' shares, measured
        # at other settings, say more than the flight shows, and the excess ratio would send
        # the gain x4 (and the gusts, the fluctuation and the gyro gains with it, together):
        # the ratio of the statistics themselves moves it instead
        step = min(max((target / max(got, 1e-9)) ** DAMPING, 0.25), 4.0)
    return float(min(max(gain * step, 0.0), 20.0))


def fit_vehicle(log_stats: Mapping[str, float], log_params: Mapping[str, float] | None = None,
                iterations: int = 10, seed: int = 1,
                progress: Callable[[int], None] | None = None,
                battery: Mapping[str, float] | None = None,
                mode: int | None = None) -> FitResult:
    """Fit tlm's vehicle to ``log_stats`` (:func:`segment_stats` of the log's steady segment),
    starting from the log's parameters; a floor flight (no vibration), with VIBE in the log
    the rotor frequency's start (:func:`_rotor_start`), two calibration
    flights (gyro vibration alone, the rotors' fluctuation alone: :func:`_shared_start`), then
    ``iterations`` fitting flights; the knobs averaged over the second half of them are
    returned with a flight of them (fewer than :data:`TAIL_MIN` in that half: the flight with
    the smallest largest relative error over :data:`FIT_STATS`). ``progress`` is called with
    the number of fitting steps flown (:func:`fit_steps` in all); ``battery``: the log's pack
    (:func:`log_battery`); ``mode``: the segment's flight mode (:data:`ALT_HOLD`: the hovers
    fly it, and the gusts, which do not lean a copter that holds no position, are not
    fitted; :func:`fly_hover`)."""
    from tlm_sim.params import Params

    base, dropped = log_vehicle_params(log_params or {})
    base.update(battery or {})
    base["SIM_VIB_MOT_MAX"] = ROTOR_HZ
    base["TLM_ROTOR_TC"] = ROTOR_TC
    base["TLM_VIB_SPREAD"] = MOT_SPREAD
    base["TLM_VIB_CMD_REF"] = CMD_REF
    fixed = {"SIM_ACC1_RND": ACC_AMP, "SIM_ACC2_RND": ACC_AMP,
             "SIM_GYR1_RND": GYR_AMP, "SIM_GYR2_RND": GYR_AMP, "TLM_TURB_TC": TURB_TC}

    def fly(params: Mapping[str, float]) -> dict[str, float]:
        return _mean_stats([fly_hover_stats(params, seed + j, mode=mode)
                            for j in range(FIT_SEEDS)])

    floor = fly(base)
    if progress is not None:
        progress(1)
    if _has_vibe(log_stats):
        # the rotor frequency before the calibrations: the gyro vibration's share of the
        # logged noise depends on it
        base["SIM_VIB_MOT_MAX"] = _rotor_start(log_stats, floor, lambda hz: fly(
            {**base, **fixed, "SIM_VIB_MOT_MAX": hz}))
    knobs = {"TLM_HOVER_THR": Params(base)["TLM_HOVER_THR"],
             **{f"TLM_VIB_ACC_{a}": 1.0 for a in "XYZ"},
             **{f"TLM_VIB_GYR_{a}": 1.0 for a in "XYZ"},
             "SIM_WIND_TURB": (TURB_START if math.isfinite(attitude_std(log_stats))
                               and mode != ALT_HOLD else 0.0),
             "TLM_ROTOR_RND": 0.0}
    shares: dict[str, dict[str, float]] = {}
    if math.isfinite(tracking_error_std(log_stats)):
        # calibration: the gyro vibration alone, then the rotors' fluctuation alone
        gyros = {name: 0.0 for name, _, _ in SHARED_STATS}
        vib = fly({**base, **fixed, **dict.fromkeys(gyros, 1.0)})
        rot = fly({**base, **fixed, **gyros, "TLM_ROTOR_RND": ROTOR_RND_CAL})
        shares = _shares(floor, vib, rot)
        knobs.update(_shared_start(log_stats, floor, shares))
    if progress is not None:
        progress(SETUP_STEPS)
    balance = [k for k, (stat, _, _) in ASYM_KNOBS.items()
               if math.isfinite(log_stats.get(stat, math.nan))]
    knobs.update(dict.fromkeys(balance, 0.0))
    if _has_vibe(log_stats):
        knobs["SIM_VIB_MOT_MAX"] = base["SIM_VIB_MOT_MAX"]
    last: dict[str, tuple[float, float]] = {}
    history, best, best_err = [], None, math.inf
    for k in range(iterations):
        params = {**base, **fixed, **knobs}
        got = fly(params)
        if progress is not None:
            progress(SETUP_STEPS + k + 1)
        err = _max_rel_err(got, log_stats)
        history.append({**{s: got[s] for s in (*STAT_NAMES, *ASYM_NAMES) if s in got},
                        **knobs, "max_rel_err": err})
        if err < best_err:
            best, best_err = (dict(params), got), err
        _step_knobs(knobs, log_stats, got, floor, shares, balance, last)
    assert best is not None
    params, got = best
    tail = history[iterations // 2:]
    if len(tail) >= TAIL_MIN:
        # each knob averaged over the second half of the fitting flights (one flight's
        # statistics scatter by several per cent, and so would its knobs), flown once more
        mean = {k: float(np.mean([h[k] for h in tail])) for k in knobs}
        params = {**base, **fixed, **mean}
        got = fly(params)
    if progress is not None:
        progress(fit_steps(iterations))
    return FitResult(params=params, log=dict(log_stats), tlm=got, history=history,
                     dropped=dropped)


def _step_knobs(knobs: dict[str, float], log_stats: Mapping[str, float],
                got: Mapping[str, float], floor: Mapping[str, float],
                shares: Mapping[str, Mapping[str, float]], balance: list[str],
                last: dict[str, tuple[float, float]]) -> None:
    """One fitting step: every knob moved (in place) from the flight ``got`` towards the log's
    ``log_stats`` (the hover thrust, the vibration gains, the gusts, the rotors' fluctuation,
    the balance and, with VIBE, the rotor frequency)."""
    thr = knobs["TLM_HOVER_THR"] * log_stats["hover_thr"] / max(got["hover_thr"], 1e-3)
    knobs["TLM_HOVER_THR"] = float(min(max(thr, 0.05), 0.95))
    for a in "xyz":
        for kind, stat in (("ACC", f"acc_{a}_std"), ("GYR", f"gyr_{a}_std_dps")):
            name = f"TLM_VIB_{kind}_{a.upper()}"
            # what the statistic would be without this gain: the floor and, for the
            # roll and pitch gyros, the rotors' fluctuation's share
            without = _without(floor, shares, stat, knobs, "TLM_ROTOR_RND")
            knobs[name] = _gain(knobs[name], log_stats[stat], got[stat], without)
    if knobs["SIM_WIND_TURB"] > 0.0:
        without = 0.5 * sum(_without(floor, shares, s, knobs, "TLM_ROTOR_RND", gain)
                            for gain, s in AXIS_ATTITUDE.items())
        knobs["SIM_WIND_TURB"] = _gain(knobs["SIM_WIND_TURB"], attitude_std(log_stats),
                                       attitude_std(got), without)
    if knobs["TLM_ROTOR_RND"] > 0.0:
        without = 0.5 * sum(_without(floor, shares, err, knobs, gain)
                            for gain, _, err in SHARED_STATS)
        knobs["TLM_ROTOR_RND"] = min(_gain(knobs["TLM_ROTOR_RND"],
                                           tracking_error_std(log_stats),
                                           tracking_error_std(got), without), 0.5)
    for name in balance:
        knobs[name] = _balance_step(name, knobs[name], log_stats, got, floor, last)
    if "SIM_VIB_MOT_MAX" in knobs:
        knobs["SIM_VIB_MOT_MAX"] = _rotor_step(knobs["SIM_VIB_MOT_MAX"], log_stats, got,
                                               floor)


def fit_steps(iterations: int) -> int:
    """Flights (each :data:`FIT_SEEDS` hovers) :func:`fit_vehicle` reports through
    ``progress``: the floor, two calibrations, the iterations and the averaged knobs'."""
    return SETUP_STEPS + iterations + 1


def _shares(floor: Mapping[str, float], vib: Mapping[str, float], rot: Mapping[str, float]
            ) -> dict[str, dict[str, float]]:
    """What the roll / pitch gyro vibration and the rotors' fluctuation each add to the
    :data:`SHARED_STATS` statistics and to the attitude's (which the gusts are fitted to),
    in quadrature over the floor: per knob, statistic -> added variance per unit knob squared
    (the gyro gains at 1, the fluctuation at :data:`ROTOR_RND_CAL`)."""
    out: dict[str, dict[str, float]] = {"TLM_ROTOR_RND": {}}
    for gain, gyr, err in SHARED_STATS:
        out[gain] = {s: max(vib[s] ** 2 - floor[s] ** 2, 0.0)
                     for s in (gyr, err, AXIS_ATTITUDE[gain])}
    for s in (*(s for _, gyr, err in SHARED_STATS for s in (gyr, err)),
              "roll_std_deg", "pitch_std_deg"):
        out["TLM_ROTOR_RND"][s] = max(rot[s] ** 2 - floor[s] ** 2, 0.0) / ROTOR_RND_CAL**2
    return out


def _shared_start(target: Mapping[str, float], floor: Mapping[str, float],
                  shares: Mapping[str, Mapping[str, float]]) -> dict[str, float]:
    """The roll and pitch gyro gains and the rotors' fluctuation to start from: the
    non-negative least-squares solution, in relative terms, of each :data:`SHARED_STATS`
    statistic's excess over the floor as the sum of the knobs' shares (the vibration raises a
    gyro's noise and its axis's tracking error about alike, the fluctuation the tracking error
    about twice as much, so the four statistics tell the three knobs apart)."""
    from scipy.optimize import nnls

    knobs = [gain for gain, _, _ in SHARED_STATS] + ["TLM_ROTOR_RND"]
    rows, rhs = [], []
    for gain, gyr, err in SHARED_STATS:
        for s in (gyr, err):
            t = target[s]
            if not (math.isfinite(t) and t > 0):
                continue
            rows.append([shares[k].get(s, 0.0) / t**2 if k in (gain, "TLM_ROTOR_RND") else 0.0
                         for k in knobs])
            rhs.append((t**2 - floor[s] ** 2) / t**2)
    if len(rows) < len(knobs):
        return {}
    sq, _ = nnls(np.asarray(rows), np.asarray(rhs))
    start = {k: float(math.sqrt(v)) for k, v in zip(knobs, sq, strict=True)}
    start["TLM_ROTOR_RND"] = min(start["TLM_ROTOR_RND"], 0.5)
    for gain, _, _ in SHARED_STATS:
        start[gain] = min(start[gain], 20.0)
    return start


def _without(floor: Mapping[str, float], shares: Mapping[str, Mapping[str, float]], stat: str,
             knobs: Mapping[str, float], *others: str) -> float:
    """``stat`` without the knob being fitted: the floor and the shares of the knobs
    ``others`` (the rotors' fluctuation for a gyro gain, the axis's gyro gain for the
    fluctuation, both for the gusts) at their present values, in quadrature; the floor alone
    where no share is known."""
    var = floor[stat] ** 2
    for other in others:
        var += shares.get(other, {}).get(stat, 0.0) * knobs.get(other, 0.0) ** 2
    return math.sqrt(var)


def _balance_step(name: str, value: float, target: Mapping[str, float],
                  got: Mapping[str, float], floor: Mapping[str, float],
                  last: dict[str, tuple[float, float]]) -> float:
    """The balance knob ``name`` (:data:`ASYM_KNOBS`) moved so that its motor asymmetry meets
    the log's: the asymmetry is linear in the knob, its slope measured from the last two
    flights (or from the floor flight's asymmetry at 0), :data:`ASYM_KNOBS`' until one moved
    it."""
    stat, slope, top = ASYM_KNOBS[name]
    g = got.get(stat, math.nan)
    if not (math.isfinite(g) and math.isfinite(target[stat])):
        return value
    v0, g0 = last.get(name, (0.0, floor.get(stat, 0.0)))
    if abs(value - v0) > 1e-4 and math.isfinite(g0):
        measured = (g - g0) / (value - v0)
        if measured * slope > 0.0 and 0.2 < measured / slope < 5.0:
            slope = measured
    last[name] = (value, g)
    return float(min(max(value + (target[stat] - g) / slope, -top), top))


def _mean_stats(runs: list[dict[str, float]]) -> dict[str, float]:
    """Each statistic's mean over flights (a rotor-locked vibration beats between the motors,
    so one flight's standard deviation scatters by several per cent)."""
    return {k: float(np.mean([r[k] for r in runs])) for k in runs[0]}


def attitude_std(stats: Mapping[str, float]) -> float:
    """The mean of the ATT roll and pitch standard deviations [deg] (what the gusts are fitted
    to; NaN without ATT)."""
    return 0.5 * (stats["roll_std_deg"] + stats["pitch_std_deg"])


def tracking_error_std(stats: Mapping[str, float]) -> float:
    """The mean of the RATE roll and pitch tracking errors' standard deviations [deg/s]: what
    the rotors' fluctuation is fitted to. The fluctuation moves both axes alike and raises
    their tracking error about twice as much as their gyro noise (it is slow: the attitude
    lags it), while the gyro vibration raises both about equally, so with the gyro noise the
    errors tell the two apart (log171: pitch gyro 2.3 deg/s with a 4.0 deg/s rate error, roll
    5.0 with 6.7; :func:`_shared_start`)."""
    return 0.5 * (stats["rate_roll_err_std_dps"] + stats["rate_pitch_err_std_dps"])


def _has_vibe(stats: Mapping[str, float]) -> bool:
    """Whether ``stats`` hold VIBE on every axis (a log of Copter 3.4 on)."""
    return all(math.isfinite(stats.get(v, math.nan)) and stats[v] > 0 for v in VIBE_STATS)


def fitted_stats(log_stats: Mapping[str, float]) -> tuple[str, ...]:
    """The statistics a fit of ``log_stats`` drives to the log's: :data:`FIT_STATS`, and
    :data:`VIBE_STATS` where the log has VIBE."""
    return (*FIT_STATS, *(VIBE_STATS if _has_vibe(log_stats) else ()))


def _vibe_ratio(stats: Mapping[str, float], floor: Mapping[str, float]) -> float:
    """The geometric mean over the axes of VIBE over the accel noise's excess over the floor
    (the flight's own motion, in quadrature)."""
    r = [stats[f"vibe_{a}"] / math.sqrt(max(stats[f"acc_{a}_std"] ** 2
                                            - floor[f"acc_{a}_std"] ** 2, 1e-12))
         for a in "xyz"]
    return float(np.exp(np.mean(np.log(r))))


def _rotor_start(target: Mapping[str, float], floor: Mapping[str, float],
                 fly: Callable[[float], Mapping[str, float]]) -> float:
    """The rotor frequency [Hz at full command] the fit starts from: from :data:`ROTOR_HZ`,
    :data:`ROTOR_START_FLIGHTS` flights with the vibration at its starting gains, each moving
    the frequency by the square root of the log's :func:`_vibe_ratio` over the flight's
    (undamped), within :data:`ROTOR_HZ_RANGE`."""
    hz = ROTOR_HZ
    for _ in range(ROTOR_START_FLIGHTS):
        ratio = _rotor_ratio(target, fly(hz), floor)
        if ratio is None:
            break
        hz = _rotor_clamp(hz * math.sqrt(ratio))
    return hz


def _rotor_ratio(target: Mapping[str, float], got: Mapping[str, float],
                 floor: Mapping[str, float]) -> float | None:
    """The log's :func:`_vibe_ratio` over a flight's (None when either is not a positive
    number)."""
    want, have = _vibe_ratio(target, floor), _vibe_ratio(got, floor)
    if not (math.isfinite(want) and math.isfinite(have) and want > 0 and have > 0):
        return None
    return want / have


def _rotor_clamp(hz: float) -> float:
    """A rotor frequency [Hz] within :data:`ROTOR_HZ_RANGE`."""
    return float(min(max(hz, ROTOR_HZ_RANGE[0]), ROTOR_HZ_RANGE[1]))


def _rotor_step(hz: float, target: Mapping[str, float], got: Mapping[str, float],
                floor: Mapping[str, float]) -> float:
    """The rotor frequency at full command [Hz] moved towards the log's ratio of VIBE to the
    logged accel noise (:func:`_vibe_ratio`), which goes with the frequency squared (the INS
    filter's roll-off): damped (:data:`DAMPING`), at most x1.4 per flight, within
    :data:`ROTOR_HZ_RANGE`."""
    ratio = _rotor_ratio(target, got, floor)
    if ratio is None:
        return hz
    return _rotor_clamp(hz * min(max(ratio ** (0.5 * DAMPING), 1 / 1.4), 1.4))


def _max_rel_err(got: Mapping[str, float], want: Mapping[str, float]) -> float:
    """Largest |got / want - 1| over the :func:`fitted_stats` the log has, the attitude
    (:func:`attitude_std`) and its tracking (:func:`tracking_error_std`)."""
    pairs = [(got[s], want[s]) for s in fitted_stats(want)]
    pairs.append((attitude_std(got), attitude_std(want)))
    pairs.append((tracking_error_std(got), tracking_error_std(want)))
    errs = [abs(g / w - 1.0) for g, w in pairs if math.isfinite(w) and w > 0]
    return max(errs) if errs else 0.0
