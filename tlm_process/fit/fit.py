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
  standard deviation per axis.

A statistic is the flight's own motion and the sensor's noise together; the motion (the
statistic of a first flight without vibration, the *floor*) is taken out in quadrature when a
gain is scaled. Attitude noise and rate-tracking error are not fitted: they follow from the
gyro noise through tlm's controllers, and the report compares them too. A log's rotor
frequency is not in its 25-50 Hz IMU rows: ``SIM_VIB_MOT_MAX`` is :data:`ROTOR_HZ` (a SITL
log's own SIM_* parameters are its simulator's, not its vehicle's, and are not taken).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tlm_process.fit.stats import STAT_NAMES, segment_stats

__all__ = ["ACC_AMP", "FIT_STATS", "GYR_AMP", "ROTOR_HZ", "FitResult", "fit_vehicle",
           "fly_hover_stats", "hover_mission", "hover_window", "log_vehicle_params"]

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
#: flights (seeds) each fitting step averages
FIT_SEEDS = 2
#: exponent of the excess ratio a gain follows per fitting flight (< 1: damped)
DAMPING = 0.8
#: statistics the fit drives to the log's (the others are compared, not fitted)
FIT_STATS = ("hover_thr", "acc_x_std", "acc_y_std", "acc_z_std",
             "gyr_x_std_dps", "gyr_y_std_dps", "gyr_z_std_dps")
#: hover flown per fit flight [s], and what of it is measured (after settling)
HOVER_S = 60
SETTLE_S = 8.0
#: and before its end (the copter turns for its RTL there) [s]
END_S = 4.0


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


def log_vehicle_params(log_params: Mapping[str, float]) -> tuple[dict[str, float], dict[str, str]]:
    """The log's parameters tlm models, where they differ from tlm's defaults, each checked
    alone (a value out of tlm's range is dropped, with why); Copter 3.x's ``FRAME`` becomes
    ``FRAME_CLASS`` 1 (quad) and ``FRAME_TYPE``."""
    from tlm_sim.params import PARAM_INFO, ParamError, Params

    defaults = Params.defaults()
    values = dict(log_params)
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


def fly_hover_stats(params: Mapping[str, float], seed: int = 1,
                    hold_s: int = HOVER_S) -> dict[str, float]:
    """tlm's :data:`STAT_NAMES` over a hover flown with ``params`` (from :data:`SETTLE_S` after
    it reaches the hold point to :data:`END_S` before the hold of ``hold_s`` ends;
    :func:`hover_window`)."""
    from tlm_sim import fly
    from tlm_sim.params import Params

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        log = fly(hover_mission(hold_s=hold_s), params=Params(dict(params)), seed=seed)
    t0, t1 = hover_window(log.tables)
    t1 = min(t1, t0 + hold_s * 1e6) - END_S * 1e6  # the hold ends hold_s after arriving
    return segment_stats(log.tables, t0 + SETTLE_S * 1e6, t1, unit=1.0)


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
        raise RuntimeError("tlm's hover flight did not hold its position (too much noise?)")
    return float(t[best[0]]), float(t[best[1] - 1])


def _gain(gain: float, target: float, got: float, floor: float) -> float:
    """A vibration gain moved towards the one at which sqrt(floor^2 + (gain x v)^2) meets
    target (the statistic's excess over the floor taken as proportional to the gain), damped
    (the excess's exponent :data:`DAMPING`, at most x4 per flight) and within the gain's range."""
    if not (math.isfinite(target) and math.isfinite(got)):
        return gain
    want = max(target**2 - floor**2, (0.1 * target) ** 2)
    have = max(got**2 - floor**2, 1e-12)
    step = min(max((want / have) ** (0.5 * DAMPING), 0.25), 4.0)
    return float(min(max(gain * step, 0.0), 20.0))


def fit_vehicle(log_stats: Mapping[str, float], log_params: Mapping[str, float] | None = None,
                iterations: int = 10, seed: int = 1,
                progress: Callable[[int], None] | None = None) -> FitResult:
    """Fit tlm's vehicle to ``log_stats`` (:func:`segment_stats` of the log's steady segment),
    starting from the log's parameters; a floor flight (no vibration) then ``iterations``
    fitting flights; the best flight's parameters are returned (the smallest largest relative
    error over :data:`FIT_STATS`). ``progress`` is called with the number of flights flown."""
    from tlm_sim.params import Params

    base, dropped = log_vehicle_params(log_params or {})
    base["SIM_VIB_MOT_MAX"] = ROTOR_HZ
    floor = _mean_stats([fly_hover_stats(base, seed + j) for j in range(FIT_SEEDS)])
    if progress is not None:
        progress(1)
    knobs = {"TLM_HOVER_THR": Params(base)["TLM_HOVER_THR"],
             **{f"TLM_VIB_ACC_{a}": 1.0 for a in "XYZ"},
             **{f"TLM_VIB_GYR_{a}": 1.0 for a in "XYZ"}}
    fixed = {"SIM_ACC1_RND": ACC_AMP, "SIM_ACC2_RND": ACC_AMP,
             "SIM_GYR1_RND": GYR_AMP, "SIM_GYR2_RND": GYR_AMP}
    history, best, best_err = [], None, math.inf
    for k in range(iterations):
        params = {**base, **fixed, **knobs}
        got = _mean_stats([fly_hover_stats(params, seed + j) for j in range(FIT_SEEDS)])
        if progress is not None:
            progress(k + 2)
        err = _max_rel_err(got, log_stats)
        history.append({**{s: got[s] for s in STAT_NAMES}, **knobs, "max_rel_err": err})
        if err < best_err:
            best, best_err = (dict(params), got), err
        thr = knobs["TLM_HOVER_THR"] * log_stats["hover_thr"] / max(got["hover_thr"], 1e-3)
        knobs["TLM_HOVER_THR"] = float(min(max(thr, 0.05), 0.95))
        for a in "xyz":
            for kind, stat in (("ACC", f"acc_{a}_std"), ("GYR", f"gyr_{a}_std_dps")):
                name = f"TLM_VIB_{kind}_{a.upper()}"
                knobs[name] = _gain(knobs[name], log_stats[stat], got[stat], floor[stat])
    assert best is not None
    params, got = best
    return FitResult(params=params, log=dict(log_stats), tlm=got, history=history,
                     dropped=dropped)


def _mean_stats(runs: list[dict[str, float]]) -> dict[str, float]:
    """Each statistic's mean over flights (a rotor-locked vibration beats between the motors,
    so one flight's standard deviation scatters by several per cent)."""
    return {k: float(np.mean([r[k] for r in runs])) for k in runs[0]}


def _max_rel_err(got: Mapping[str, float], want: Mapping[str, float]) -> float:
    """Largest |got / want - 1| over the :data:`FIT_STATS` the log has."""
    errs = [abs(got[s] / want[s] - 1.0) for s in FIT_STATS
            if math.isfinite(want[s]) and want[s] > 0]
    return max(errs) if errs else 0.0
