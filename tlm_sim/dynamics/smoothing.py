"""What the sensors see of the truth: SITL's sensor smoothing (ardupilot-reference.md §1.9.1).

SITL's ground contact (NO_MOVEMENT) changes the truth instantly: the descent stops, roll and
pitch are zeroed, the rates and the horizontal velocity are set to zero. The rigid body's own
acceleration never shows that (§1.9 step 4 only clamps a downward acceleration while already on
the ground), so SITL switches on a "sensor smoothing" at its first ground contact: from then on
the IMU, GPS and barometer read a kinematic shadow of the truth that follows it with a 0.1 s
time constant. A SITL multicopter starts on the ground, so the shadow is in use for the whole
flight (ArduPilot ``libraries/SITL/SIM_Aircraft.cpp``, ``Aircraft::smooth_sensors``, used by
``fill_fdm`` once ``use_smoothing`` is set in the ground branch of ``update_dynamics``).

Per physics tick, after the truth update (tc = SMOOTH_TC_S, g down = (0, 0, g)):

* acceleration that brings the shadow onto the truth's position and velocity within tc:
  ``a = a_true + ((v - v_s) + (p - p_s)/tc)/tc``, each NED axis limited to +-14 g;
* accelerometer (body frame of the shadow's attitude before this tick's update):
  ``f_s = R_s^T (a - g)``;
* gyro: the true body rate plus the rotation vector from the shadow's attitude to the truth's
  over tc, ``w_s = w + theta(q_s^-1 q)/tc``;
* integrate: ``q_s <- q_s exp(w_s dt)``, ``v_s <- v_s + a dt``, ``p_s <- p_s + v_s dt``;
* if the shadow is more than 10 m from the truth it is reset onto it.

In flight the shadow equals the truth to within dt * tc * (rate of change of the acceleration),
far below the sensor noise; so, to save the work, the shadow is simply the truth (copied) until
a ground contact changes the truth abruptly, and from then on follows it by the law above until
it has converged again (position and velocity within 1 um and 1 um/s, attitude within 1 urad)
and has left the ground. At an impact at v [m/s] the accelerometer sees about v/tc of
deceleration (limited at 14 g), decaying as a damped oscillation (natural frequency 1/tc =
10 rad/s, damping ratio 0.5), and the gyro sees the levelling of the attitude spread over
~0.1 s. The engine-fault log engine_s14.bin shows exactly this: 0.04 s after "SIM Hit ground at
12.7 m/s" IMU0 reads (79, -71, -96) m/s^2, back through -1 within 0.25 s, then an overshoot to
+10.7 m/s^2 on z and a second swing to -13 before settling at -9.8.
"""

from __future__ import annotations

import math

import numpy as np

from tlm_sim._jit import tick_jit
from tlm_sim.dynamics import layout as X
from tlm_sim.dynamics.atmosphere import GRAVITY_MSS
from tlm_sim.dynamics.kinematics import step_translation
from tlm_sim.rotation import quat_mul_normalised, quat_to_dcm, rotation_half_angle

#: time constant of the shadow [s] (SITL's smoothing time constant, 0.1 s)
SMOOTH_TC_S: float = 0.1
#: limit of the shadow's acceleration per NED axis [m/s^2] (SITL: 14 g)
SMOOTH_ACCEL_LIMIT: float = 14.0 * GRAVITY_MSS
#: distance from the truth beyond which the shadow is reset onto it [m] (SITL: 10 m)
SMOOTH_RESET_M: float = 10.0
#: the shadow counts as converged onto the truth within these squared distances:
#: position [m^2] plus velocity [m^2/s^2], and attitude quaternion vector part
SMOOTH_DONE_PV2: float = 1e-12
SMOOTH_DONE_Q2: float = 1e-13


@tick_jit
def smoothing_reset(x: np.ndarray) -> None:
    """Put the shadow onto the truth: position, velocity, attitude, specific force, rates."""
    x[X.SMOOTH_ACTIVE] = 0.0
    for k in range(3):
        x[X.SPN + k] = x[X.PN + k]
        x[X.SVN + k] = x[X.VN + k]
        x[X.SFX + k] = x[X.FX + k]
        x[X.SWX + k] = x[X.WX + k]
    for k in range(4):
        x[X.SQW + k] = x[X.QW + k]


@tick_jit
def _lim(v: float) -> float:
    if v > SMOOTH_ACCEL_LIMIT:
        return SMOOTH_ACCEL_LIMIT
    if v < -SMOOTH_ACCEL_LIMIT:
        return -SMOOTH_ACCEL_LIMIT
    return v


@tick_jit
def smooth_sensors(x: np.ndarray, dt: float) -> None:
    """Advance the shadow by one physics tick of ``dt`` [s] after the truth update (in place).

    Without a recent ground contact (``SMOOTH_ACTIVE`` 0 and not ``ON_GROUND``) the shadow is
    the truth."""
    if x[X.SMOOTH_ACTIVE] == 0.0:
        if x[X.ON_GROUND] == 0.0:
            smoothing_reset(x)
            return
        x[X.SMOOTH_ACTIVE] = 1.0
    dpn = x[X.PN] - x[X.SPN]
    dpe = x[X.PE] - x[X.SPE]
    dpd = x[X.PD] - x[X.SPD]
    if dpn * dpn + dpe * dpe + dpd * dpd > SMOOTH_RESET_M * SMOOTH_RESET_M:
        smoothing_reset(x)
        return
    inv = 1.0 / SMOOTH_TC_S
    an = _lim(((x[X.VN] - x[X.SVN]) + dpn * inv) * inv + x[X.AN])
    ae = _lim(((x[X.VE] - x[X.SVE]) + dpe * inv) * inv + x[X.AE])
    ad = _lim(((x[X.VD] - x[X.SVD]) + dpd * inv) * inv + x[X.AD])

    sw, sx, sy, sz = x[X.SQW], x[X.SQX], x[X.SQY], x[X.SQZ]
    # accelerometer: R_s^T (a - g), R_s = DCM body -> NED of the shadow's attitude
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = quat_to_dcm(sw, sx, sy, sz)
    fd = ad - GRAVITY_MSS
    x[X.SFX] = r00 * an + r10 * ae + r20 * fd
    x[X.SFY] = r01 * an + r11 * ae + r21 * fd
    x[X.SFZ] = r02 * an + r12 * ae + r22 * fd

    # gyro: attitude error q_e = q_s^-1 q (shadow body frame) as a rotation vector over tc
    qw, qx, qy, qz = x[X.QW], x[X.QX], x[X.QY], x[X.QZ]
    ew = sw * qw + sx * qx + sy * qy + sz * qz
    ex = sw * qx - sx * qw - sy * qz + sz * qy
    ey = sw * qy + sx * qz - sy * qw - sz * qx
    ez = sw * qz - sx * qy + sy * qx - sz * qw
    if ew < 0.0:  # the shorter way round
        ew, ex, ey, ez = -ew, -ex, -ey, -ez
    s2 = ex * ex + ey * ey + ez * ez
    if s2 < 2.5e-3 * ew * ew:
        # angle / |e_v| = 2 atan(r)/(r ew), r = |e_v|/ew < 0.05: series exact to double precision
        r2 = s2 / (ew * ew)
        k = 2.0 / ew * (1.0 - r2 * (1.0 / 3.0 - r2 * (0.2 - r2 / 7.0)))
    else:
        s = math.sqrt(s2)
        k = 2.0 * math.atan2(s, ew) / s
    k *= inv
    wx = x[X.WX] + k * ex
    wy = x[X.WY] + k * ey
    wz = x[X.WZ] + k * ez
    x[X.SWX], x[X.SWY], x[X.SWZ] = wx, wy, wz

    # integrate the shadow's attitude with its own rate (exact exponential over the tick)
    c, kk = rotation_half_angle(wx, wy, wz, dt)
    x[X.SQW], x[X.SQX], x[X.SQY], x[X.SQZ] = quat_mul_normalised(
        (sw, sx, sy, sz), (c, kk * wx, kk * wy, kk * wz))

    # translation
    vn, ve, vd = step_translation(x, X.SPN, an, ae, ad, dt)
    # converged and airborne: hand back to the truth
    if x[X.ON_GROUND] == 0.0 and ex * ex + ey * ey + ez * ez < SMOOTH_DONE_Q2:
        pv = dpn * dpn + dpe * dpe + dpd * dpd
        wn, we, wd = x[X.VN] - vn, x[X.VE] - ve, x[X.VD] - vd
        if pv + wn * wn + we * we + wd * wd < SMOOTH_DONE_PV2:
            x[X.SMOOTH_ACTIVE] = 0.0
