"""Barometer and compass as the autopilot reads them (10 Hz each).

Baro altitude is relative to the ground calibration (home), with SIM_BARO_RND uniform noise and
SIM_BARO_GLITCH offset; pressure and temperature follow the 1976 standard atmosphere. The compass
reports the earth field (NED, gauss) rotated into the body frame plus SIM_MAG_RND noise.
"""


from tlm_sim._jit import tick_jit
from tlm_sim.dynamics import layout as X
from tlm_sim.dynamics.atmosphere import pressure_temperature
from tlm_sim.rng import uniform_pm1
from tlm_sim.rotation import quat_to_dcm
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


@tick_jit
def mag_sample(s, x, cfg, rng):
    """Take a compass sample: earth field rotated into the body frame [gauss] (+ noise)."""
    qw, qx, qy, qz = x[X.QW], x[X.QX], x[X.QY], x[X.QZ]
    mn = cfg[S.C_MAG_EARTH]
    me = cfg[S.C_MAG_EARTH + 1]
    md = cfg[S.C_MAG_EARTH + 2]
    # R^T m with R the body->NED rotation of q
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = quat_to_dcm(qw, qx, qy, qz)
    s[S.M_FIELD] = r00 * mn + r10 * me + r20 * md
    s[S.M_FIELD + 1] = r01 * mn + r11 * me + r21 * md
    s[S.M_FIELD + 2] = r02 * mn + r12 * me + r22 * md
    rnd = cfg[S.C_MAG_RND]
    if rnd != 0.0:
        for k in range(3):
            s[S.M_FIELD + k] += rnd * uniform_pm1(rng)
