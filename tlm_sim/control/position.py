"""Position controller (AC_PosControl structure, our implementation).

Horizontal: position error -> square-root velocity demand (PSC_POSXY_P) + feed-forward ->
velocity PID (PSC_VELXY_*) -> acceleration -> lean angles in the heading frame, limited to
ANGLE_MAX. Vertical: position error -> velocity demand (PSC_POSZ_P) -> acceleration demand
(PSC_VELZ_P) + the path's acceleration feed-forward -> acceleration PID (PSC_ACCZ_*, ArduPilot's
cm/s^2 units, x0.001) + hover throttle.
NED positions/velocities in m, m/s; PZ_ACC_T is "up" acceleration like ArduPilot's ADes.
"""

import math

from tlm_sim._jit import inline_jit, tick_jit
from tlm_sim.ardupilot import GRAVITY_MSS
from tlm_sim.control import layout as C
from tlm_sim.control.attitude import sqrt_ctrl

#: the lean-angle limit from the throttle headroom never goes below this (AC_AttitudeControl's
#: AC_ATTITUDE_CONTROL_ANGLE_LIMIT_MIN, 10 deg); engine_s14.bin shows it on the ground after the
#: crash: throttle saturated, the lean target held at 10 deg (accel target 1.73 m/s^2) for 25 s
LEAN_LIMIT_MIN = math.radians(10.0)
#: throttle fraction (of the maximum thrust) above which the lean is limited
#: (AC_ATTITUDE_CONTROL_ANGLE_LIMIT_THROTTLE_MAX)
LEAN_LIMIT_THROTTLE = 0.8
#: AC_PosControl's POSCONTROL_RELAX_TC [s]: the time constant of soften_for_landing's decay
POSCONTROL_RELAX_TC = 0.16
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
        c[C.PXY_LIMIT + k] = 0.0
    c[C.PXY_VEL_T] = 0.0


@tick_jit
def xy_init_stopping_point(c, g, pos, vel):
    """Restart the horizontal controller without a bump (AC_PosControl's
    init_xy_controller_stopping_point); returns the stopping point (north, east) [m].

    The new target is where the vehicle would stop, at the distance the square-root position
    controller (PSC_POSXY_P, WPNAV_ACCEL) needs from its current speed, so that the position
    loop at first asks for exactly the current velocity; the velocity integrator takes the
    current acceleration target (the present lean), and the filters restart from zero error.
    """
    kp = g[C.G_POSXY_P]
    accel = g[C.G_WP_ACCEL]
    vn, ve = vel[0], vel[1]
    v = math.sqrt(vn * vn + ve * ve)
    sn, se = pos[0], pos[1]
    if v > 1e-6 and kp > 0.0 and accel > 0.0:
        lin = accel / kp
        d = v / kp if v <= lin else 0.5 * accel / (kp * kp) + v * v / (2.0 * accel)
        sn += vn * d / v
        se += ve * d / v
    imax = g[C.G_VELXY_IMAX]
    for k in range(2):
        c[C.PXY_I + k] = min(max(c[C.PXY_ACC_T + k], -imax), imax)
        c[C.PXY_LIMIT + k] = 0.0
        c[C.PXY_VEL_FF + k] = 0.0
        c[C.PXY_ACC_FF + k] = 0.0
        c[C.PXY_EF + k] = 0.0
        c[C.PXY_DF + k] = 0.0
        c[C.PXY_EPREV + k] = 0.0
    c[C.PXY_POS_T] = sn
    c[C.PXY_POS_T + 1] = se
    return sn, se


@tick_jit
def relax_xy_target(c, pos, dt):
    """AC_PosControl::soften_for_landing_NE's position part: the horizontal position target
    decays to the estimate pos (NED) [m] with POSCONTROL_RELAX_TC, dt [s]."""
    k = dt / (dt + POSCONTROL_RELAX_TC)
    for j in range(2):
        c[C.PXY_POS_T + j] += (pos[j] - c[C.PXY_POS_T + j]) * k


@tick_jit
def soften_for_landing_xy(c, pos, dt):
    """AC_PosControl::soften_for_landing_NE, while the land detector says maybe landed (LAND,
    and AC_Loiter's soften_for_landing in LOITER and POSHOLD): the horizontal position target
    decays to the estimate pos (NED) [m] (:func:`relax_xy_target`), and the velocity
    integrator may not grow along last tick's acceleration target
    (set_externally_limited_NE), so a copter on the ground in wind does not wind its lean
    target up before the detector completes."""
    relax_xy_target(c, pos, dt)
    for j in range(2):
        c[C.PXY_LIMIT + j] = c[C.PXY_ACC_T + j]


@tick_jit
def althold_lean_update(c, g, throttle):
    """Update the lean-angle limit from the throttle demand (0..1): acos(throttle / 0.8) low-passed
    with ATC_ANG_LIM_TC, so that a saturated throttle leaves thrust for height before lean
    (AC_AttitudeControl_Multi's althold lean angle limit)."""
    target = math.acos(min(max(throttle / LEAN_LIMIT_THROTTLE, 0.0), 1.0))
    c[C.ALTHOLD_LEAN] += g[C.G_ANG_LIM_ALPHA] * (target - c[C.ALTHOLD_LEAN])


@inline_jit
def _limit_accel_xy(c, an, ae, accel_max):
    """The horizontal acceleration (an, ae) [m/s^2] limited to accel_max, keeping the part
    across the desired velocity (PXY_VEL_FF) first (AC_PosControl's limit_accel_xy); records
    the unlimited vector in PXY_LIMIT while limited (else zero). Returns the limited vector."""
    c[C.PXY_LIMIT] = 0.0
    c[C.PXY_LIMIT + 1] = 0.0
    amag2 = an * an + ae * ae
    if amag2 > accel_max * accel_max:
        c[C.PXY_LIMIT] = an
        c[C.PXY_LIMIT + 1] = ae
        vn, ve = c[C.PXY_VEL_FF], c[C.PXY_VEL_FF + 1]
        vm = math.sqrt(vn * vn + ve * ve)
        if vm > 1e-6:
            un, ue = vn / vm, ve / vm
            a_dir = un * an + ue * ae
            xn, xe = an - un * a_dir, ae - ue * a_dir
            xm = math.sqrt(xn * xn + xe * xe)
            if xm > accel_max:
                xn *= accel_max / xm
                xe *= accel_max / xm
                a_dir = 0.0
            else:
                a_lim = math.sqrt(max(accel_max * accel_max - xm * xm, 0.0))
                a_dir = min(max(a_dir, -a_lim), a_lim)
            an = xn + un * a_dir
            ae = xe + ue * a_dir
        else:
            k = accel_max / math.sqrt(amag2)
            an *= k
            ae *= k
    return an, ae


@tick_jit
def xy_update(c, g, pos, vel, cy, sy):
    """:func:`xy_control` with the waypoint navigation's position correction (WPNAV_ACCEL,
    the error that asks for WPNAV_SPEED): AUTO, GUIDED, RTL, LAND."""
    xy_control(c, g, pos, vel, cy, sy, (g[C.G_WP_ACCEL], g[C.G_POSXY_ERR_MAX]))


@tick_jit
def xy_control(c, g, pos, vel, cy, sy, corr):
    """Run the horizontal controller on the EKF position/velocity (NED); sets ATT_ROLL/PITCH_CMD.

    cy, sy: cosine and sine of the heading the lean angles are about (the attitude target's);
    corr: the position correction's acceleration limit [m/s^2] and the largest position error
    it acts on [m] (waypoints: WPNAV_ACCEL and the error asking for WPNAV_SPEED; LOITER:
    LOIT_ACC_MAX and 2 m).
    The acceleration is limited to the lean angle min(ANGLE_MAX, max(ALTHOLD_LEAN, 10 deg)),
    keeping the part across the desired velocity first; while limited, the velocity integrator
    does not grow along the limit.
    """
    dt = g[C.G_DT]
    lean = max(c[C.ALTHOLD_LEAN], LEAN_LIMIT_MIN)
    accel_max = g[C.G_ACCEL_XY_MAX]
    if lean < g[C.G_ANGLE_MAX]:
        accel_max = GRAVITY_MSS * math.tan(lean)
    # position -> velocity (square-root shaped along the error vector, PSC_POSXY_P and
    # WPNAV_ACCEL). As AC_P_2D, an error beyond the one that asks for WPNAV_SPEED is cut to that
    # length and the target moved to match: after a jump of the position estimate (the EKF
    # stopping or resuming aiding) the vehicle flies towards its target at the feed-forward
    # plus at most WPNAV_SPEED.
    en = c[C.PXY_POS_T] - pos[0]
    ee = c[C.PXY_POS_T + 1] - pos[1]
    dist = math.sqrt(en * en + ee * ee)
    corr_accel, emax = corr
    if dist > emax:
        en *= emax / dist
        ee *= emax / dist
        dist = emax
        c[C.PXY_POS_T] = pos[0] + en
        c[C.PXY_POS_T + 1] = pos[1] + ee
    vcorr = sqrt_ctrl(dist, g[C.G_POSXY_P], corr_accel, dt)
    if dist > 1e-9:
        vcn = vcorr * en / dist
        vce = vcorr * ee / dist
    else:
        vcn = 0.0
        vce = 0.0
    c[C.PXY_VEL_T] = c[C.PXY_VEL_FF] + vcn
    c[C.PXY_VEL_T + 1] = c[C.PXY_VEL_FF + 1] + vce
    # velocity PID (2-D: the integrator may not grow along last tick's limited acceleration)
    an = c[C.PXY_ACC_FF]
    ae = c[C.PXY_ACC_FF + 1]
    di_n = 0.0
    di_e = 0.0
    for k in range(2):
        err = c[C.PXY_VEL_T + k] - vel[k]
        ef_prev = c[C.PXY_EF + k]
        c[C.PXY_EF + k] += g[C.G_VELXY_FLTE] * (err - ef_prev)
        ef = c[C.PXY_EF + k]
        d = (ef - ef_prev) / dt
        c[C.PXY_DF + k] += g[C.G_VELXY_FLTD] * (d - c[C.PXY_DF + k])
        if k == 0:
            di_n = g[C.G_VELXY_I] * ef * dt
        else:
            di_e = g[C.G_VELXY_I] * ef * dt
    ln, le = c[C.PXY_LIMIT], c[C.PXY_LIMIT + 1]
    if di_n * ln + di_e * le > 0.0:
        di_n = 0.0
        di_e = 0.0
    i_n = c[C.PXY_I] + di_n
    i_e = c[C.PXY_I + 1] + di_e
    imax = g[C.G_VELXY_IMAX]
    im = math.sqrt(i_n * i_n + i_e * i_e)
    if im > imax:
        i_n *= imax / im
        i_e *= imax / im
    c[C.PXY_I] = i_n
    c[C.PXY_I + 1] = i_e
    for k in range(2):
        a = g[C.G_VELXY_P] * c[C.PXY_EF + k] + g[C.G_VELXY_D] * c[C.PXY_DF + k] + c[C.PXY_I + k]
        if k == 0:
            an += a
        else:
            ae += a
    an, ae = _limit_accel_xy(c, an, ae, accel_max)
    c[C.PXY_ACC_T] = an
    c[C.PXY_ACC_T + 1] = ae
    # acceleration -> lean angles in the heading frame
    a_fwd = an * cy + ae * sy
    a_rgt = -an * sy + ae * cy
    u = -a_fwd / GRAVITY_MSS
    pitch = math.atan(u)
    roll = math.atan(a_rgt / math.sqrt(1.0 + u * u) / GRAVITY_MSS)  # cos(atan(u)) = 1/sqrt(1+u^2)
    c[C.ATT_ROLL_CMD] = roll
    c[C.ATT_PITCH_CMD] = pitch


@tick_jit
def z_reset(c, g, pd, vd, throttle):
    """Hold the current altitude; the accel integrator starts at throttle - hover."""
    c[C.PZ_POS_T] = pd
    c[C.PZ_VEL_T] = 0.0
    c[C.PZ_VEL_FF] = 0.0
    c[C.PZ_ACC_FF] = 0.0
    c[C.PZ_ACC_T] = 0.0
    c[C.PZ_ACC_EF] = 0.0
    c[C.PZ_I] = throttle - c[C.THR_HOVER]


@tick_jit
def z_update(c, g, pd, vd, acc_up_meas, limit_lo, limit_hi):
    """:func:`z_control` with the waypoint navigation's limits (WPNAV_SPEED_UP / _DN,
    WPNAV_ACCEL_Z): AUTO, GUIDED, RTL, LAND."""
    return z_control(c, g, (pd, vd, acc_up_meas), (limit_lo, limit_hi),
                     (g[C.G_WP_SPEED_UP], g[C.G_WP_SPEED_DN], g[C.G_WP_ACCEL_Z],
                      g[C.G_POSZ_ERR_UP], g[C.G_POSZ_ERR_DN]))


@tick_jit
def z_control(c, g, meas, limits, kin):
    """Run the vertical controller; returns the throttle demand 0..1 (before angle boost; the
    unclamped demand, as AC_PosControl passes it on, in c[THR_IN_RAW]).

    meas: (pd, vd, acc_up_meas); limits: (limit_lo, limit_hi); kin: the climb and descent
    speed limits [m/s], the correction's acceleration [m/s^2] and the largest position
    errors acted on above and below [m] (waypoints: WPNAV_*; the pilot's modes: PILOT_*).

    pd, vd: EKF down position [m] and velocity [m/s]; acc_up_meas: measured up acceleration
    [m/s^2] (earth frame, gravity removed); limit_lo/hi: mixer throttle saturation flags.

    With vibration compensation on (c[VIBE_COMP]) the velocity is the height-rate filter's
    (c[VCF_VEL]) and the throttle comes from the velocity loop alone, ignoring the
    accelerometers: P 0.25 on the acceleration target and an integrator fed by the velocity
    error at 0.125 x PSC_VELZ_P, both scaled by hover throttle per cm/s^2 (ArduPilot's
    POSCONTROL_VIBE_COMP gains).
    """
    dt = g[C.G_DT]
    pd, vd, acc_up_meas = meas
    limit_lo, limit_hi = limits
    up_max, dn_max, accel_z, err_up_max, err_dn_max = kin
    vibe = c[C.VIBE_COMP] != 0.0
    v_up_est = -c[C.VCF_VEL] if vibe else -vd
    err_up = -(c[C.PZ_POS_T] - pd)  # positive when the target is above
    # as AC_P_1D: the target stays within the errors that ask for WPNAV_SPEED_UP / _DN
    # (combined_s21.bin: during the accelerometer fault's climb PSCD's target is dragged up
    # with the vehicle and then follows it down 1.625 m below, the error asking for 1.5 m/s)
    if err_up > err_up_max:
        err_up = err_up_max
        c[C.PZ_POS_T] = pd - err_up
    elif err_up < -err_dn_max:
        err_up = -err_dn_max
        c[C.PZ_POS_T] = pd - err_up
    v_up = sqrt_ctrl(err_up, g[C.G_POSZ_P], accel_z, dt) - c[C.PZ_VEL_FF]
    v_up = min(max(v_up, -dn_max), up_max)
    c[C.PZ_VEL_T] = -v_up
    acc_up = g[C.G_VELZ_P] * (v_up - v_up_est) - c[C.PZ_ACC_FF]
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
        c[C.THR_IN_RAW] = thr
        return min(max(thr, 0.0), 1.0)
    # acceleration PID in ArduPilot units (cm/s^2 in, throttle x1000 out)
    err_cm = (acc_up - acc_up_meas) * 100.0
    c[C.PZ_ACC_EF] += g[C.G_ACCZ_FLTE] * (err_cm - c[C.PZ_ACC_EF])
    ef = c[C.PZ_ACC_EF]
    # AC_PID::update_i with AC_PosControl's limit (either throttle limit of the motors): while
    # limited the integrator moves only where the error opposes its sign (back towards zero)
    i0 = c[C.PZ_I]
    if not (limit_lo or limit_hi) or (i0 > 0.0 and ef < 0.0) or (i0 < 0.0 and ef > 0.0):
        c[C.PZ_I] = min(max(i0 + g[C.G_ACCZ_I] * ef * dt * 0.001, -imax), imax)
    thr = g[C.G_ACCZ_P] * ef * 0.001 + c[C.PZ_I] + c[C.THR_HOVER]
    c[C.THR_IN_RAW] = thr
    return min(max(thr, 0.0), 1.0)


@tick_jit
def angle_boost(throttle, cos_tilt):
    """ATC_ANGLE_BOOST: raise throttle by 1/cos(tilt), fading out when nearly inverted."""
    inverted = min(max(10.0 * cos_tilt, 0.0), 1.0)
    return min(throttle * inverted / max(cos_tilt, 0.5), 1.0)
