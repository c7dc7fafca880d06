"""RC receiver as SITL feeds it to the autopilot: 50 Hz frames of 8 channels (PWM, us).

Without a pilot the receiver sends SITL's idle channels: 1500, 1500, 1000, 1500, 1800, 1000,
1000, 1800. A pilot-flown flight has an RC table (``FlightPlan.rc``: rows of time since boot
[us] and channels 1..8 [us]; a stick script rendered by :mod:`tlm_sim.mission.sticks`, or a
log's RCIN for a replay): each frame carries the last row at or before its time.

SIM_RC_FAIL = 1 stops the frames (radio failsafe by timeout); 2 keeps frames coming with every
channel at 1500 and throttle (channel 3) at 950 us (failsafe by low throttle), whatever the
pilot does.
"""

from tlm_sim._jit import tick_jit
from tlm_sim.ardupilot import RC_IDLE_PWM
from tlm_sim.sensors import layout as S

RC_FRAME_US = 20000.0  # 50 Hz
RC_DEFAULTS = RC_IDLE_PWM
#: columns of an RC table row: the time [us since boot], then channels 1..8 [us]
RC_T, RC_C1 = 0, 1
RC_COLS = 9


@tick_jit
def rc_init(s, t_us):
    """Receiver with the SITL default channel values; first frame at t_us."""
    for k in range(8):
        s[S.RC_CH + k] = RC_DEFAULTS[k]
    s[S.RC_NEXT_US] = t_us
    s[S.RC_LAST_FRAME_US] = t_us
    s[S.RC_ROW] = 0.0


@tick_jit
def rc_update(s, cfg, t_us, table):
    """Deliver the frames due at t_us according to SIM_RC_FAIL, the channels from the RC
    table (its last row at or before t_us; SITL's idle channels before its first row or
    without one); returns True if a frame arrived."""
    if t_us < s[S.RC_NEXT_US]:
        return False
    s[S.RC_NEXT_US] += RC_FRAME_US
    mode = cfg[S.C_RC_FAIL]
    if mode == 1.0:
        return False
    if mode == 2.0:
        for k in range(8):
            s[S.RC_CH + k] = 1500.0
        s[S.RC_CH + 2] = 950.0
    elif table.shape[0] == 0:
        for k in range(8):
            s[S.RC_CH + k] = RC_DEFAULTS[k]
    else:
        row = int(s[S.RC_ROW])
        n = table.shape[0]
        while row < n and table[row, RC_T] <= t_us:
            row += 1
        s[S.RC_ROW] = row
        for k in range(8):
            s[S.RC_CH + k] = RC_DEFAULTS[k] if row == 0 else table[row - 1, RC_C1 + k]
    s[S.RC_LAST_FRAME_US] = t_us
    return True
