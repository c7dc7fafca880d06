"""ArduPilot's DCM attitude estimator (``AP_AHRS_DCM``): the AHRS's second solution, run every
main-loop tick beside the EKF (AP_AHRS::update runs it first) and logged as DCM and AHR2.

A direction cosine matrix (body -> NED) follows the primary gyro's delta angle plus three
corrections (Premerlani & Bizard's complementary filter):

* roll/pitch (``omega_P``, gain AHRS_RP_P, x8 for 20 s after a reset while disarmed): at each
  new GPS fix (or every 0.2 s without GPS), the specific force of every healthy accel rotated to
  NED and integrated since the last fix is compared with gravity (plus, armed with a GPS lock,
  the change of GPS velocity over the interval scaled by AHRS_GPS_GAIN, the accel sum delayed
  by one interval to match the GPS lag). The accel with the smallest error wins; ``error_rp``
  low-passes that error (DCM.ErrRP).
* yaw (``omega_yaw_P``, gain AHRS_YAW_P, lowered when the horizontal acceleration is large):
  at each new sample of the first healthy compass, the heading error of the field rotated to
  the earth frame against the declination; the first sample sets the heading outright.
  ``error_yaw`` low-passes its size (DCM.ErrYaw). A copter never takes yaw from the GPS course.
* gyro drift (``omega_I``): both errors are integrated and applied every 5 s, limited to the
  INS's 0.5 deg/min drift rate, and not while spinning faster than 20 deg/s.

The matrix is re-orthonormalised every tick and reset from its last Euler angles when it
degenerates. Its position (AHR2.Lat/Lng) is the last GPS fix moved on by the last GPS velocity
for the GPS lag plus the time since (at most 0.5 s), dead-reckoned without GPS; its altitude is
the baro's above home (the GPS's with AHRS_GPS_USE 2). Fly-forward (plane) behaviour,
airspeed and wind estimation are not modelled: DCM.VWN/VWE/VWD stay 0, as SITL's copter logs.
"""

import math

from tlm_sim._jit import inline_jit, tick_jit
from tlm_sim.ardupilot import GRAVITY_MSS
from tlm_sim.control import layout as C
from tlm_sim.control.ahrs import _usable_imu
from tlm_sim.control.dcm_layout import (
    D_ACCEL_EF,
    D_ERR_RP,
    D_ERR_YAW,
    D_GPS_LOCK,
    D_GPS_T,
    D_HAVE_POS,
    D_HAVE_YAW,
    D_INIT,
    D_INIT_TRIES,
    D_LAST_TAS,
    D_LAST_VEL,
    D_MAG_T,
    D_OFS_E,
    D_OFS_N,
    D_OMEGA,
    D_OMEGA_I,
    D_OMEGA_I_SUM,
    D_OMEGA_I_SUM_T,
    D_OMEGA_P,
    D_OMEGA_YAW_P,
    D_PITCH,
    D_POS_E,
    D_POS_N,
    D_R,
    D_RA_DELAY,
    D_RA_DT,
    D_RA_START,
    D_RA_SUM,
    D_ROLL,
    D_T_POS,
    D_T_START,
    D_YAW,
    N_DCM,
)
from tlm_sim.sensors import layout as S

KI = 0.0087  # roll/pitch drift integrator gain
KI_YAW = 0.01  # yaw drift integrator gain
RP_P_MIN = 0.05  # floor of AHRS_RP_P
YAW_P_MIN = 0.05  # floor of AHRS_YAW_P
SPIN_RATE_LIMIT = math.radians(20.0)  # no drift learning above this rotation rate [rad/s]
GYRO_DRIFT_RATE = math.radians(0.5 / 60.0)  # the INS's largest gyro drift [rad/s per s]
FAST_GAIN_TIME = 20.0  # s after a reset with x8 gains while disarmed
NO_GPS_INTERVAL = 0.2  # s between corrections without GPS


@tick_jit
def dcm_init(d):
    """Empty estimator: waits for a usable accel to set its tilt (:func:`dcm_update`)."""
    for j in range(N_DCM):
        d[j] = 0.0
    d[D_R] = 1.0
    d[D_R + 4] = 1.0
    d[D_R + 8] = 1.0
    d[D_ERR_RP] = 1.0
    d[D_ERR_YAW] = 1.0
    d[D_RA_START] = -1.0
    d[D_GPS_T] = -1.0


@tick_jit
def dcm_update(d, g, s, inputs, gps, imu, t_us):
    """One main-loop tick of the DCM estimator at t_us [us].

    d: its state (control.dcm_layout D_*); g: controller configuration (G_AHRS_*, G_MAG_DEC,
    G_DT); s: sensor state (filtered IMU samples, compasses); inputs: the tick's
    :class:`tlm_sim.bundles.EkfInputs`, what the EKF takes too (the IMU deltas [rad, m/s, body
    FRD] and health, whether a GPS epoch arrived, whether armed); gps: the latest GPS epoch
    (sensors.layout GE_*); imu: the primary IMU (the EKF primary lane's).
    """
    dang, gps_new, armed = inputs.dang, inputs.gps_new, inputs.armed
    t = t_us * 1e-6
    dt = g[C.G_DT]
    if gps_new:
        d[D_GPS_T] = t
    gb = _usable_imu(s, imu, S.I_GYR_OK)
    ab = _usable_imu(s, imu, S.I_ACC_OK)
    if d[D_INIT] == 0.0 and not _start(d, s, ab, t):
        return
    if s[gb + S.I_GYR_OK] != 0.0:  # integrate the primary gyro's delta angle
        gi = (gb - S.IMU_BASE) // S.IMU_STRIDE
        f = 1.0 / dt
        wx = dang[gi, 0] * f + d[D_OMEGA_I] + d[D_OMEGA_P] + d[D_OMEGA_YAW_P]
        wy = dang[gi, 1] * f + d[D_OMEGA_I + 1] + d[D_OMEGA_P + 1] + d[D_OMEGA_YAW_P + 1]
        wz = dang[gi, 2] * f + d[D_OMEGA_I + 2] + d[D_OMEGA_P + 2] + d[D_OMEGA_YAW_P + 2]
        _rotate(d, wx * dt, wy * dt, wz * dt)
    for k in range(3):
        d[D_OMEGA + k] = s[gb + S.I_GYR_F + k] + d[D_OMEGA_I + k]
    if not _normalize(d):
        _reset(d, t)
    _yaw_correction(d, g, s, ab, armed, t)
    _drift_correction(d, g, s, inputs, gps, (ab, gb), t)
    _check_matrix(d, t)


@tick_jit
def dcm_eulers(d):
    """Roll, pitch and yaw [rad] of the matrix into D_ROLL, D_PITCH, D_YAW. The firmware derives
    them every tick; tlm where they are read (the log, the compass's first heading) and at
    each drift correction, so a reset rebuilds the matrix from angles at most one correction
    (0.2 s) old."""
    d[D_PITCH] = -math.asin(min(max(d[D_R + 6], -1.0), 1.0))
    d[D_ROLL] = math.atan2(d[D_R + 7], d[D_R + 8])
    d[D_YAW] = math.atan2(d[D_R + 3], d[D_R])


@inline_jit
def _start(d, s, ab, t):
    """Initial tilt from the primary's filtered accel once its length is 9..11 m/s^2 (or after
    20 ticks: from any accel over 5 m/s^2, else level), heading 0; True when done."""
    ax, ay, az = s[ab + S.I_ACC_F], s[ab + S.I_ACC_F + 1], s[ab + S.I_ACC_F + 2]
    n = math.sqrt(ax * ax + ay * ay + az * az)
    if (n < 9.0 or n > 11.0) and d[D_INIT_TRIES] < 20.0:
        d[D_INIT_TRIES] += 1.0
        return False
    roll = pitch = 0.0
    if n > 5.0:
        pitch = math.atan2(ax, math.sqrt(ay * ay + az * az))
        roll = math.atan2(-ay, -az)
    d[D_ROLL] = roll
    d[D_PITCH] = pitch
    d[D_YAW] = 0.0
    _from_euler(d, roll, pitch, 0.0)
    d[D_T_START] = t
    d[D_INIT] = 1.0
    return True


@tick_jit
def _from_euler(d, roll, pitch, yaw):
    """The matrix of ZYX Euler angles [rad]."""
    sr, cr = math.sin(roll), math.cos(roll)
    sp, cp = math.sin(pitch), math.cos(pitch)
    sy, cy = math.sin(yaw), math.cos(yaw)
    r = D_R
    d[r], d[r + 1], d[r + 2] = cp * cy, sr * sp * cy - cr * sy, cr * sp * cy + sr * sy
    d[r + 3], d[r + 4], d[r + 5] = cp * sy, sr * sp * sy + cr * cy, cr * sp * sy - sr * cy
    d[r + 6], d[r + 7], d[r + 8] = -sp, sr * cp, cr * cp


@tick_jit
def _rotate(d, gx, gy, gz):
    """First-order rotation by the body-frame angle (gx, gy, gz) [rad]: each row r += r x g."""
    for i in range(3):
        r = D_R + 3 * i
        x, y, z = d[r], d[r + 1], d[r + 2]
        d[r] = x + y * gz - z * gy
        d[r + 1] = y + z * gx - x * gz
        d[r + 2] = z + x * gy - y * gx


@tick_jit
def _normalize(d):
    """Premerlani's renormalisation: rows a, b share their orthogonality error, c = a x b, each
    scaled to unit length. False when a row's length is absurd (the caller resets)."""
    r = D_R
    a0, a1, a2, b0, b1, b2 = d[r], d[r + 1], d[r + 2], d[r + 3], d[r + 4], d[r + 5]
    h = 0.5 * (a0 * b0 + a1 * b1 + a2 * b2)
    t0, t1, t2 = a0 - b0 * h, a1 - b1 * h, a2 - b2 * h
    u0, u1, u2 = b0 - a0 * h, b1 - a1 * h, b2 - a2 * h
    v0, v1, v2 = t1 * u2 - t2 * u1, t2 * u0 - t0 * u2, t0 * u1 - t1 * u0
    fa = _inv_length(t0 * t0 + t1 * t1 + t2 * t2)
    fb = _inv_length(u0 * u0 + u1 * u1 + u2 * u2)
    fc = _inv_length(v0 * v0 + v1 * v1 + v2 * v2)
    if fa < 0.0 or fb < 0.0 or fc < 0.0:
        return False
    d[r], d[r + 1], d[r + 2] = t0 * fa, t1 * fa, t2 * fa
    d[r + 3], d[r + 4], d[r + 5] = u0 * fb, u1 * fb, u2 * fb
    d[r + 6], d[r + 7], d[r + 8] = v0 * fc, v1 * fc, v2 * fc
    return True


@tick_jit
def _inv_length(n2):
    """1 / sqrt(n2) of a squared row length, -1 when absurd (outside 1e-6..1e6). Rows are
    renormalised every tick, so n2 is within ~1e-6 of 1: there the second-order expansion
    (3 - n2) / 2 equals the square root to ~1e-12 (below float32, what the log stores)."""
    if abs(n2 - 1.0) < 1e-4:
        return 0.5 * (3.0 - n2)
    f = 1.0 / math.sqrt(n2) if n2 > 0.0 else -1.0
    return f if 1e-6 < f < 1e6 else -1.0


@tick_jit
def _reset(d, t):
    """Corrections and drift estimate cleared; the matrix rebuilt from the last Euler angles
    (fast gains again for FAST_GAIN_TIME while disarmed)."""
    for k in range(3):
        d[D_OMEGA_I + k] = 0.0
        d[D_OMEGA_P + k] = 0.0
        d[D_OMEGA_YAW_P + k] = 0.0
        d[D_OMEGA + k] = 0.0
    roll, pitch, yaw = d[D_ROLL], d[D_PITCH], d[D_YAW]
    if not (math.isnan(roll) or math.isnan(pitch) or math.isnan(yaw)):
        _from_euler(d, roll, pitch, yaw)
    d[D_T_START] = t


@tick_jit
def _check_matrix(d, t):
    """Reset a matrix with NaNs or one whose pitch term left (-1, 1) even after renormalising."""
    nan = False
    for j in range(9):
        if math.isnan(d[D_R + j]):
            nan = True
    if nan:
        _reset(d, t)
        return
    if not (-1.0 < d[D_R + 6] < 1.0):
        ok = _normalize(d)
        if not ok or math.isnan(d[D_R + 6]) or abs(d[D_R + 6]) > 10.0:
            _reset(d, t)


@tick_jit
def _p_gain(spin):
    """Gain multiplier for fast rotation: 1 below 50 deg/s, spin / 50 deg/s up to 10."""
    if spin < math.radians(50.0):
        return 1.0
    if spin > math.radians(500.0):
        return 10.0
    return spin / math.radians(50.0)


@tick_jit
def _spin(d):
    """Rotation rate [rad/s]: length of the filtered gyro plus the drift estimate."""
    return math.sqrt(d[D_OMEGA] ** 2 + d[D_OMEGA + 1] ** 2 + d[D_OMEGA + 2] ** 2)


@tick_jit
def _fast_gains(d, armed, t):
    """x8 gains while disarmed within FAST_GAIN_TIME of the last reset."""
    return not armed and t - d[D_T_START] < FAST_GAIN_TIME


@tick_jit
def _compass(s):
    """Record base of the first healthy compass (the AHRS's primary), -1 when none."""
    for j in range(S.N_MAG):
        b = S.MAG_BASE + j * S.MAG_STRIDE
        if s[b + S.M_HEALTHY] != 0.0:
            return b
    return -1


@inline_jit
def _yaw_correction(d, g, s, ab, armed, t):
    """drift_correction_yaw: on a new sample of the primary compass, the heading error sets
    omega_yaw_P (body z) and feeds the yaw drift integrator; without one omega_yaw_P decays.
    The gain drops with the horizontal acceleration (the primary's filtered accel ab rotated to
    NED, D_ACCEL_EF)."""
    mb = _compass(s)
    new = False
    yaw_error = 0.0
    yaw_dt = 0.0
    if mb >= 0 and s[mb + S.M_T_US] != d[D_MAG_T]:
        yaw_dt = (s[mb + S.M_T_US] - d[D_MAG_T]) * 1e-6
        d[D_MAG_T] = s[mb + S.M_T_US]
        mx, my, mz = s[mb + S.M_FIELD], s[mb + S.M_FIELD + 1], s[mb + S.M_FIELD + 2]
        dec = g[C.G_MAG_DEC]
        if d[D_HAVE_YAW] == 0.0:  # the first sample sets the heading
            dcm_eulers(d)
            _from_euler(d, d[D_ROLL], d[D_PITCH], _heading(d, mx, my, mz, dec))
            for k in range(3):
                d[D_OMEGA_YAW_P + k] = 0.0
            d[D_HAVE_YAW] = 1.0
        new = True
        yaw_error = _yaw_error(d, mx, my, mz, dec)
    if not new:
        for k in range(3):
            d[D_OMEGA_YAW_P + k] *= 0.97
        return
    err_z = d[D_R + 8] * yaw_error
    spin = _spin(d)
    kp = max(g[C.G_AHRS_YAW_P], YAW_P_MIN)
    # the gain drops as the horizontal acceleration makes the heading observable otherwise
    ax, ay, az = s[ab + S.I_ACC_F], s[ab + S.I_ACC_F + 1], s[ab + S.I_ACC_F + 2]
    for k in range(3):
        d[D_ACCEL_EF + k] = d[D_R + 3 * k] * ax + d[D_R + 3 * k + 1] * ay + \
            d[D_R + 3 * k + 2] * az
    v = math.sqrt(d[D_ACCEL_EF] ** 2 + d[D_ACCEL_EF + 1] ** 2)
    yaw_gain = 0.2 * (4.5 - v) if v <= 4.0 else 0.1
    wz = err_z * _p_gain(spin) * kp * yaw_gain
    d[D_OMEGA_YAW_P + 2] = wz * 8.0 if _fast_gains(d, armed, t) else wz
    if yaw_dt < 2.0 and spin < SPIN_RATE_LIMIT:
        d[D_OMEGA_I_SUM + 2] += err_z * KI_YAW * yaw_dt
    d[D_ERR_YAW] = 0.8 * d[D_ERR_YAW] + 0.2 * abs(yaw_error)


@tick_jit
def _heading(d, mx, my, mz, dec):
    """Compass heading [rad] of the body field (mx, my, mz) with the matrix's tilt, plus the
    declination dec, in [-pi, pi]."""
    cx, cy, cz = d[D_R + 6], d[D_R + 7], d[D_R + 8]
    head_y = my * cz - mz * cy
    head_x = mx * (1.0 - cx * cx) - cx * (my * cy + mz * cz)
    h = math.atan2(-head_y, head_x) + dec
    if h > math.pi:
        h -= 2.0 * math.pi
    elif h < -math.pi:
        h += 2.0 * math.pi
    return h


@tick_jit
def _yaw_error(d, mx, my, mz, dec):
    """Sine of the heading error: the horizontal field in the matrix's earth frame (unit) cross
    the declination's direction."""
    r = D_R
    bx = d[r] * mx + d[r + 1] * my + d[r + 2] * mz
    by = d[r + 3] * mx + d[r + 4] * my + d[r + 5] * mz
    n = math.sqrt(bx * bx + by * by)
    if n < 1.2e-7:
        return 0.0
    return (bx * math.sin(dec) - by * math.cos(dec)) / n


@inline_jit
def _drift_correction(d, g, s, inputs, gps, imus, t):
    """Roll/pitch drift correction (see the module docstring): integrate the accels (the
    tick's delta velocities of inputs, :class:`tlm_sim.bundles.EkfInputs`) in NED; at a new GPS
    fix (or every 0.2 s without GPS) compare them with gravity plus the GPS velocity change and
    update omega_P, the drift integrator and error_rp."""
    ab, gb = imus  # the record bases of the IMUs whose accel and gyro it reads
    dvel, imu_ok, armed, dt = inputs.dvel, inputs.imu_ok, inputs.armed, g[C.G_DT]
    r = D_R
    for i in range(S.N_IMU):
        if imu_ok[i] != 0.0:
            vx, vy, vz = dvel[i, 0], dvel[i, 1], dvel[i, 2]
            for k in range(3):
                d[D_RA_SUM + 3 * i + k] += d[r + 3 * k] * vx + d[r + 3 * k + 1] * vy + \
                    d[r + 3 * k + 2] * vz
    d[D_RA_DT] += dt
    have_gps = g[C.G_AHRS_GPS_USE] != 0.0 and gps[S.GE_STATUS] > 1.0
    ok, t_corr, vn, ve, vd = _reference_velocity(d, g, gps, have_gps, t)
    if not ok:
        return
    if have_gps:  # any fix: the position restarts from it
        d[D_POS_N] = gps[S.GE_PN]
        d[D_POS_E] = gps[S.GE_PE]
        d[D_OFS_N] = 0.0
        d[D_OFS_E] = 0.0
        d[D_T_POS] = t
        d[D_HAVE_POS] = 1.0
    else:
        d[D_OFS_N] += vn * d[D_RA_DT]
        d[D_OFS_E] += ve * d[D_RA_DT]
    if d[D_RA_START] < 0.0:  # the first reference: only remember it
        d[D_RA_START] = t_corr
        _keep_velocity(d, vn, ve, vd)
        return
    ra_scale = 1.0 / (d[D_RA_DT] * GRAVITY_MSS)
    ex, ey, ez, best_err = _tilt_error(d, g, imu_ok, (vn, ve, vd), ra_scale, armed)
    if best_err < 0.0:
        return
    if _compass(s) >= 0:  # the compass owns yaw: the accels correct it only when banked
        roll = math.atan2(d[r + 7], d[r + 8])
        ez = ez * math.sin(abs(roll)) if have_gps and g[C.G_AHRS_GPS_GAIN] == 1.0 else 0.0
    if s[gb + S.I_GYR_OK] == 0.0 or s[ab + S.I_ACC_OK] == 0.0:
        ex = ey = ez = 0.0
    else:  # to body axes
        ex, ey, ez = (d[r] * ex + d[r + 3] * ey + d[r + 6] * ez,
                      d[r + 1] * ex + d[r + 4] * ey + d[r + 7] * ez,
                      d[r + 2] * ex + d[r + 5] * ey + d[r + 8] * ez)
    if math.isnan(ex + ey + ez) or math.isinf(ex + ey + ez):
        return
    d[D_ERR_RP] = 0.8 * d[D_ERR_RP] + 0.2 * best_err
    _apply_tilt_pi(d, g, ex, ey, ez, armed, t)
    for j in range(3 * S.N_IMU):
        d[D_RA_SUM + j] = 0.0
    d[D_RA_DT] = 0.0
    d[D_RA_START] = t_corr
    _keep_velocity(d, vn, ve, vd)
    dcm_eulers(d)


@tick_jit
def _keep_velocity(d, vn, ve, vd):
    """Remember the reference velocity NED [m/s] for the next correction."""
    d[D_LAST_VEL] = vn
    d[D_LAST_VEL + 1] = ve
    d[D_LAST_VEL + 2] = vd


@inline_jit
def _reference_velocity(d, g, gps, have_gps, t):
    """(due, time, vn, ve, vd): the velocity NED [m/s] of this correction and its time [s].
    With a usable GPS (3-D fix, AHRS_GPS_MINSATS satellites) a new fix's velocity (not due
    without one); else, every NO_GPS_INTERVAL, the body x axis times the last forward speed
    through the air (no wind estimate)."""
    r = D_R
    if not have_gps or gps[S.GE_FIX_3D] == 0.0 or gps[S.GE_NSATS] < g[C.G_AHRS_GPS_MINSATS]:
        if d[D_RA_DT] < NO_GPS_INTERVAL:
            return False, 0.0, 0.0, 0.0, 0.0
        tas = d[D_LAST_TAS]
        d[D_GPS_LOCK] = 0.0
        return True, t, d[r] * tas, d[r + 3] * tas, d[r + 6] * tas
    if d[D_GPS_T] == d[D_RA_START]:
        return False, 0.0, 0.0, 0.0, 0.0
    vn, ve, vd = gps[S.GE_VN], gps[S.GE_VE], gps[S.GE_VD]
    if d[D_GPS_LOCK] == 0.0:
        _keep_velocity(d, vn, ve, vd)
    d[D_GPS_LOCK] = 1.0
    d[D_LAST_TAS] = max(d[r] * vn + d[r + 3] * ve + d[r + 6] * vd, 0.0)
    return True, d[D_GPS_T], vn, ve, vd


@inline_jit
def _tilt_error(d, g, imu_ok, v_gps, ra_scale, armed):
    """(ex, ey, ez, error): the smallest tilt error over the healthy accels, earth frame, as
    the cross product of the accel's direction with the reference (gravity, plus the GPS
    velocity change when armed with a GPS lock, the accel then one interval late), and its
    length (1 when they point apart); error -1 when no accel could be used."""
    vn, ve, vd = v_gps  # the GPS velocity NED [m/s]
    gx, gy, gz = 0.0, 0.0, -1.0
    delayed = False
    if armed and d[D_GPS_LOCK] != 0.0:
        vs = g[C.G_AHRS_GPS_GAIN] * ra_scale
        gx += (vn - d[D_LAST_VEL]) * vs
        gy += (ve - d[D_LAST_VEL + 1]) * vs
        gz += (vd - d[D_LAST_VEL + 2]) * vs
        n = math.sqrt(gx * gx + gy * gy + gz * gz)
        if n == 0.0 or math.isinf(n):
            return 0.0, 0.0, 0.0, -1.0
        gx, gy, gz = gx / n, gy / n, gz / n
        delayed = True
    best = -1
    best_err = 0.0
    best_dirn = 1.0
    bx = by = bz = 0.0
    for i in range(S.N_IMU):
        if imu_ok[i] == 0.0:
            continue
        o = D_RA_SUM + 3 * i
        ax, ay, az = d[o] * ra_scale, d[o + 1] * ra_scale, d[o + 2] * ra_scale
        d[o], d[o + 1], d[o + 2] = ax, ay, az
        if delayed:  # swap with the previous interval's sum (unless that one is empty)
            q = D_RA_DELAY + 3 * i
            px, py, pz = d[q], d[q + 1], d[q + 2]
            d[q], d[q + 1], d[q + 2] = ax, ay, az
            if px != 0.0 or py != 0.0 or pz != 0.0:
                ax, ay, az = px, py, pz
        n = math.sqrt(ax * ax + ay * ay + az * az)
        if n == 0.0 or math.isinf(n):
            continue
        ax, ay, az = ax / n, ay / n, az / n
        cx, cy, cz = ay * gz - az * gy, az * gx - ax * gz, ax * gy - ay * gx
        length = math.sqrt(cx * cx + cy * cy + cz * cz)
        if best < 0 or length < best_err:
            best = i
            best_err = length
            best_dirn = ax * gx + ay * gy + az * gz
            bx, by, bz = cx, cy, cz
        if best_dirn < 0.0:  # upside down relative to the reference
            best_err = 1.0
    if best < 0:
        return 0.0, 0.0, 0.0, -1.0
    return bx, by, bz, best_err


@inline_jit
def _apply_tilt_pi(d, g, ex, ey, ez, armed, t):
    """omega_P from the body-frame tilt error, the drift integrator (applied to omega_I every
    5 s of collected time, limited to GYRO_DRIFT_RATE)."""
    spin = _spin(d)
    f = _p_gain(spin) * max(g[C.G_AHRS_RP_P], RP_P_MIN)
    if _fast_gains(d, armed, t):
        f *= 8.0
    d[D_OMEGA_P] = ex * f
    d[D_OMEGA_P + 1] = ey * f
    d[D_OMEGA_P + 2] = ez * f
    ra_dt = d[D_RA_DT]
    if spin < SPIN_RATE_LIMIT:
        d[D_OMEGA_I_SUM] += ex * KI * ra_dt
        d[D_OMEGA_I_SUM + 1] += ey * KI * ra_dt
        d[D_OMEGA_I_SUM + 2] += ez * KI * ra_dt
        d[D_OMEGA_I_SUM_T] += ra_dt
    if d[D_OMEGA_I_SUM_T] >= 5.0:
        lim = GYRO_DRIFT_RATE * d[D_OMEGA_I_SUM_T]
        for k in range(3):
            d[D_OMEGA_I + k] += min(max(d[D_OMEGA_I_SUM + k], -lim), lim)
            d[D_OMEGA_I_SUM + k] = 0.0
        d[D_OMEGA_I_SUM_T] = 0.0


@tick_jit
def dcm_location(d, g, s, gps, t, home_alt):
    """(have, north, east, alt): the DCM's position estimate at t [s] -- NE from home [m] of
    the last GPS fix plus the dead-reckoned offset, moved on by the last velocity for the GPS
    lag plus the time since that fix (at most 0.5 s); have: a GPS fix was ever seen (else NE
    is 0, 0) -- and its altitude AMSL [m]: baro above home, or GPS with AHRS_GPS_USE 2."""
    if g[C.G_AHRS_GPS_USE] == 2.0 and gps[S.GE_FIX_3D] != 0.0:
        alt = home_alt - gps[S.GE_PD]
    else:
        alt = s[S.B_ALT] + home_alt
    if d[D_HAVE_POS] == 0.0:
        return False, 0.0, 0.0, alt
    lead = g[C.G_GPS_LAG] + min(max(t - d[D_T_POS], 0.0), 0.5)
    north = d[D_POS_N] + d[D_OFS_N] + d[D_LAST_VEL] * lead
    east = d[D_POS_E] + d[D_OFS_E] + d[D_LAST_VEL + 1] * lead
    return True, north, east, alt


@tick_jit
def dcm_quaternion(d):
    """(qw, qx, qy, qz) of the matrix (body -> NED, scalar first), branch on the largest
    diagonal term for precision."""
    r = D_R
    m00, m01, m02 = d[r], d[r + 1], d[r + 2]
    m10, m11, m12 = d[r + 3], d[r + 4], d[r + 5]
    m20, m21, m22 = d[r + 6], d[r + 7], d[r + 8]
    tr = m00 + m11 + m22
    if tr > 0.0:
        k = 2.0 * math.sqrt(tr + 1.0)
        return 0.25 * k, (m21 - m12) / k, (m02 - m20) / k, (m10 - m01) / k
    if m00 > m11 and m00 > m22:
        k = 2.0 * math.sqrt(1.0 + m00 - m11 - m22)
        return (m21 - m12) / k, 0.25 * k, (m01 + m10) / k, (m02 + m20) / k
    if m11 > m22:
        k = 2.0 * math.sqrt(1.0 + m11 - m00 - m22)
        return (m02 - m20) / k, (m01 + m10) / k, 0.25 * k, (m12 + m21) / k
    k = 2.0 * math.sqrt(1.0 + m22 - m00 - m11)
    return (m10 - m01) / k, (m02 + m20) / k, (m12 + m21) / k, 0.25 * k
