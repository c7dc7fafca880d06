"""RC receiver as SITL feeds it to the autopilot: 50 Hz frames of 8 channels (PWM, us).

SIM_RC_FAIL = 1 stops the frames (radio failsafe by timeout); 2 keeps frames coming with every
channel at 1500 and throttle (channel 3) at 950 us (failsafe by low throttle).
Defaults when nothing was ever received: 1500, 1500, 1000, 1500, 1800, 1000, 1000, 1800.
"""

from tlm_sim._jit import tick_jit
from tlm_sim.sensors import layout as S

RC_FRAME_US = 20000.0  # 50 Hz
RC_DEFAULTS = (1500.0, 1500.0, 1000.0, 1500.0, 1800.0, 1000.0, 1000.0, 1800.0)


@tick_jit
def rc_init(s, t_us):
    """Receiver with the SITL default channel values; first frame at t_us."""
    for k in range(8):
        s[S.RC_CH + k] = RC_DEFAULTS[k]
    s[S.RC_NEXT_US] = t_us
    s[S.RC_LAST_FRAME_US] = t_us


@tick_jit
def rc_update(s, cfg, t_us):
    """Deliver the frames due at t_us according to SIM_RC_FAIL; returns True if one arrived."""
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
    else:
        for k in range(8):
            s[S.RC_CH + k] = RC_DEFAULTS[k]
    s[S.RC_LAST_FRAME_US] = t_us
    return True
