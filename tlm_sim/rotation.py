"""Attitude conversions shared by the physics, sensors, EKF and logger (numba, scalar).

Quaternions are Hamilton, scalar first, rotating body (FRD) vectors into NED.
"""

import math

from tlm_sim._jit import tick_jit


@tick_jit
def quat_to_dcm(qw, qx, qy, qz):
    """Rotation matrix body -> NED of a unit quaternion, as 9 row-major entries r00..r22."""
    return (
        1.0 - 2.0 * (qy * qy + qz * qz), 2.0 * (qx * qy - qw * qz), 2.0 * (qx * qz + qw * qy),
        2.0 * (qx * qy + qw * qz), 1.0 - 2.0 * (qx * qx + qz * qz), 2.0 * (qy * qz - qw * qx),
        2.0 * (qx * qz - qw * qy), 2.0 * (qy * qz + qw * qx), 1.0 - 2.0 * (qx * qx + qy * qy),
    )


@tick_jit
def quat_to_euler(qw, qx, qy, qz):
    """ZYX Euler angles (roll, pitch, yaw) [rad] of a body -> NED quaternion."""
    roll = math.atan2(2.0 * (qw * qx + qy * qz), 1.0 - 2.0 * (qx * qx + qy * qy))
    sp = min(max(2.0 * (qw * qy - qz * qx), -1.0), 1.0)
    pitch = math.asin(sp)
    yaw = math.atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
    return roll, pitch, yaw
