"""The simulated vehicle's log messages: SIM (the truth attitude and position, 10 Hz) and SIM2
(the truth position and velocity relative to home and the pitot airspeed, 50 Hz: SITL logs it
every loop, capped by LOG_FILE_RATEMAX 50). Columns by name (:mod:`tlm_sim.logger`). (BAT is
the autopilot's battery monitor: tlm_sim.control.log.)"""

import math

from tlm_sim import logger as L
from tlm_sim._jit import tick_jit
from tlm_sim.dynamics import layout as X
from tlm_sim.dynamics.atmosphere import RHO0
from tlm_sim.geo import ne_to_latlon_scalar

SIM, SIM2 = L.SIM_COLS, L.SIM2_COLS
PITOT_AOA_MAX = math.radians(20.0)  # SITL's pitot reads the full airspeed up to 20 deg off
PITOT_TAN_AOA_MAX = math.tan(PITOT_AOA_MAX)
PITOT_GAIN = 0.5 * math.pi / (0.5 * math.pi - PITOT_AOA_MAX)  # ... then falls off as a cosine


@tick_jit
def log_dynamics_10hz(log, t_us, x, home):
    """The SIM row from the truth state x (home: degrees, m AMSL)."""
    bufs = log[0]  # the log buffers
    home_lat, home_lon, home_alt = home[0], home[1], home[2]  # deg, deg, m AMSL
    r = L.new_row(log, L.K_SIM, t_us)
    if r >= 0:
        b = bufs[L.K_SIM]
        tr, tp, ty = L.euler_deg(x[X.QW], x[X.QX], x[X.QY], x[X.QZ])
        lat, lon = ne_to_latlon_scalar(x[X.PN], x[X.PE], home_lat, home_lon)
        b[r, SIM.Roll] = tr
        b[r, SIM.Pitch] = tp
        b[r, SIM.Yaw] = ty
        b[r, SIM.Alt] = home_alt - x[X.PD]
        b[r, SIM.Lat] = lat
        b[r, SIM.Lng] = lon
        for k in range(4):
            b[r, SIM.Q1 + k] = x[X.QW + k]


@tick_jit
def log_sim2(log, t_us, x):
    """The SIM2 row from the truth state x: NED position from home [m] and velocity [m/s], the
    airspeed a forward pitot tube would read (SITL's airspeed_pitot: the equivalent airspeed,
    cut by the flow's angle to the body x axis beyond 20 deg, 0 beyond 90 deg) and the
    serial-output pauses (none). ASpdU, SITL's achieved wall-clock speed-up, is SIM_SPEEDUP,
    filled in after the flight (tlm's time is simulated only; tlm_sim.flight.fill_evidence)."""
    bufs = log[0]  # the log buffers
    r = L.new_row(log, L.K_SIM2, t_us)
    if r < 0:
        return
    b = bufs[L.K_SIM2]
    b[r, SIM2.PN] = x[X.PN]
    b[r, SIM2.PE] = x[X.PE]
    b[r, SIM2.PD] = x[X.PD]
    b[r, SIM2.VN] = x[X.VN]
    b[r, SIM2.VE] = x[X.VE]
    b[r, SIM2.VD] = x[X.VD]
    vx, vy, vz = x[X.VAIR_X], x[X.VAIR_Y], x[X.VAIR_Z]
    side = math.sqrt(vy * vy + vz * vz)
    eas = math.sqrt(vx * vx + side * side) * math.sqrt(x[X.RHO] / RHO0)
    if vx < 0.0:  # the flow comes from behind: more than 90 deg off the nose
        eas = 0.0
    elif side > vx * PITOT_TAN_AOA_MAX:
        eas *= math.cos((math.atan2(side, vx) - PITOT_AOA_MAX) * PITOT_GAIN)
    b[r, SIM2.As] = eas
    b[r, SIM2.UFC] = 0.0
