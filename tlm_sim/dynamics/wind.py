"""SITL's wind model (ardupilot-reference.md §1.10, sitl-faults.md §9), every physics step.

Mean wind (``SITL_State::_simulator_servos``):

* **Start delay:** the mean wind is exactly 0 until ``WIND_START_DELAY_S`` (5 s) of simulated
  time after boot (SITL's first servo update, tlm's ``t_s`` = 0).
* **Slew filter:** speed, direction and vertical direction follow ``SIM_WIND_SPD``,
  ``SIM_WIND_DIR`` and ``SIM_WIND_DIR_Z`` through a first-order low-pass filter whose
  **cut-off frequency is 1/SIM_WIND_TC Hz**, i.e. whose time constant is TC/(2 pi) (0.80 s
  at the default TC = 5 s), with TC floored at 0.1 s. The filters start at 0 (speed 0 m/s,
  direction 0 deg, vertical angle 0 deg) and advance only when more than 1 ms of simulated time
  has passed since their last update (every second 833 us physics step), with that elapsed
  time as the filter step. Their last-update time starts at 0 (boot), so the first update
  after the start delay spans the whole delay (the filters jump most of the way, e.g. 86 % at
  TC = 5 s). The direction is filtered on the error wrapped into (-180, 180] deg and kept in
  (-180, 180] deg (so from its start at 0 deg it swings through east to the default 180 deg);
  the vertical angle on the plain difference. A parameter changed in flight slews likewise.
* **Height profile** ``SIM_WIND_T`` with h = height of the ground-contact point above home
  ground, ``-PD - frame_height`` [m] (SITL's ``height_agl``: altitude minus the altitude on
  the pad, 0 at rest): 0 = square-root law ``S * sqrt(max(h / T_ALT, 0))`` below ``T_ALT``
  (0 at and below ground level), 1 = none, 2 = linear ``S + (h - T_ALT) * T_COEF``; then
  ``max(., 0)``. Computed only after the start delay.
* The wind comes FROM direction psi at vertical angle theta_z: the air moves along
  ``-S (cos psi cos theta_z, sin psi cos theta_z, sin theta_z)`` NED (theta_z = 90 deg: an
  updraft, ``WIND_D`` < 0).

Turbulence (``Aircraft::update_wind``), not delayed: while ``SIM_WIND_TURB`` > 0 and the
vehicle is airborne (height above ground > ``AIRBORNE_HAGL_M`` = 1 mm), every physics step the
horizontal and vertical gust speeds are updated ``g <- 0.98 g + 0.02 * (10 TURB) * N(0, 1)``
(stationary std 0.2 TURB / sqrt(1 - 0.98^2) ~ 1.005 TURB, correlation time -1/ln 0.98 ~ 49.5
steps ~ 41 ms) and the horizontal gust acts along an azimuth drawn uniformly afresh every step
(SITL advances it by ``2 * rand()`` degrees, an effectively random angle). The gusts are added
to the vector the wind comes from before it is negated. On the ground the gusts are neither
updated nor applied (they resume from their last values after take-off, as in SITL).

The result is the velocity of the air mass, NED [m/s], written to ``WIND_N/E/D``.
Randomness comes from the flight's wind generator ``rng`` (:mod:`tlm_sim.rng`, seeded from the
flight seed): two Gaussians (:func:`~tlm_sim.rng.normal_pair`) and a uniform direction
(:func:`~tlm_sim.rng.unit_pair`) per airborne step with turbulence, none otherwise.
"""

from __future__ import annotations

import math

import numpy as np

from tlm_sim._jit import tick_jit
from tlm_sim.dynamics import layout as X
from tlm_sim.dynamics.frame import (
    F_FRAME_HEIGHT,
    F_GUST_A,
    F_WIND_DIR,
    F_WIND_DIR_Z,
    F_WIND_SPD,
    F_WIND_T,
    F_WIND_T_ALT,
    F_WIND_T_COEF,
    F_WIND_TC,
    F_WIND_TURB,
)
from tlm_sim.rng import normal_pair, unit_pair

#: simulated time after boot before the mean wind is applied [s] (SITL lets the airspeed
#: sensor calibrate)
WIND_START_DELAY_S: float = 5.0
#: floor of SIM_WIND_TC [s]
WIND_TC_MIN_S: float = 0.1
#: the slew filters advance only when more than this has passed since their last update [s]
WIND_SLEW_MIN_DT_S: float = 0.001
#: height above ground [m] above which the vehicle is airborne (SITL's ``on_ground()``)
AIRBORNE_HAGL_M: float = 0.001
#: per-step IIR coefficient of the gust filters
GUST_IIR: float = 0.98
#: gust input scale: filtered N(0,1) * 10 * TURB has a standard deviation of about TURB
GUST_SCALE: float = 10.0


@tick_jit
def wrap_180(deg: float) -> float:
    """Wrap an angle [deg] into (-180, 180] (ArduPilot's ``wrap_180``: +180 stays +180)."""
    if -180.0 < deg <= 180.0:
        return deg
    res = wrap_360(deg)
    return res - 360.0 if res > 180.0 else res


@tick_jit
def wrap_360(deg: float) -> float:
    """Wrap an angle [deg] into [0, 360)."""
    if 0.0 <= deg < 360.0:
        return deg
    return deg % 360.0


@tick_jit
def lowpass_alpha(dt: float, cutoff_hz: float) -> float:
    """Gain of a first-order low-pass filter step of ``dt`` [s] with cut-off frequency
    ``cutoff_hz`` [Hz] (ArduPilot's ``calc_lowpass_alpha_dt``): dt / (dt + 1 / (2 pi fc));
    1 (no filtering) for a cut-off <= 0, 0 for dt <= 0."""
    if cutoff_hz <= 0.0:
        return 1.0
    if dt <= 0.0:
        return 0.0
    return dt / (dt + 1.0 / (2.0 * math.pi * cutoff_hz))


@tick_jit
def profile_speed(speed: float, height_m: float, frame: np.ndarray) -> float:
    """Wind speed [m/s] at ``height_m`` [m] above ground for the ``SIM_WIND_T`` profile
    (0 square-root law below T_ALT, 1 none, 2 linear; any other value none), at least 0."""
    kind = frame[F_WIND_T]
    t_alt = frame[F_WIND_T_ALT]
    if kind < 0.5:  # 0: square-root law below T_ALT
        if height_m < t_alt:
            speed *= math.sqrt(max(height_m / t_alt, 0.0)) if t_alt > 0.0 else 1.0
    elif 1.5 < kind < 2.5:  # 2: linear
        speed += (height_m - t_alt) * frame[F_WIND_T_COEF]
    return max(speed, 0.0)


@tick_jit
def _set_direction(x: np.ndarray, dir_deg: float, dirz_deg: float) -> None:
    """Store the filtered directions [deg] and the unit vector the wind comes from."""
    x[X.WIND_DIR_F] = dir_deg
    x[X.WIND_DIRZ_F] = dirz_deg
    psi = math.radians(dir_deg)
    thz = math.radians(dirz_deg)
    ch = math.cos(thz)
    x[X.WIND_UN] = ch * math.cos(psi)
    x[X.WIND_UE] = ch * math.sin(psi)
    x[X.WIND_UD] = math.sin(thz)


@tick_jit
def init_wind(x: np.ndarray, frame: np.ndarray) -> None:
    """Reset the wind state at boot as SITL starts it: no wind, no gusts, slew filters at
    speed 0 m/s, direction 0 deg and vertical angle 0 deg, last filter update at t = 0 s.
    ``frame`` is not read (the parameters are followed from the first update on)."""
    x[X.WIND_N] = 0.0
    x[X.WIND_E] = 0.0
    x[X.WIND_D] = 0.0
    x[X.WIND_SPD_F] = 0.0
    x[X.GUST_H] = 0.0
    x[X.GUST_V] = 0.0
    x[X.WIND_SLEW_T] = 0.0
    x[X.WIND_STILL_DT] = -1.0
    _set_direction(x, 0.0, 0.0)


@tick_jit
def settle_wind(x: np.ndarray, frame: np.ndarray) -> None:
    """Put the slew filters at their targets (SIM_WIND_SPD, SIM_WIND_DIR wrapped into
    (-180, 180], SIM_WIND_DIR_Z), as after a long steady wind; for tests and for experiments
    that start in settled wind. Call after :func:`init_wind`."""
    x[X.WIND_SPD_F] = frame[F_WIND_SPD]
    x[X.WIND_STILL_DT] = -1.0
    _set_direction(x, wrap_180(frame[F_WIND_DIR]), frame[F_WIND_DIR_Z])


@tick_jit
def _slew_filters(x: np.ndarray, frame: np.ndarray, t_s: float) -> None:
    """Advance the speed/direction slew filters to simulated time ``t_s`` [s] if more than
    ``WIND_SLEW_MIN_DT_S`` has passed since their last update (cut-off 1/TC Hz).

    Once the filters have settled (a step changed none of them: they sit at, or within a
    rounding step of, their targets) a step of the same length at the same targets changes
    nothing either; it is skipped (``WIND_STILL_DT``, ``WIND_STILL_KEY``), which saves the
    filter gain's three divisions on almost every step of a flight."""
    dt = t_s - x[X.WIND_SLEW_T]
    if dt <= WIND_SLEW_MIN_DT_S:
        return
    x[X.WIND_SLEW_T] = t_s
    if dt == x[X.WIND_STILL_DT] and _still(x, frame):
        return
    alpha = lowpass_alpha(dt, 1.0 / max(frame[F_WIND_TC], WIND_TC_MIN_S))
    spd_old = x[X.WIND_SPD_F]
    spd = spd_old + (frame[F_WIND_SPD] - spd_old) * alpha
    x[X.WIND_SPD_F] = spd
    dir_old = x[X.WIND_DIR_F]
    dirz_old = x[X.WIND_DIRZ_F]
    dirf = wrap_180(dir_old + wrap_180(frame[F_WIND_DIR] - dir_old) * alpha)
    dirz = dirz_old + (frame[F_WIND_DIR_Z] - dirz_old) * alpha
    if dirf != dir_old or dirz != dirz_old:
        _set_direction(x, dirf, dirz)
    if _same(spd, spd_old) and _same(dirf, dir_old) and _same(dirz, dirz_old):
        x[X.WIND_STILL_DT] = dt
        k = X.WIND_STILL_KEY
        x[k], x[k + 1] = frame[F_WIND_SPD], frame[F_WIND_DIR]
        x[k + 2], x[k + 3] = frame[F_WIND_DIR_Z], frame[F_WIND_TC]
        x[k + 4], x[k + 5], x[k + 6] = spd, dirf, dirz
    else:
        x[X.WIND_STILL_DT] = -1.0


@tick_jit
def _same(a: float, b: float) -> bool:
    """a and b are the same number, zeros of the same sign included (NaN is never the same)."""
    return a == b and (a != 0.0 or math.copysign(1.0, a) == math.copysign(1.0, b))


@tick_jit
def _still(x: np.ndarray, frame: np.ndarray) -> bool:
    """The targets and the filters are exactly those of the settled step recorded in
    WIND_STILL_KEY (so a step of the same length would change nothing again)."""
    k = X.WIND_STILL_KEY
    return (_same(frame[F_WIND_SPD], x[k]) and _same(frame[F_WIND_DIR], x[k + 1])
            and _same(frame[F_WIND_DIR_Z], x[k + 2]) and _same(frame[F_WIND_TC], x[k + 3])
            and _same(x[X.WIND_SPD_F], x[k + 4]) and _same(x[X.WIND_DIR_F], x[k + 5])
            and _same(x[X.WIND_DIRZ_F], x[k + 6]))


@tick_jit
def _correlated_gusts(x: np.ndarray, a: float, turb: float,
                      rng: np.ndarray) -> tuple[float, float, float]:
    """One physics step of the correlated gusts (TLM_TURB_TC > 0): north, east and down gust
    speeds [m/s] (x[GUST_H], x[GUST_E], x[GUST_V]), each a first-order Gauss-Markov process
    g <- a g + sqrt(1 - a^2) TURB N(0, 1) with a = exp(-dt / TLM_TURB_TC): standard deviation
    TURB on each axis and correlation time TLM_TURB_TC (SITL's gusts decorrelate in ~41 ms
    and turn to a new azimuth every step, too fast to move a copter's attitude; a real
    copter's hover shows its lean angle following gusts over seconds)."""
    b = math.sqrt(1.0 - a * a) * turb
    n0, n1 = normal_pair(rng)
    n2 = normal_pair(rng)[0]
    gn = a * x[X.GUST_H] + b * n0
    ge = a * x[X.GUST_E] + b * n1
    gd = a * x[X.GUST_V] + b * n2
    x[X.GUST_H] = gn
    x[X.GUST_E] = ge
    x[X.GUST_V] = gd
    return gn, ge, gd


@tick_jit
def update_wind(x: np.ndarray, frame: np.ndarray, t_s: float, rng: np.ndarray) -> None:
    """Advance the wind model to simulated time ``t_s`` [s] since boot (the start of the
    physics step) and write the air velocity ``WIND_N/E/D`` [m/s, NED].
    ``rng``: the wind's random generator state (:mod:`tlm_sim.rng`)."""
    wn = 0.0
    we = 0.0
    wd = 0.0
    hagl = -x[X.PD] - frame[F_FRAME_HEIGHT]
    if t_s > WIND_START_DELAY_S:
        _slew_filters(x, frame, t_s)
        spd = x[X.WIND_SPD_F]
        s = 0.0
        if spd != 0.0 or frame[F_WIND_T] > 1.5:
            s = profile_speed(spd, hagl, frame)
        if s != 0.0:
            # vector pointing where the wind comes FROM; negated at the end
            wn = s * x[X.WIND_UN]
            we = s * x[X.WIND_UE]
            wd = s * x[X.WIND_UD]
    turb = frame[F_WIND_TURB]
    if turb > 0.0 and hagl > AIRBORNE_HAGL_M and frame[F_GUST_A] > 0.0:
        gn, ge, gd = _correlated_gusts(x, frame[F_GUST_A], turb, rng)
        wn += gn
        we += ge
        wd += gd
    elif turb > 0.0 and hagl > AIRBORNE_HAGL_M:
        amp = GUST_SCALE * turb * (1.0 - GUST_IIR)
        nh, nv = normal_pair(rng)
        gh = GUST_IIR * x[X.GUST_H] + amp * nh
        gv = GUST_IIR * x[X.GUST_V] + amp * nv
        cos_az, sin_az = unit_pair(rng)  # the azimuth of the horizontal gust
        x[X.GUST_H] = gh
        x[X.GUST_V] = gv
        wn += cos_az * gh
        we += sin_az * gh
        wd += gv
    x[X.WIND_N] = -wn
    x[X.WIND_E] = -we
    x[X.WIND_D] = -wd
