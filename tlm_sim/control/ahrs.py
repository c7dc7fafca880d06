"""The autopilot's view of the vehicle (ArduPilot's AHRS): built each main-loop tick from the
EKF's output block (``tlm_sim.ekf.layout`` O_*, filled by :func:`tlm_sim.ekf.lanes.ekf_output`)
and the filtered samples of the IMU the primary lane integrates (or of the first healthy IMU
while that one's gyro or accel is stopped). The controllers read only this.
"""

from tlm_sim._jit import tick_jit
from tlm_sim.ardupilot import GRAVITY_MSS
from tlm_sim.ekf import layout as EK
from tlm_sim.sensors import layout as S


@tick_jit
def _usable_imu(s, imu, ok_slot):
    """Record base of the IMU whose gyro (ok_slot I_GYR_OK) or accel (I_ACC_OK) the controllers
    read: the primary lane's IMU while that sensor is healthy, else the first healthy one
    (ArduPilot's AHRS falls back to the INS's first usable sensor); the primary's own (its held
    value) when none is healthy."""
    ib = S.IMU_BASE + imu * S.IMU_STRIDE
    if s[ib + ok_slot] != 0.0:
        return ib
    for j in range(S.N_IMU):
        jb = S.IMU_BASE + j * S.IMU_STRIDE
        if s[jb + ok_slot] != 0.0:
            return jb
    return ib


@tick_jit
def ahrs_update(eo, s, pos, vel, q, gyro, acc_ned):
    """Fill the controllers' inputs from the EKF output eo and the sensor state s.

    pos, vel: position / velocity NED [m, m/s] (position (0, 0) in constant-position mode);
    q: attitude body->NED; gyro: filtered body rates minus the EKF's gyro bias [rad/s];
    acc_ned: kinematic acceleration NED [m/s^2] (filtered accel minus the EKF's bias, rotated
    by the EKF attitude, gravity removed). The failsafe checks read the EKF's status from eo
    itself (:mod:`tlm_sim.control.failsafe`).
    """
    for k in range(3):
        pos[k] = eo[EK.O_PN + k]
        vel[k] = eo[EK.O_VN + k]
    if eo[EK.O_F_CONST_POS] != 0.0:
        # no horizontal position from the EKF (constant-position mode): AC_PosControl's
        # estimate is then the EKF origin, as the AHRS call fails and leaves it at zero
        # (gps_s12.bin: PSCN.PN / PSCE.PE are 0.000 from "stopped aiding" to "is using GPS")
        pos[0] = 0.0
        pos[1] = 0.0
    if eo[EK.O_F_VERT_POS] == 0.0 and eo[EK.O_F_ATTITUDE] != 0.0:
        # no valid height (EKF3's height timeout: no baro fused for 10 s): the AHRS call for
        # the NED position relative to the origin fails as a whole and AC_PosControl's estimate
        # is the origin, all three axes (baro_s44.bin: PSCN.PN, PSCE.PE, PSCD.PD and CTUN.Alt
        # are 0 from +10.19 s until the baros return). Its targets are then held within the
        # errors that ask for WPNAV_SPEED / WPNAV_SPEED_UP of it (PSCD.TPD -3.625 m), so the
        # copter climbs at WPNAV_SPEED_UP and flies off towards its horizontal target.
        pos[0] = 0.0
        pos[1] = 0.0
        pos[2] = 0.0
    for k in range(4):
        q[k] = eo[EK.O_QW + k]
    gb = _usable_imu(s, int(eo[EK.O_IMU]), S.I_GYR_OK)
    for k in range(3):
        gyro[k] = s[gb + S.I_GYR_F + k] - eo[EK.O_BGX + k]
    ab = _usable_imu(s, int(eo[EK.O_IMU]), S.I_ACC_OK)
    ax = s[ab + S.I_ACC_F] - eo[EK.O_BAX]
    ay = s[ab + S.I_ACC_F + 1] - eo[EK.O_BAY]
    az = s[ab + S.I_ACC_F + 2] - eo[EK.O_BAZ]
    acc_ned[0] = eo[EK.O_R00] * ax + eo[EK.O_R01] * ay + eo[EK.O_R02] * az
    acc_ned[1] = eo[EK.O_R10] * ax + eo[EK.O_R11] * ay + eo[EK.O_R12] * az
    acc_ned[2] = eo[EK.O_R20] * ax + eo[EK.O_R21] * ay + eo[EK.O_R22] * az + GRAVITY_MSS
