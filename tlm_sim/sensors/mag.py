"""The three compasses as SITL's copter has them (``AP_Compass_SITL``), read at 10 Hz.

Per compass tick the body field is computed once (SITL ``update_mag_field_bf`` and
``AP_Compass_SITL::_timer``): the earth field plus the ``SIM_MAG_ALY`` anomaly (NED, scaled by
``(H / (h + H))^3`` with H = ``SIM_MAG_ALY_HGT`` and h the height above the home ground) rotated
into the body frame, plus ``SIM_MAG_MOT`` times the battery current, plus ``SIM_MAG_RND``
uniform noise: one draw per axis shared by the three compasses (SITL adds it before the
per-compass stage). Then each compass's ``SIM_MAGn_FAIL`` switch: 0 delivers the field, 1
delivers nothing (the reading and its time stay as they were), 2 delivers its last reading
again (frozen). A compass is healthy while its last sample is under 0.5 s old
(``AP_Compass::read``); what the log shows: ``MAG.Health`` 0 and frozen ``MagX/Y/Z`` and ``S``
for a compass without data.

The per-compass records (``sensors.layout`` MAG: field, new, healthy, time) are what the EKF
reads (:func:`tlm_sim.ekf.lanes.ekf_update`); ``MAG`` logs them. ArduCopter writes
``ERR 3/4`` / ``ERR 3/0`` when the health of the first compass changes: :func:`mag_sample`
returns that change.
"""

import numpy as np

from tlm_sim._jit import tick_jit
from tlm_sim.dynamics import layout as X
from tlm_sim.rng import uniform_pm1
from tlm_sim.rotation import quat_to_dcm
from tlm_sim.sensors import layout as S

#: a compass is healthy while its last sample is younger than 0.5 s (AP_Compass); on tlm's
#: 10 Hz compass ticks (whose times jitter by a physics step) that is: unhealthy from the fifth
#: tick without a sample, hence the threshold half a tick below 0.5 s [us]
HEALTH_TIMEOUT_US = 450000.0
#: SIM_MAGn_FAIL values
MAG_FAIL_NONE, MAG_FAIL_NO_DATA, MAG_FAIL_FROZEN = 0, 1, 2


@tick_jit
def mag_init(s):
    """Power on: no compass healthy yet (no sample); the first compass tick delivers one at
    once and the first compass's change to healthy is ArduCopter's boot ERR 3/0 (every
    reference SITL log has it at its first MAG row)."""
    for i in range(S.N_MAG):
        b = S.MAG_BASE + i * S.MAG_STRIDE
        for k in range(3):
            s[b + S.M_FIELD + k] = 0.0
        s[b + S.M_NEW] = 0.0
        s[b + S.M_HEALTHY] = 0.0
        s[b + S.M_T_US] = 0.0
    s[S.M_NEXT_US] = 0.0


@tick_jit
def body_field(s, x, cfg, rng):
    """The compasses' common body field [gauss] into s[M_BODY:M_BODY + 3]."""
    mn = cfg[S.C_MAG_EARTH]
    me = cfg[S.C_MAG_EARTH + 1]
    md = cfg[S.C_MAG_EARTH + 2]
    an, ae, ad = cfg[S.C_MAG_ALY], cfg[S.C_MAG_ALY + 1], cfg[S.C_MAG_ALY + 2]
    if an != 0.0 or ae != 0.0 or ad != 0.0:
        hh = cfg[S.C_MAG_ALY_HGT]
        h = max(-x[X.PD] - cfg[S.C_FRAME_HEIGHT], 0.0)
        f = (hh / (h + hh)) ** 3
        mn += an * f
        me += ae * f
        md += ad * f
    # R^T m with R the body->NED rotation of q
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = quat_to_dcm(x[X.QW], x[X.QX], x[X.QY], x[X.QZ])
    s[S.M_BODY] = r00 * mn + r10 * me + r20 * md
    s[S.M_BODY + 1] = r01 * mn + r11 * me + r21 * md
    s[S.M_BODY + 2] = r02 * mn + r12 * me + r22 * md
    cur = x[X.BATT_I]
    for k in range(3):
        mot = cfg[S.C_MAG_MOT + k]
        if mot != 0.0:
            s[S.M_BODY + k] += mot * cur
    rnd = cfg[S.C_MAG_RND]
    if rnd != 0.0:
        for k in range(3):
            s[S.M_BODY + k] += rnd * uniform_pm1(rng)


@tick_jit
def mag_sample(s, x, cfg, rng, t_us):
    """One compass tick at t_us: the body field, each compass's fault switch, health.

    Returns the change of the first compass's health: 1 healthy again, -1 unhealthy, 0 none
    (ArduCopter's ERR 3/0 and 3/4).
    """
    body_field(s, x, cfg, rng)
    was = s[S.MAG_BASE + S.M_HEALTHY]
    for i in range(S.N_MAG):
        b = S.MAG_BASE + i * S.MAG_STRIDE
        fail = cfg[S.C_MAG_FAIL + i]
        if fail == MAG_FAIL_NO_DATA:
            s[b + S.M_NEW] = 0.0
        else:
            if fail != MAG_FAIL_FROZEN:
                for k in range(3):
                    s[b + S.M_FIELD + k] = s[S.M_BODY + k]
            s[b + S.M_NEW] = 1.0
            s[b + S.M_T_US] = t_us
        s[b + S.M_HEALTHY] = 1.0 if t_us - s[b + S.M_T_US] < HEALTH_TIMEOUT_US else 0.0
    now = s[S.MAG_BASE + S.M_HEALTHY]
    if now == was:
        return 0
    return 1 if now != 0.0 else -1


def healthy_compasses(field: np.ndarray, t_us: float = 0.0) -> np.ndarray:
    """The compass block (sensors.layout MAG records, N_MAG of them) of three healthy compasses
    that all delivered ``field`` [gauss, body] at ``t_us``: EKF input for tests and tools."""
    block = np.zeros(S.N_MAG * S.MAG_STRIDE)
    for i in range(S.N_MAG):
        b = i * S.MAG_STRIDE
        block[b + S.M_FIELD:b + S.M_FIELD + 3] = field
        block[b + S.M_NEW] = 1.0
        block[b + S.M_HEALTHY] = 1.0
        block[b + S.M_T_US] = t_us
    return block
