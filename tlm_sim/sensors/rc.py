"""RC receiver as SITL feeds it to the autopilot: 50 Hz frames of 8 channels (PWM, us).

Without a pilot the receiver sends SITL's idle channels: 1500, 1500, 1000, 1500, 1800, 1000,
1000, 1800. A pilot-flown flight has an RC table (``FlightPlan.rc``: rows of time since boot
[us] and channels 1..8 [us]; a stick script rendered by :mod:`tlm_sim.mission.sticks`, or a
log's RCIN for a replay): each frame carries the last row at or before its time.

A table's throttle (channel 3) may instead hand the stick to the pilot's hand
(:func:`pilot_hand`), as a pilot flying STABILIZE or ACRO works it: :data:`HOLD_PWM` holds the
height the copter has when it starts, :data:`LAND_PWM` descends at :data:`HAND_DESCENT_MS` and
puts the stick down on touchdown, a code at or below :data:`HEIGHT_PWM` climbs or descends to
the height it carries (:func:`height_code`) and holds it (stick script ``throttle: hold`` /
``land``, ``height: H``).

SIM_RC_FAIL = 1 stops the frames (radio failsafe by timeout); 2 keeps frames coming with every
channel at 1500 and throttle (channel 3) at 950 us (failsafe by low throttle), whatever the
pilot does.
"""

from tlm_sim._jit import inline_jit, tick_jit
from tlm_sim.ardupilot import RC_IDLE_PWM
from tlm_sim.dynamics import layout as X
from tlm_sim.mission.sticks import HEIGHT_PWM, HOLD_PWM, LAND_PWM
from tlm_sim.sensors import layout as S

RC_FRAME_US = 20000.0  # 50 Hz
RC_DEFAULTS = RC_IDLE_PWM
#: columns of an RC table row: the time [us since boot], then channels 1..8 [us]
RC_T, RC_C1 = 0, 1
RC_COLS = 9
#: the pilot's hand: a steady pilot's PID from height to throttle stick (gains chosen for a
#: vertical loop of about 1.6 rad/s, critically damped: an estimate from the default quad's
#: thrust per us of stick around mid-stick, not a measurement)
HAND_KP = 80.0  # us of stick per m below the height held
HAND_KD = 100.0  # us per m/s of climb (beyond the descent wanted, landing)
HAND_KI = 20.0  # us per m s: the stick that hovers, learnt
HAND_CLIMB_MS = 1.5  # the hand's climb to a height [m/s]
HAND_LEAD_M = 1.0  # the height held stays within this of the copter's [m]
HAND_DESCENT_MS = 0.7  # the hand's descent to a height, and landing [m/s]
#: landing: the copter rests (the height held this far below it, the climb above
#: -TOUCHDOWN_CLIMB_MS): the stick goes down
TOUCHDOWN_LAG_M = 0.99 * HAND_LEAD_M
TOUCHDOWN_CLIMB_MS = 0.2


@tick_jit
def rc_init(s, t_us):
    """Receiver with the SITL default channel values; first frame at t_us."""
    for k in range(8):
        s[S.RC_CH + k] = RC_DEFAULTS[k]
    s[S.RC_NEXT_US] = t_us
    s[S.RC_LAST_FRAME_US] = t_us
    s[S.RC_ROW] = 0.0


@tick_jit
def rc_update(s, cfg, t_us, table, x):
    """Deliver the frames due at t_us according to SIM_RC_FAIL, the channels from the RC
    table (its last row at or before t_us; SITL's idle channels before its first row or
    without one; the throttle codes flown by :func:`pilot_hand` from the truth state x);
    returns True if a frame arrived."""
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
        if s[S.RC_CH + 2] < 0.0:
            s[S.RC_CH + 2] = pilot_hand(s, cfg, x, s[S.RC_CH + 2])
        else:
            s[S.RC_HAND] = 0.0
    s[S.RC_LAST_FRAME_US] = t_us
    return True


@inline_jit
def pilot_hand(s, cfg, x, code):
    """The throttle stick [us] a steady pilot gives this frame (code: :data:`HOLD_PWM`,
    :data:`LAND_PWM` or a :func:`height_code`). At a new code the height held is the copter's
    (above home); taking the stick, the learnt stick is mid-stick (where STABILIZE's and
    ACRO's throttle curve puts the hover), kept from code to code. The height held then moves
    towards the goal (the start's height, the code's, or the ground when landing) at
    HAND_CLIMB_MS up and HAND_DESCENT_MS down, never more than HAND_LEAD_M from the copter's,
    and a PID on the height and the climb gives the stick, within RC3_MIN..RC3_MAX. Landing,
    the stick goes down once the copter rests on the ground (it no longer sinks with the
    height held a metre below it) and stays down. The pilot sees the copter as the sensors do
    (x's sensor shadow)."""
    dt = RC_FRAME_US * 1e-6
    lo, hi = cfg[S.C_RC3_RANGE], cfg[S.C_RC3_RANGE + 1]
    h = -x[X.SPD]
    climb = -x[X.SVD]
    if s[S.RC_HAND] != code:
        if s[S.RC_HAND] == 0.0:  # the hand takes the stick: hover is mid-stick
            s[S.RC_HAND_I] = 0.5 * (lo + hi)
        s[S.RC_HAND] = code
        s[S.RC_HAND_ALT] = h
        s[S.RC_HAND_GOAL] = h if code == HOLD_PWM else (-1e9 if code == LAND_PWM
                                                         else HEIGHT_PWM - code)
    if code == LAND_PWM and (s[S.RC_HAND_GOAL] > 0.0 or (
            s[S.RC_HAND_ALT] <= h - TOUCHDOWN_LAG_M and climb > -TOUCHDOWN_CLIMB_MS)):
        s[S.RC_HAND_GOAL] = 1.0  # down: the stick stays low
        return lo
    step = min(max(s[S.RC_HAND_GOAL] - s[S.RC_HAND_ALT], -HAND_DESCENT_MS * dt),
               HAND_CLIMB_MS * dt)
    s[S.RC_HAND_ALT] = min(max(s[S.RC_HAND_ALT] + step, h - HAND_LEAD_M), h + HAND_LEAD_M)
    want = step / dt
    err = s[S.RC_HAND_ALT] - h
    s[S.RC_HAND_I] = min(max(s[S.RC_HAND_I] + HAND_KI * err * dt, lo), hi)
    return min(max(s[S.RC_HAND_I] + HAND_KP * err - HAND_KD * (climb - want), lo), hi)
