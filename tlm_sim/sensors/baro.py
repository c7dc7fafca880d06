"""Barometer and compass as the autopilot reads them (10 Hz each).

Baro altitude is relative to the ground calibration (home), with SIM_BARO_RND uniform noise and
SIM_BARO_GLITCH offset; pressure and temperature follow the 1976 standard atmosphere. The compass
reports the earth field (NED, gauss) rotated into the body frame plus SIM_MAG_RND noise.
"""


from tlm_sim._jit import tick_jit
from tlm_sim.dynamics import layout as X
from tlm_sim.dynamics.atmosphere import pressure_temperature
from tlm_sim.rng import uniform_pm1
from tlm_sim.sensors import layout as S


@tick_jit
def baro_sample(s, x, cfg, rng):
    """Take a baro sample: altitude above home ground [m], pressure, temperature.

    Reads the sensors' view of the truth's height (SITL's sensor smoothing, ``X.SPD``).
    """
    h = -x[X.SPD] - cfg[S.C_FRAME_HEIGHT]
    alt = h + cfg[S.C_BARO_RND] * uniform_pm1(rng) + cfg[S.C_BARO_GLITCH]
    s[S.B_ALT_PREV] = s[S.B_ALT]
    s[S.B_ALT] = alt
    p, t_k = pressure_temperature(cfg[S.C_HOME_ALT] + alt)
    s[S.B_PRESS] = p
    s[S.B_TEMP] = t_k - 273.15
    return alt
