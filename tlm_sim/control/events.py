"""Event log rows (MODE, EV, ERR) written by the vehicle logic into the flight's log buffers
(the tuple and row counts of :mod:`tlm_sim.logger`, columns by name from the schema). The
codes they carry are :mod:`tlm_sim.ardupilot`'s (``EV_*``, ``ERR_*``, ``MODE_*``, ``RSN_*``).
"""

from tlm_sim import logger as L
from tlm_sim._jit import tick_jit

MODE, EV, ERR = L.MODE_COLS, L.EV_COLS, L.ERR_COLS


@tick_jit
def log_mode(ev, t_us, mode, rsn):
    """Append a MODE row (mode number, reason) to the flight's log buffers."""
    r = L.new_row(ev, L.E_MODE, t_us)
    if r >= 0:
        b = ev[0][L.E_MODE]
        b[r, MODE.Mode] = mode
        b[r, MODE.ModeNum] = mode
        b[r, MODE.Rsn] = rsn


@tick_jit
def log_err(ev, t_us, subsys, code):
    """Append an ERR row (subsystem, error code)."""
    r = L.new_row(ev, L.E_ERR, t_us)
    if r >= 0:
        ev[0][L.E_ERR][r, ERR.Subsys] = subsys
        ev[0][L.E_ERR][r, ERR.ECode] = code


@tick_jit
def log_ev(ev, t_us, ev_id):
    """Append an EV row (event id)."""
    r = L.new_row(ev, L.E_EV, t_us)
    if r >= 0:
        ev[0][L.E_EV][r, EV.Id] = ev_id
