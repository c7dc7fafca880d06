"""Event log rows (MODE, EV, ERR) written by the vehicle logic into the flight's log buffers
(the tuple and row counts of :mod:`tlm_sim.logger`, columns by name from the schema).
"""

from tlm_sim import logger as L
from tlm_sim._jit import tick_jit

MODE, EV, ERR = L.MODE_COLS, L.EV_COLS, L.ERR_COLS

# EV ids (AP_Logger LogEvent)
EV_ARMED = 10
EV_DISARMED = 11
EV_AUTO_ARMED = 15
EV_LAND_COMPLETE_MAYBE = 17
EV_LAND_COMPLETE = 18
EV_NOT_LANDED = 28
EV_SET_HOME = 25

# ERR subsystems and codes
ERR_RADIO = 2
ERR_FAILSAFE_RADIO = 5
ERR_FAILSAFE_BATT = 6
ERR_CRASH_CHECK = 12
ERR_THRUST_LOSS_CHECK = 25
ERR_CODE_RESOLVED = 0
ERR_CODE_FAILSAFE = 1
ERR_CODE_LATE_FRAME = 2


@tick_jit
def log_mode(events, ev_counts, t_us, mode, rsn):
    """Append a MODE row (mode number, reason) to the flight's log buffers."""
    r = L.new_row(events, ev_counts, L.E_MODE, t_us)
    if r >= 0:
        b = events[L.E_MODE]
        b[r, MODE.Mode] = mode
        b[r, MODE.ModeNum] = mode
        b[r, MODE.Rsn] = rsn


@tick_jit
def log_err(events, ev_counts, t_us, subsys, code):
    """Append an ERR row (subsystem, error code)."""
    r = L.new_row(events, ev_counts, L.E_ERR, t_us)
    if r >= 0:
        events[L.E_ERR][r, ERR.Subsys] = subsys
        events[L.E_ERR][r, ERR.ECode] = code


@tick_jit
def log_ev(events, ev_counts, t_us, ev_id):
    """Append an EV row (event id)."""
    r = L.new_row(events, ev_counts, L.E_EV, t_us)
    if r >= 0:
        events[L.E_EV][r, EV.Id] = ev_id
