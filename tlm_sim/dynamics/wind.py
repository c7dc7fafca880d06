"""SITL wind model (ardupilot-reference.md §1.10).

Speed, direction and vertical direction are low-pass filtered towards ``SIM_WIND_SPD``,
``SIM_WIND_DIR`` and ``SIM_WIND_DIR_Z`` with time constant ``SIM_WIND_TC`` (direction on the
wrapped +-180 deg error); the speed is shaped by the height profile ``SIM_WIND_T``; while
airborne with ``SIM_WIND_TURB > 0`` filtered Gaussian gusts are added along an azimuth drawn
afresh every step. No wind at all during the first 5 s of simulated time. The result is the
velocity of the air mass, NED [m/s], written to ``WIND_N/E/D``.

Randomness comes from the flight's wind generator ``rng`` (:mod:`tlm_sim.rng`, seeded from the
flight seed): two Gaussians (:func:`~tlm_sim.rng.normal_pair`) and a uniform direction
(:func:`~tlm_sim.rng.unit_pair`) per step.
"""

from __future__ import annotations

import math

import numpy as np

from tlm_sim._jit import tick_jit
from tlm_sim.dynamics import layout as X
from tlm_sim.dynamics.frame import (
    F_FRAME_HEIGHT,
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

#: simulated time before any wind is applied [s] (SITL lets the airspeed sensor calibrate)
WIND_START_DELAY_S: float = 5.0
#: per-step IIR coefficient of the gust filters
GUST_IIR: float = 0.98
#: gust input scale: filtered N(0,1) * 10 * TURB has a standard deviation of about TURB
GUST_SCALE: float = 10.0


@tick_jit
def wrap_180(deg: float) -> float:
    """Wrap an angle [deg] into [-180, 180)."""
    if -180.0 <= deg < 180.0:
        return deg
    return (deg + 180.0) % 360.0 - 180.0


@tick_jit
def wrap_360(deg: float) -> float:
    """Wrap an angle [deg] into [0, 360)."""
    if 0.0 <= deg < 360.0:
        return deg
    return deg % 360.0


@tick_jit
def profile_speed(speed: float, height_m: float, frame: np.ndarray) -> float:
    """Wind speed [m/s] at ``height_m`` above ground for the ``SIM_WIND_T`` profile (>= 0)."""
    kind = frame[F_WIND_T]
    t_alt = frame[F_WIND_T_ALT]
    if kind < 0.5:  # 0: square-root law below T_ALT
        if height_m < t_alt:
            speed *= math.sqrt(max(height_m / t_alt, 0.0)) if t_alt > 0.0 else 1.0
    elif kind > 1.5:  # 2: linear
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
    """Reset the wind state: no wind, filters at zero speed and at the parameter directions.

    (SITL starts its direction filters at 0 deg; starting them at the parameter values avoids
    a wind that swings round while it ramps up, and changes nothing once they have settled.)
    """
    x[X.WIND_N] = 0.0
    x[X.WIND_E] = 0.0
    x[X.WIND_D] = 0.0
    x[X.WIND_SPD_F] = 0.0
    x[X.GUST_H] = 0.0
    x[X.GUST_V] = 0.0
    _set_direction(x, wrap_360(frame[F_WIND_DIR]), frame[F_WIND_DIR_Z])


@tick_jit
def update_wind(x: np.ndarray, frame: np.ndarray, dt: float, t_s: float,
                rng: np.ndarray) -> None:
    """Advance the wind model by ``dt`` [s] at simulated time ``t_s`` [s]; writes WIND_N/E/D.
    ``rng``: the wind's random generator state (:mod:`tlm_sim.rng`).

    The height used by the profile is the height of the ground-contact point above home
    ground, ``-PD - frame_height`` [m] (what the barometer reads relative to the pad).
    """
    wn = 0.0
    we = 0.0
    wd = 0.0
    if t_s > WIND_START_DELAY_S:
        tc = frame[F_WIND_TC]
        alpha = dt / (dt + tc) if tc > 0.0 else 1.0
        spd = x[X.WIND_SPD_F] + alpha * (frame[F_WIND_SPD] - x[X.WIND_SPD_F])
        x[X.WIND_SPD_F] = spd
        dir_old = x[X.WIND_DIR_F]
        dirz_old = x[X.WIND_DIRZ_F]
        dirf = wrap_360(dir_old + alpha * wrap_180(frame[F_WIND_DIR] - dir_old))
        dirz = dirz_old + alpha * wrap_180(frame[F_WIND_DIR_Z] - dirz_old)
        if dirf != dir_old or dirz != dirz_old:
            _set_direction(x, dirf, dirz)
        s = 0.0
        if spd != 0.0 or frame[F_WIND_T] > 1.5:
            s = profile_speed(spd, -x[X.PD] - frame[F_FRAME_HEIGHT], frame)
        # vector pointing where the wind comes FROM; negated at the end
        wn = s * x[X.WIND_UN]
        we = s * x[X.WIND_UE]
        wd = s * x[X.WIND_UD]
        turb = frame[F_WIND_TURB]
        if turb > 0.0 and x[X.ON_GROUND] < 0.5:
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
