"""Event log rows (MODE, EV, ERR) written by the vehicle logic into the flight's log buffers.

Buffers follow tlm_sim.flightlog.schema: MODE (TimeUS, Mode, ModeNum, Rsn), EV (TimeUS, Id),
ERR (TimeUS, Subsys, ECode). ``counts`` holds the row count of each buffer at the index given.
"""

from tlm_sim._jit import tick_jit

# EV ids (AP_Logger LogEvent)
EV_ARMED = 10
EV_DISARMED = 11
EV_AUTO_ARMED = 15
EV_LAND_COMPLETE_MAYBE = 17
EV_LAND_COMPLETE = 18
EV_NOT_LANDED = 28

# ERR subsystems and codes
ERR_RADIO = 2
ERR_FAILSAFE_RADIO = 5
ERR_CRASH_CHECK = 12
ERR_THRUST_LOSS_CHECK = 25
ERR_CODE_RESOLVED = 0
ERR_CODE_FAILSAFE = 1
ERR_CODE_LATE_FRAME = 2


@tick_jit
def log_row3(buf, counts, k, t_us, a, b, c_):
    """Append (TimeUS, a, b, c) to a 4-column buffer (MODE); drops rows when full."""
    n = counts[k]
    if n < buf.shape[0]:
        buf[n, 0] = t_us
        buf[n, 1] = a
        buf[n, 2] = b
        buf[n, 3] = c_
        counts[k] = n + 1


@tick_jit
def log_row2(buf, counts, k, t_us, a, b):
    """Append (TimeUS, a, b) to a 3-column buffer (ERR)."""
    n = counts[k]
    if n < buf.shape[0]:
        buf[n, 0] = t_us
        buf[n, 1] = a
        buf[n, 2] = b
        counts[k] = n + 1


@tick_jit
def log_row1(buf, counts, k, t_us, a):
    """Append (TimeUS, a) to a 2-column buffer (EV)."""
    n = counts[k]
    if n < buf.shape[0]:
        buf[n, 0] = t_us
        buf[n, 1] = a
        counts[k] = n + 1
