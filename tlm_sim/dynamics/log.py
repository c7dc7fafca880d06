"""The simulated vehicle's log message SIM (the truth attitude and position), 10 Hz. Columns by
name (:mod:`tlm_sim.logger`). (BAT is the autopilot's battery monitor: tlm_sim.control.log.)"""

from tlm_sim import logger as L
from tlm_sim._jit import tick_jit
from tlm_sim.dynamics import layout as X
from tlm_sim.geo import ne_to_latlon_scalar

SIM = L.SIM_COLS


@tick_jit
def log_dynamics_10hz(bufs, counts, t_us, x, home_lat, home_lon, home_alt):
    """The SIM row from the truth state x (home: degrees, m AMSL)."""
    r = L.new_row(bufs, counts, L.K_SIM, t_us)
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
