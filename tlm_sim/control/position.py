"""Position controller (AC_PosControl structure, our implementation).

Horizontal: position error -> square-root velocity demand (PSC_POSXY_P) + feed-forward ->
velocity PID (PSC_VELXY_*) -> acceleration -> lean angles in the heading frame, limited to
ANGLE_MAX. Vertical: position error -> velocity demand (PSC_POSZ_P) -> acceleration demand
(PSC_VELZ_P) -> acceleration PID (PSC_ACCZ_*, ArduPilot's cm/s^2 units, x0.001) + hover throttle.
NED positions/velocities in m, m/s; PZ_ACC_T is "up" acceleration like ArduPilot's ADes.
"""

import math

from tlm_sim._jit import tick_jit
from tlm_sim.control import layout as C
from tlm_sim.control.attitude import sqrt_ctrl

GRAVITY = 9.80665
VIBE_COMP_P_GAIN = 0.25  # throttle per (hover throttle per cm/s^2) of acceleration target
VIBE_COMP_I_GAIN = 0.125  # integrator gain on the velocity error, x PSC_VELZ_P


@tick_jit
def xy_reset(c, pn, pe, vn, ve):
    """Hold the current position: target = estimate, integrators cleared."""
    c[C.PXY_POS_T] = pn
    c[C.PXY_POS_T + 1] = pe
    for k in range(2):
        c[C.PXY_VEL_T + k] = 0.0
        c[C.PXY_ACC_T + k] = 0.0
        c[C.PXY_VEL_FF + k] = 0.0
        c[C.PXY_ACC_FF + k] = 0.0
        c[C.PXY_I + k] = 0.0
        c[C.PXY_EF + k] = 0.0
        c[C.PXY_DF + k] = 0.0
        c[C.PXY_EPREV + k] = 0.0
    c[C.PXY_VEL_T] = 0.0


@tick_jit
def xy_update(c, g, pos, vel, cy, sy):
    """Run the horizontal controller on the EKF position/velocity (NED); sets ATT_ROLL/PITCH_CMD.

    cy, sy: cosine and sine of the vehicle heading.
    """
    dt = g[C.G_DT]
    accel_max = g[C.G_ACCEL_XY_MAX]
    # position -> velocity (square-root shaped along the error vector)
    en = c[C.PXY_POS_T] - pos[0]
    ee = c[C.PXY_POS_T + 1] - pos[1]
    dist = math.sqrt(en * en + ee * ee)
    vcorr = sqrt_ctrl(dist, g[C.G_POSXY_P], 0.5 * g[C.G_WP_ACCEL] + 1.0, dt)
    if dist > 1e-9:
        vcn = vcorr * en / dist
        vce = vcorr * ee / dist
    else:
        vcn = 0.0
        vce = 0.0
    c[C.PXY_VEL_T] = c[C.PXY_VEL_FF] + vcn
    c[C.PXY_VEL_T + 1] = c[C.PXY_VEL_FF + 1] + vce
    # velocity PID (per axis)
    an = c[C.PXY_ACC_FF]
    ae = c[C.PXY_ACC_FF + 1]
    for k in range(2):
        err = c[C.PXY_VEL_T + k] - vel[k]
        ef_prev = c[C.PXY_EF + k]
        c[C.PXY_EF + k] += g[C.G_VELXY_FLTE] * (err - ef_prev)
        ef = c[C.PXY_EF + k]
        d = (ef - ef_prev) / dt
        c[C.PXY_DF + k] += g[C.G_VELXY_FLTD] * (d - c[C.PXY_DF + k])
        i_new = c[C.PXY_I + k] + g[C.G_VELXY_I] * ef * dt
        imax = g[C.G_VELXY_IMAX]
        c[C.PXY_I + k] = min(max(i_new, -imax), imax)
        a = g[C.G_VELXY_P] * ef + g[C.G_VELXY_D] * c[C.PXY_DF + k] + c[C.PXY_I + k]
        if k == 0:
            an += a
        else:
            ae += a
    amag = math.sqrt(an * an + ae * ae)
    if amag > accel_max:
        an *= accel_max / amag
        ae *= accel_max / amag
    c[C.PXY_ACC_T] = an
    c[C.PXY_ACC_T + 1] = ae
    # acceleration -> lean angles in the heading frame
    a_fwd = an * cy + ae * sy
    a_rgt = -an * sy + ae * cy
    u = -a_fwd / GRAVITY
    pitch = math.atan(u)
    roll = math.atan(a_rgt / math.sqrt(1.0 + u * u) / GRAVITY)  # cos(atan(u)) = 1/sqrt(1+u^2)
    c[C.ATT_ROLL_CMD] = roll
    c[C.ATT_PITCH_CMD] = pitch


@tick_jit
def z_reset(c, g, pd, vd, throttle):
    """Hold the current altitude; the accel integrator starts at throttle - hover."""
    c[C.PZ_POS_T] = pd
    c[C.PZ_VEL_T] = 0.0
    c[C.PZ_VEL_FF] = 0.0
    c[C.PZ_ACC_T] = 0.0
    c[C.PZ_ACC_EF] = 0.0
    c[C.PZ_I] = throttle - c[C.THR_HOVER]


@tick_jit
def z_update(c, g, pd, vd, acc_up_meas, limit_lo, limit_hi):
    """Run the vertical controller; returns the throttle demand 0..1 (before angle boost).

    pd, vd: EKF down position [m] and velocity [m/s]; acc_up_meas: measured up acceleration
    [m/s^2] (earth frame, gravity removed); limit_lo/hi: mixer throttle saturation flags.

    With vibration compensation on (c[VIBE_COMP]) the velocity is the height-rate filter's
    (c[VCF_VEL]) and the throttle comes from the velocity loop alone, ignoring the
    accelerometers: P 0.25 on the acceleration target and an integrator fed by the velocity
    error at 0.125 x PSC_VELZ_P, both scaled by hover throttle per cm/s^2 (ArduPilot's
    POSCONTROL_VIBE_COMP gains).
    """
    dt = g[C.G_DT]
    up_max = g[C.G_WP_SPEED_UP]
    dn_max = g[C.G_WP_SPEED_DN]
    vibe = c[C.VIBE_COMP] != 0.0
    v_up_est = -c[C.VCF_VEL] if vibe else -vd
    err_up = -(c[C.PZ_POS_T] - pd)  # positive when the target is above
    v_up = sqrt_ctrl(err_up, g[C.G_POSZ_P], g[C.G_WP_ACCEL_Z], dt) - c[C.PZ_VEL_FF]
    v_up = min(max(v_up, -dn_max), up_max)
    c[C.PZ_VEL_T] = -v_up
    acc_up = g[C.G_VELZ_P] * (v_up - v_up_est)
    c[C.PZ_ACC_T] = acc_up
    c[C.PZ_ACC_MEAS] = acc_up_meas
    imax = g[C.G_ACCZ_IMAX] * 0.001
    if vibe:
        thr_per_cmss = c[C.THR_HOVER] / 980.665
        verr_cm = (v_up - v_up_est) * 100.0
        i_new = c[C.PZ_I] + dt * thr_per_cmss * verr_cm * g[C.G_VELZ_P] * VIBE_COMP_I_GAIN
        # integrate unless saturated, or when integrating unwinds the integrator
        if (not (limit_lo or limit_hi) or (c[C.PZ_I] > 0.0 and verr_cm < 0.0)
                or (c[C.PZ_I] < 0.0 and verr_cm > 0.0)):
            c[C.PZ_I] = min(max(i_new, -imax), imax)
        thr = VIBE_COMP_P_GAIN * thr_per_cmss * acc_up * 100.0 + c[C.PZ_I] + c[C.THR_HOVER]
        return min(max(thr, 0.0), 1.0)
    # acceleration PID in ArduPilot units (cm/s^2 in, throttle x1000 out)
    err_cm = (acc_up - acc_up_meas) * 100.0
    c[C.PZ_ACC_EF] += g[C.G_ACCZ_FLTE] * (err_cm - c[C.PZ_ACC_EF])
    ef = c[C.PZ_ACC_EF]
    i_new = c[C.PZ_I] + g[C.G_ACCZ_I] * ef * dt * 0.001
    i_new = min(max(i_new, -imax), imax)
    if (limit_lo and i_new < c[C.PZ_I]) or (limit_hi and i_new > c[C.PZ_I]):
        i_new = c[C.PZ_I]
    c[C.PZ_I] = i_new
    thr = g[C.G_ACCZ_P] * ef * 0.001 + c[C.PZ_I] + c[C.THR_HOVER]
    return min(max(thr, 0.0), 1.0)


@tick_jit
def angle_boost(throttle, cos_tilt):
    """ATC_ANGLE_BOOST: raise throttle by 1/cos(tilt), fading out when nearly inverted."""
    inverted = min(max(10.0 * cos_tilt, 0.0), 1.0)
    return min(throttle * inverted / max(cos_tilt, 0.5), 1.0)
