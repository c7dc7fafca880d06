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


@tick_jit
def heading_vector(q):
    """Body x axis of a body->NED quaternion array q projected on the horizontal plane (hx,
    hy), and its length."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    hx = 1.0 - 2.0 * (y * y + z * z)
    hy = 2.0 * (w * z + x * y)
    return hx, hy, math.sqrt(hx * hx + hy * hy)


@tick_jit
def heading(q):
    """Heading [rad] of a body->NED quaternion array q (0 when the body x axis points straight
    down or up); only where needed: an atan2 every tick cost about 1.5 % of the loop."""
    hx, hy, norm = heading_vector(q)
    return 0.0 if norm < 1e-9 else math.atan2(hy, hx)


_R6, _R12, _R20, _R30, _R42, _R56 = (1.0 / n for n in (6.0, 12.0, 20.0, 30.0, 42.0, 56.0))


@tick_jit
def rotation_half_angle(wx, wy, wz, dt):
    """(c, k) of the rotation by |w| dt about w: dq = (c, k w) = (cos(th/2), w_hat sin(th/2)).

    For th/2 < 0.05 (always at 1200 Hz with |w| <= 2000 deg/s) the series are exact to double
    precision; otherwise sin/cos are evaluated. w [rad/s], dt [s].
    """
    h2 = 0.25 * (wx * wx + wy * wy + wz * wz) * dt * dt  # (th/2)^2
    if h2 < 2.5e-3:
        # Taylor series, multiplying by reciprocal constants (a division is ~4x a multiply)
        k = 0.5 * dt * (1.0 - h2 * _R6 * (1.0 - h2 * _R20 * (1.0 - h2 * _R42)))
        c = 1.0 - h2 * 0.5 * (1.0 - h2 * _R12 * (1.0 - h2 * _R30 * (1.0 - h2 * _R56)))
    else:
        wn = math.sqrt(wx * wx + wy * wy + wz * wz)
        k = math.sin(0.5 * wn * dt) / wn
        c = math.cos(0.5 * wn * dt)
    return c, k


@tick_jit
def quat_mul_normalised(q, r):
    """q * r, renormalised (one Newton step of 1/sqrt near 1, else the exact root); q = (qw,
    qx, qy, qz), r = (c, ux, uy, uz)."""
    qw, qx, qy, qz = q
    c, ux, uy, uz = r
    nw = qw * c - qx * ux - qy * uy - qz * uz
    nx = qw * ux + qx * c + qy * uz - qz * uy
    ny = qw * uy - qx * uz + qy * c + qz * ux
    nz = qw * uz + qx * uy - qy * ux + qz * c
    n2 = nw * nw + nx * nx + ny * ny + nz * nz
    inv = 1.5 - 0.5 * n2 if abs(n2 - 1.0) < 1.0e-8 else 1.0 / math.sqrt(n2)
    return nw * inv, nx * inv, ny * inv, nz * inv
