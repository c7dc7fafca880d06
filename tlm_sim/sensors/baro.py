"""Barometers as the autopilot reads them (10 Hz).

Two independent barometers (SIM_BARO_COUNT 2; BARO 3 is not modelled), each with its own noise
stream and SITL's fault pipeline (``AP_Baro_SITL::_timer``, sitl-faults.md §3.2): DISABLE stops
its samples; else altitude = truth + accumulated DRIFT + RND uniform noise + GLITCH, replaced by
the last value while FREEZE is set. Altitude is relative to the ground calibration (home);
pressure follows the 1976 standard atmosphere, the temperature SITL's board warm-up
(:func:`board_temperature`, SIM_TEMP_*). A disabled barometer is unhealthy
(``BARO.H`` 0) from its first missed sample (baro_s44.bin: +0.09 s) until it delivers again. The
primary is BARO_PRIMARY (0) while healthy, else the first healthy one (AP_Baro::update); the EKF
fuses the primary. The compasses are in :mod:`tlm_sim.sensors.mag`.
"""

import math

from tlm_sim import ardupilot as AP
from tlm_sim._jit import tick_jit
from tlm_sim.boot import BARO_CAL_S
from tlm_sim.dynamics import layout as X
from tlm_sim.dynamics.atmosphere import pressure_temperature
from tlm_sim.rng import uniform_pm1
from tlm_sim.sensors import layout as S

BARO_PERIOD_S = 0.1  # the autopilot's baro reads (10 Hz): the sample interval of DRIFT
BARO_NOISE_ROWS = (S.RNG_BARO, S.RNG_BARO2)  # noise stream of each instance


@tick_jit
def baro_sample(s, x, cfg, rng, i, t_us):
    """Take baro instance i's sample at t_us: altitude above home ground [m], pressure,
    temperature; returns False (and leaves the last values) while SIM_BARn_DISABLE is set.

    Reads the sensors' view of the truth's height (SITL's sensor smoothing, ``X.SPD``); rng is
    the instance's noise stream (drawn once per sample, also while frozen).
    """
    b = S.BARO_BASE + i * S.BARO_STRIDE
    if cfg[S.C_BARO_DISABLE + i] != 0.0:
        s[b + S.BA_HEALTHY] = 0.0
        return False
    s[b + S.BA_DRIFT] += cfg[S.C_BARO_DRIFT + i] * BARO_PERIOD_S
    h = -x[X.SPD] - cfg[S.C_FRAME_HEIGHT]
    alt = h + s[b + S.BA_DRIFT] + cfg[S.C_BARO_RND + i] * uniform_pm1(rng) \
        + cfg[S.C_BARO_GLITCH + i]
    if cfg[S.C_BARO_FREEZE + i] != 0.0:
        alt = s[b + S.BA_ALT]  # the value stored before freezing
    s[b + S.BA_ALT_PREV] = s[b + S.BA_ALT]
    s[b + S.BA_ALT] = alt
    s[b + S.BA_T_MS] = t_us // 1000
    s[b + S.BA_HEALTHY] = 1.0
    p, t_k = pressure_temperature(cfg[S.C_HOME_ALT] + alt)
    s[b + S.BA_PRESS] = p
    s[b + S.BA_TEMP] = board_temperature(cfg, t_k - 273.15, t_us * 1e-6)
    return True


@tick_jit
def board_temperature(cfg, t_air, t_s):
    """The baro's temperature [degC] at t_s [s] since boot (AP_Baro_SITL's warm-up): from
    SIM_TEMP_START towards the air temperature t_air [degC] (1976 atmosphere at its altitude) +
    SIM_TEMP_BRD_OFF with time constant SIM_TEMP_TCONST; exactly the end value after 23 time
    constants. (SIM_TEMP_BFACTOR's pressure error is not modelled.)"""
    t_end = t_air + cfg[S.C_TEMP_BRD_OFF]
    tc = cfg[S.C_TEMP_TCONST]
    if t_s >= 23.0 * tc:
        return t_end
    return t_end - (t_end - cfg[S.C_TEMP_START]) * math.exp(-t_s / tc)


@tick_jit
def baro_init(s):
    """Power on: both barometers and the primary healthy, first read due at once."""
    s[S.B_NEXT_US] = 0.0
    s[S.B_PRIMARY] = 0.0
    s[S.B_PRIMARY_OK] = 1.0
    for i in range(S.N_BARO):
        s[S.BARO_BASE + i * S.BARO_STRIDE + S.BA_HEALTHY] = 1.0


@tick_jit
def calibration_temperature(cfg):
    """BARO.GndTemp from the boot calibration until the field elevation is set: the sensor
    temperature at tlm_sim.boot.BARO_CAL_S, on the ground at home [degC]."""
    t_air = pressure_temperature(cfg[S.C_HOME_ALT])[1] - 273.15
    return board_temperature(cfg, t_air, BARO_CAL_S)


@tick_jit
def baro_read(s, x, cfg, rng, t_us):
    """The autopilot's 10 Hz baro update at t_us: every instance samples, the primary is chosen
    and its altitude put in B_ALT. Returns (whether the primary has a new sample for the EKF,
    the ERR 18 code to log: 4 when the primary became unhealthy, 0 when it recovered, -1 none).
    """
    new0 = baro_sample(s, x, cfg, rng[BARO_NOISE_ROWS[0]], 0, t_us)
    new1 = baro_sample(s, x, cfg, rng[BARO_NOISE_ROWS[1]], 1, t_us)
    prim = 0
    if s[S.BARO_BASE + S.BA_HEALTHY] == 0.0 and \
            s[S.BARO_BASE + S.BARO_STRIDE + S.BA_HEALTHY] != 0.0:
        prim = 1
    s[S.B_PRIMARY] = prim
    ok = s[S.BARO_BASE + prim * S.BARO_STRIDE + S.BA_HEALTHY]
    s[S.B_ALT] = s[S.BARO_BASE + prim * S.BARO_STRIDE + S.BA_ALT]
    code = -1
    if ok != s[S.B_PRIMARY_OK]:
        code = AP.ERR_CODE_RESOLVED if ok != 0.0 else AP.ERR_CODE_UNHEALTHY
        s[S.B_PRIMARY_OK] = ok
    return (new1 if prim == 1 else new0), code


@tick_jit
def baro_set_field_elevation(s, alt):
    """AP_Baro's field elevation [m AMSL], set at its first reading after the EKF's origin is
    set (BARO.AltAMSL), and its ground temperature from the primary barometer's (BARO.GndTemp)."""
    s[S.B_FIELD_ELEV] = alt
    s[S.B_GND_TEMP] = s[S.BARO_BASE + int(s[S.B_PRIMARY]) * S.BARO_STRIDE + S.BA_TEMP]
