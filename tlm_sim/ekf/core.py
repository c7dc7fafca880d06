"""Numerical kernels of the error-state EKF (one lane row ``e = ekf[lane]`` at a time).

All kernels are allocation-free ``@njit`` functions that read and write the lane row only
(scratch space included). Conventions in :mod:`tlm_sim.ekf.layout`.

Why no numba runtime: every numba function that receives arrays increments and decrements
their reference counts with atomic instructions on entry and exit (also when inlined), and with
~10 small kernels per tick per lane that is a large share of the EKF's time. The kernels never
allocate, so the fast build (:mod:`tlm_sim._jit_fast`) compiles them without the runtime
(``_nrt=False``): no reference counting, and an accidental allocation fails to compile
(``benchmarks/RESULTS.md`` has the measured gain).

Model (error state dx = [phi, dv, dp, dbg, dba], earth-frame attitude error phi):

* phi' = -R dbg,  dv' = -[f_n x] phi - R dba,  dp' = dv,  biases: random walks.
* Discrete F = I + G over the accumulated interval T, with the accumulated specific-force
  velocity increment dV_n (NED): F_phi,bg = -R T, F_v,phi = -[dV_n x], F_v,ba = -R T,
  F_p,v = I T. Process noise as EKF3 parameterises it: (sigma * T)^2 per prediction.

The covariance prediction exploits that only the attitude, velocity and position rows/columns of
F differ from the identity (about 650 multiply-adds instead of 2 x 15^3 for dense products).

Output observer: the nominal velocity/position slots and the ring buffer are EKF3's *output*
states; the filter state is the output plus the tracking error OUT_E* (:func:`filter_get`,
:func:`filter_now`). Measurement corrections change the filter state (:func:`apply_correction`),
:func:`output_track` pulls the output after it every tick, resets move both (:func:`shift_output`).
Measurement updates are scalar and sequential: K = P h / (h P h + r), P -= K (P h)^T, which equals
the Joseph form for the optimal gain.
"""

from __future__ import annotations

import math

from tlm_sim._jit import inline_jit, tick_jit
from tlm_sim.ardupilot import GRAVITY_MSS
from tlm_sim.ekf.layout import (
    ACC_DT,
    ACC_DVD,
    ACC_DVE,
    ACC_DVN,
    BAD_IMU,
    BAX,
    BAY,
    BAZ,
    BGX,
    BGY,
    BGZ,
    BUF0,
    BUF_COUNT,
    BUF_HEAD,
    BUF_OFS,
    BUF_ROW,
    ES_ATT,
    ES_BA,
    ES_BG,
    ES_POS,
    ES_VEL,
    NBUF,
    NS,
    OUT_EPN,
    OUT_EVN,
    OUT_IPN,
    OUT_IVN,
    P0,
    PD,
    PE,
    PN,
    QW,
    QX,
    QY,
    QZ,
    R00,
    R01,
    R02,
    R10,
    R11,
    R12,
    R20,
    R21,
    R22,
    SCR_A,
    SCR_C,
    SCR_DX,
    VD,
    VE,
    VN,
)

# upper bounds on variances after prediction (keep P bounded without aiding)
VAR_MAX_ATT = 1.0  # rad^2
VAR_MAX_VEL = 1.0e4  # (m/s)^2
VAR_MAX_POS = 1.0e6  # m^2
VAR_MIN = 1.0e-12


@tick_jit
def quat_to_rot(e):
    """Refresh the cached rotation matrix (body -> NED) from the lane's quaternion."""
    w = e[QW]
    x = e[QX]
    y = e[QY]
    z = e[QZ]
    xx = x * x
    yy = y * y
    zz = z * z
    xy = x * y
    xz = x * z
    yz = y * z
    wx = w * x
    wy = w * y
    wz = w * z
    e[R00] = 1.0 - 2.0 * (yy + zz)
    e[R01] = 2.0 * (xy - wz)
    e[R02] = 2.0 * (xz + wy)
    e[R10] = 2.0 * (xy + wz)
    e[R11] = 1.0 - 2.0 * (xx + zz)
    e[R12] = 2.0 * (yz - wx)
    e[R20] = 2.0 * (xz - wy)
    e[R21] = 2.0 * (yz + wx)
    e[R22] = 1.0 - 2.0 * (xx + yy)


@tick_jit
def set_quat_euler(e, roll, pitch, yaw):
    """Set the lane quaternion from ZYX Euler angles [rad] and refresh the rotation matrix."""
    cr = math.cos(0.5 * roll)
    sr = math.sin(0.5 * roll)
    cp = math.cos(0.5 * pitch)
    sp = math.sin(0.5 * pitch)
    cy = math.cos(0.5 * yaw)
    sy = math.sin(0.5 * yaw)
    e[QW] = cr * cp * cy + sr * sp * sy
    e[QX] = sr * cp * cy - cr * sp * sy
    e[QY] = cr * sp * cy + sr * cp * sy
    e[QZ] = cr * cp * sy - sr * sp * cy
    quat_to_rot(e)


@tick_jit
def propagate(e, dang, dvel, gi, ai, dt):
    """Integrate one IMU interval into the nominal state and the covariance accumulators.

    dang[gi, 0:3]: delta angle [rad, body FRD] of gyro gi; dvel[ai, 0:3]: delta velocity
    (integral of the specific force) [m/s, body FRD] of accel ai (the lane's own IMU, or the
    first healthy one while its own is stopped); dt: interval [s]. Biases are removed, the
    delta velocity is rotated to mid-interval (first-order rotation compensation), velocity and
    position are integrated (trapezoid) and the quaternion is advanced by the corrected delta
    angle.
    """
    ax = dang[gi, 0] - e[BGX] * dt
    ay = dang[gi, 1] - e[BGY] * dt
    az = dang[gi, 2] - e[BGZ] * dt
    ux = dvel[ai, 0] - e[BAX] * dt
    uy = dvel[ai, 1] - e[BAY] * dt
    uz = dvel[ai, 2] - e[BAZ] * dt
    # rotate the delta velocity to the middle of the interval
    bx = ux + 0.5 * (ay * uz - az * uy)
    by = uy + 0.5 * (az * ux - ax * uz)
    bz = uz + 0.5 * (ax * uy - ay * ux)
    dn = e[R00] * bx + e[R01] * by + e[R02] * bz
    de = e[R10] * bx + e[R11] * by + e[R12] * bz
    dd = e[R20] * bx + e[R21] * by + e[R22] * bz
    e[ACC_DVN] += dn
    e[ACC_DVE] += de
    e[ACC_DVD] += dd
    e[ACC_DT] += dt
    vn0 = e[VN]
    ve0 = e[VE]
    vd0 = e[VD]
    vn1 = vn0 + dn
    ve1 = ve0 + de
    vd1 = vd0 + dd + GRAVITY_MSS * dt
    e[VN] = vn1
    e[VE] = ve1
    e[VD] = vd1
    h = 0.5 * dt
    e[PN] += (vn0 + vn1) * h
    e[PE] += (ve0 + ve1) * h
    e[PD] += (vd0 + vd1) * h
    # quaternion q <- q * dq(a), dq = [1 - |a|^2 / 8, a / 2] (second order), then normalise
    w = e[QW]
    x = e[QX]
    y = e[QY]
    z = e[QZ]
    hx = 0.5 * ax
    hy = 0.5 * ay
    hz = 0.5 * az
    hw = 1.0 - 0.5 * (hx * hx + hy * hy + hz * hz)
    nw = w * hw - x * hx - y * hy - z * hz
    nx = w * hx + x * hw + y * hz - z * hy
    ny = w * hy - x * hz + y * hw + z * hx
    nz = w * hz + x * hy - y * hx + z * hw
    inv = 1.0 / math.sqrt(nw * nw + nx * nx + ny * ny + nz * nz)
    e[QW] = nw * inv
    e[QX] = nx * inv
    e[QY] = ny * inv
    e[QZ] = nz * inv
    quat_to_rot(e)


@tick_jit
def buffer_push(e):
    """Store the current position/velocity (minus the cumulative correction) in the ring buffer."""
    head = int(e[BUF_HEAD]) + 1
    if head >= NBUF:
        head = 0
    e[BUF_HEAD] = head
    if e[BUF_COUNT] < NBUF:
        e[BUF_COUNT] += 1.0
    b = BUF0 + head * BUF_ROW
    e[b] = e[PN] - e[BUF_OFS]
    e[b + 1] = e[PE] - e[BUF_OFS + 1]
    e[b + 2] = e[PD] - e[BUF_OFS + 2]
    e[b + 3] = e[VN] - e[BUF_OFS + 3]
    e[b + 4] = e[VE] - e[BUF_OFS + 4]
    e[b + 5] = e[VD] - e[BUF_OFS + 5]


@tick_jit
def buffer_get(e, k, col):
    """Past value ``col`` (0..5: pn, pe, pd, vn, ve, vd) from ``k`` ticks ago, corrections applied.

    ``k`` is clamped to the rows stored; with an empty buffer the current state is returned.
    """
    count = int(e[BUF_COUNT])
    if count == 0:
        if col < 3:
            return e[PN + col]
        return e[VN + col - 3]
    if k > count - 1:
        k = count - 1
    if k < 0:
        k = 0
    idx = int(e[BUF_HEAD]) - k
    if idx < 0:
        idx += NBUF
    return e[BUF0 + idx * BUF_ROW + col] + e[BUF_OFS + col]


@tick_jit
def predict_covariance(e, q_att, q_vel, q_gb, q_ab):
    """P <- F P F^T + Q over the accumulated interval, then clear the accumulators.

    q_att, q_vel, q_gb, q_ab: process-noise variances added to the diagonal for the attitude,
    velocity, gyro-bias and accel-bias states. Uses the cached rotation matrix and the
    accumulated NED delta velocity ACC_DV* and interval ACC_DT.
    """
    t = e[ACC_DT]
    r00 = e[R00] * t
    r01 = e[R01] * t
    r02 = e[R02] * t
    r10 = e[R10] * t
    r11 = e[R11] * t
    r12 = e[R12] * t
    r20 = e[R20] * t
    r21 = e[R21] * t
    r22 = e[R22] * t
    sx = e[ACC_DVN]
    sy = e[ACC_DVE]
    sz = e[ACC_DVD]
    # ---- A = F P for the rows phi, v, p (ES_ATT, ES_VEL, ES_POS: the states before the biases
    # ES_BG, ES_BA); the other rows of F are identity ----
    for c in range(NS):
        f0 = e[P0 + ES_ATT * NS + c]
        f1 = e[P0 + (ES_ATT + 1) * NS + c]
        f2 = e[P0 + (ES_ATT + 2) * NS + c]
        g0 = e[P0 + ES_BG * NS + c]
        g1 = e[P0 + (ES_BG + 1) * NS + c]
        g2 = e[P0 + (ES_BG + 2) * NS + c]
        b0 = e[P0 + ES_BA * NS + c]
        b1 = e[P0 + (ES_BA + 1) * NS + c]
        b2 = e[P0 + (ES_BA + 2) * NS + c]
        v0 = e[P0 + ES_VEL * NS + c]
        v1 = e[P0 + (ES_VEL + 1) * NS + c]
        v2 = e[P0 + (ES_VEL + 2) * NS + c]
        e[SCR_A + ES_ATT * NS + c] = f0 - (r00 * g0 + r01 * g1 + r02 * g2)
        e[SCR_A + (ES_ATT + 1) * NS + c] = f1 - (r10 * g0 + r11 * g1 + r12 * g2)
        e[SCR_A + (ES_ATT + 2) * NS + c] = f2 - (r20 * g0 + r21 * g1 + r22 * g2)
        # -[s x] f = (sz f1 - sy f2, sx f2 - sz f0, sy f0 - sx f1)
        e[SCR_A + ES_VEL * NS + c] = v0 + (sz * f1 - sy * f2) - (r00 * b0 + r01 * b1 + r02 * b2)
        e[SCR_A + (ES_VEL + 1) * NS + c] = (v1 + (sx * f2 - sz * f0)
                                            - (r10 * b0 + r11 * b1 + r12 * b2))
        e[SCR_A + (ES_VEL + 2) * NS + c] = (v2 + (sy * f0 - sx * f1)
                                            - (r20 * b0 + r21 * b1 + r22 * b2))
        e[SCR_A + ES_POS * NS + c] = e[P0 + ES_POS * NS + c] + t * v0
        e[SCR_A + (ES_POS + 1) * NS + c] = e[P0 + (ES_POS + 1) * NS + c] + t * v1
        e[SCR_A + (ES_POS + 2) * NS + c] = e[P0 + (ES_POS + 2) * NS + c] + t * v2
    # ---- P' = A F^T: apply the same column operations to each row of A (upper triangle) ----
    for r in range(ES_BG):
        a = SCR_A + r * NS
        f0 = e[a + ES_ATT]
        f1 = e[a + ES_ATT + 1]
        f2 = e[a + ES_ATT + 2]
        v0 = e[a + ES_VEL]
        v1 = e[a + ES_VEL + 1]
        v2 = e[a + ES_VEL + 2]
        g0 = e[a + ES_BG]
        g1 = e[a + ES_BG + 1]
        g2 = e[a + ES_BG + 2]
        b0 = e[a + ES_BA]
        b1 = e[a + ES_BA + 1]
        b2 = e[a + ES_BA + 2]
        row = P0 + r * NS
        # columns below ES_BG (only c >= r are written; mirrored below)
        if r <= ES_ATT:
            e[row + ES_ATT] = f0 - (r00 * g0 + r01 * g1 + r02 * g2)
        if r <= ES_ATT + 1:
            e[row + ES_ATT + 1] = f1 - (r10 * g0 + r11 * g1 + r12 * g2)
        if r <= ES_ATT + 2:
            e[row + ES_ATT + 2] = f2 - (r20 * g0 + r21 * g1 + r22 * g2)
        if r <= ES_VEL:
            e[row + ES_VEL] = v0 + (sz * f1 - sy * f2) - (r00 * b0 + r01 * b1 + r02 * b2)
        if r <= ES_VEL + 1:
            e[row + ES_VEL + 1] = v1 + (sx * f2 - sz * f0) - (r10 * b0 + r11 * b1 + r12 * b2)
        if r <= ES_VEL + 2:
            e[row + ES_VEL + 2] = v2 + (sy * f0 - sx * f1) - (r20 * b0 + r21 * b1 + r22 * b2)
        if r <= ES_POS:
            e[row + ES_POS] = e[a + ES_POS] + t * v0
        if r <= ES_POS + 1:
            e[row + ES_POS + 1] = e[a + ES_POS + 1] + t * v1
        e[row + ES_POS + 2] = e[a + ES_POS + 2] + t * v2
        # bias columns are unchanged by F^T: P'[r, ES_BG:] = A[r, ES_BG:]
        for c in range(ES_BG, NS):
            e[row + c] = e[a + c]
    _mirror_and_add_noise(e, q_att, q_vel, q_gb, q_ab)


@inline_jit
def _mirror_and_add_noise(e, q_att, q_vel, q_gb, q_ab):
    """End of the covariance prediction: mirror the upper triangle of P's 9 x 15 block into
    the lower one, add the process noise (variances, see :func:`predict_covariance`) within
    the variance limits, clear the accumulators."""
    for r in range(ES_BG):
        for c in range(r + 1, NS):
            e[P0 + c * NS + r] = e[P0 + r * NS + c]
    for i in range(3):
        d = P0 + (ES_ATT + i) * (NS + 1)
        e[d] = min(max(e[d] + q_att, VAR_MIN), VAR_MAX_ATT)
        d = P0 + (ES_VEL + i) * (NS + 1)
        e[d] = min(max(e[d] + q_vel, VAR_MIN), VAR_MAX_VEL)
        d = P0 + (ES_POS + i) * (NS + 1)
        e[d] = min(max(e[d], VAR_MIN), VAR_MAX_POS)
        d = P0 + (ES_BG + i) * (NS + 1)
        e[d] = max(e[d] + q_gb, VAR_MIN)
        d = P0 + (ES_BA + i) * (NS + 1)
        e[d] = max(e[d] + q_ab, VAR_MIN)
    e[ACC_DVN] = 0.0
    e[ACC_DVE] = 0.0
    e[ACC_DVD] = 0.0
    e[ACC_DT] = 0.0


@tick_jit
def clear_dx(e):
    """Zero the error-state correction accumulated by a measurement batch."""
    for i in range(NS):
        e[SCR_DX + i] = 0.0


@tick_jit
def _update_bias_inhibited(e, inv, y):
    """The update of :func:`_update_with_column` with the accel-bias gains K[ES_BA:] = 0."""
    for a in range(ES_BA):
        e[SCR_DX + a] += e[SCR_C + a] * inv * y
    for a in range(NS):
        ka = e[SCR_C + a] * inv if a < ES_BA else 0.0
        ra = P0 + a * NS
        for b in range(a, NS):
            kb = e[SCR_C + b] * inv if b < ES_BA else 0.0
            v = e[ra + b] - 0.5 * (ka * e[SCR_C + b] + kb * e[SCR_C + a])
            e[ra + b] = v
            e[P0 + b * NS + a] = v


@tick_jit
def _update_with_column(e, s, y):
    """P -= c c^T / s and dx += c y / s, with c = P h^T in SCR_C (upper triangle, mirrored).

    While the lane's bad-IMU response is active (``BAD_IMU``) the accel-bias gains are zero, as
    EKF3 zeroes the delta-velocity-bias Kalman gains of every fusion while ``badIMUdata``: the
    measurement does not move the bias, and P -= K (P h)^T with those gain rows zero, made
    symmetric (EKF3's ForceSymmetry averages P[i][j] and P[j][i]), halves the usual reduction of
    the bias cross-covariances and leaves the bias block as it is.
    """
    inv = 1.0 / s
    if e[BAD_IMU] != 0.0:
        _update_bias_inhibited(e, inv, y)
    else:
        for a in range(NS):
            ka = e[SCR_C + a] * inv
            e[SCR_DX + a] += ka * y
            ra = P0 + a * NS
            for b in range(a, NS):
                v = e[ra + b] - ka * e[SCR_C + b]
                e[ra + b] = v
                e[P0 + b * NS + a] = v
    # guard the diagonal against round-off
    for a in range(NS):
        d = P0 + a * (NS + 1)
        if e[d] < VAR_MIN:
            e[d] = VAR_MIN


@tick_jit
def fuse_index(e, j, innov, r):
    """Scalar update for a measurement of error state ``j`` (h = unit vector).

    innov: measurement minus the prediction from the nominal state (the part already corrected
    earlier in the same batch, dx[j], is subtracted here); r: measurement variance.
    Returns the innovation variance s = P[j, j] + r (0 if not fused).
    """
    for a in range(NS):
        e[SCR_C + a] = e[P0 + a * NS + j]
    s = e[SCR_C + j] + r
    if not s > 0.0:
        return 0.0
    y = innov - e[SCR_DX + j]
    _update_with_column(e, s, y)
    return s


@tick_jit
def innov_var_h3(e, j0, h0, h1, h2, r):
    """Innovation variance h P h^T + r for h nonzero only at j0..j0+2."""
    s = r
    for a in range(3):
        ha = h0 if a == 0 else (h1 if a == 1 else h2)
        ra = P0 + (j0 + a) * NS + j0
        s += ha * (e[ra] * h0 + e[ra + 1] * h1 + e[ra + 2] * h2)
    return s


@tick_jit
def fuse_h3(e, j0, h0, h1, h2, innov, r):
    """Scalar update with h nonzero only at states j0..j0+2 (e.g. a magnetometer axis).

    Returns the innovation variance used (0 if not fused).
    """
    for a in range(NS):
        ra = P0 + a * NS + j0
        e[SCR_C + a] = e[ra] * h0 + e[ra + 1] * h1 + e[ra + 2] * h2
    s = h0 * e[SCR_C + j0] + h1 * e[SCR_C + j0 + 1] + h2 * e[SCR_C + j0 + 2] + r
    if not s > 0.0:
        return 0.0
    y = innov - (h0 * e[SCR_DX + j0] + h1 * e[SCR_DX + j0 + 1] + h2 * e[SCR_DX + j0 + 2])
    _update_with_column(e, s, y)
    return s


@tick_jit
def apply_correction(e, gb_lim, ab_lim):
    """Inject the batch correction dx into the filter state, then zero dx.

    Attitude: q <- dq(phi) * q (earth-frame error), applied at once. Velocity and position:
    the correction goes to the filter state only (the tracking error OUT_E*); the output the
    controllers read follows through :func:`output_track`, as EKF3's output observer does.
    Biases are limited to +-gb_lim [rad/s] and +-ab_lim [m/s^2].
    """
    px = 0.5 * e[SCR_DX + ES_ATT]
    py = 0.5 * e[SCR_DX + ES_ATT + 1]
    pz = 0.5 * e[SCR_DX + ES_ATT + 2]
    w = e[QW]
    x = e[QX]
    y = e[QY]
    z = e[QZ]
    nw = w - px * x - py * y - pz * z
    nx = x + px * w + py * z - pz * y
    ny = y - px * z + py * w + pz * x
    nz = z + px * y - py * x + pz * w
    inv = 1.0 / math.sqrt(nw * nw + nx * nx + ny * ny + nz * nz)
    e[QW] = nw * inv
    e[QX] = nx * inv
    e[QY] = ny * inv
    e[QZ] = nz * inv
    quat_to_rot(e)
    for i in range(3):
        e[OUT_EVN + i] += e[SCR_DX + ES_VEL + i]
        e[OUT_EPN + i] += e[SCR_DX + ES_POS + i]
        e[BGX + i] = min(max(e[BGX + i] + e[SCR_DX + ES_BG + i], -gb_lim), gb_lim)
        e[BAX + i] = min(max(e[BAX + i] + e[SCR_DX + ES_BA + i], -ab_lim), ab_lim)
    clear_dx(e)


@tick_jit
def filter_get(e, k, col):
    """Filter-state value ``col`` (0..5: pn, pe, pd, vn, ve, vd) ``k`` ticks ago.

    The stored output history plus the current tracking error: EKF3 applies its output
    corrections to the whole output history, so the filter state at the fusion time horizon is
    the output there plus the present error.
    """
    return buffer_get(e, k, col) + e[OUT_EPN + col]


@tick_jit
def filter_now(e, col):
    """Current filter-state value ``col`` (0..5: pn, pe, pd, vn, ve, vd)."""
    if col < 3:
        return e[PN + col] + e[OUT_EPN + col]
    return e[VN + col - 3] + e[OUT_EPN + col]


@tick_jit
def shift_output(e, col, delta):
    """Move output ``col`` (0..5: pn, pe, pd, vn, ve, vd) and its whole stored history by delta.

    A reset that moves the filter state by ``delta`` calls this too, so the tracking error is
    unchanged (EKF3 shifts the output history by a reset's jump).
    """
    if col < 3:
        e[PN + col] += delta
    else:
        e[VN + col - 3] += delta
    e[BUF_OFS + col] += delta


@tick_jit
def output_track(e, dt, tau, k, bad_imu):
    """One step of the output observer: the output velocity/position move towards the filter's.

    EKF3's proportional-integral tracking loop, in continuous form: correction rate
    ``err / tau + 0.1 * integral(err) / tau^2`` per axis (EKF3 applies ``g err + 0.1 g^2 sum(err)``
    with ``g = dt_ekf / tau`` at every filter update, which is the same loop); dt: step [s];
    tau: EK3_TAU_OUTPUT [s]. The integral term removes the steady offset a continuing
    disagreement would leave. While the bad-IMU response is active (bad_imu) EKF3 integrates,
    for the vertical velocity, the filter's value at the fusion time horizon (``k`` ticks ago)
    minus the *current* output, with 0.07 instead of 0.1: the output vertical velocity is
    driven to the filter's delayed one. The filter position integrates the filter velocity, so
    the position error first grows by the velocity error times dt. Each correction shifts the
    stored output history too.
    """
    kp = dt / tau
    ki = 0.1 * dt / (tau * tau)
    for i in range(3):
        ev = e[OUT_EVN + i]
        ep = e[OUT_EPN + i] + ev * dt
        e[OUT_IPN + i] += ep * dt
        if i == 2 and bad_imu:
            e[OUT_IVN + i] += (buffer_get(e, k, 5) + ev - e[VD]) * dt
            cv = kp * ev + 0.7 * ki * e[OUT_IVN + i]
        else:
            e[OUT_IVN + i] += ev * dt
            cv = kp * ev + ki * e[OUT_IVN + i]
        cp = kp * ep + ki * e[OUT_IPN + i]
        e[VN + i] += cv
        e[BUF_OFS + 3 + i] += cv
        e[OUT_EVN + i] = ev - cv
        e[PN + i] += cp
        e[BUF_OFS + i] += cp
        e[OUT_EPN + i] = ep - cp


@tick_jit
def reset_block(e, j0, n, var):
    """Decorrelate states j0..j0+n-1 from all others and set their variances to ``var``."""
    for j in range(j0, j0 + n):
        for a in range(NS):
            e[P0 + j * NS + a] = 0.0
            e[P0 + a * NS + j] = 0.0
        e[P0 + j * (NS + 1)] = var
