"""Waypoint navigation along a polyline (AC_WPNav behaviour, our implementation).

A target point moves along the legs of a path (NED, m) at a speed limited per leg, with the
acceleration limit WPNAV_ACCEL and jerk limit WPNAV_JERK while speeding up; it slows for corners
(to cos(turn angle) of the leg speed) and stops at the path's end. ArduCopter plans every leg as an
S-curve that could stop at its end; on the short (~13 m) legs of Algorithm 1 missions that caps the
cruise speed well below WPNAV_SPEED (the reference SITL logs cruise at ~3.4 m/s with WPNAV_SPEED
6 m/s). We model that cap as v_leg = K * (L * sqrt(J) / 2)^(2/3), the peak speed of a jerk-limited
rest-to-rest move over the leg length L, with K (TLM_WP_LEG_K) fitted to the reference logs.
The target waits for the vehicle when it falls behind (position error beyond 2 m).
"""

import math

from numba import njit

from tlm_sim.control import layout as C


@njit(cache=True, nogil=True)
def leg_speed(g, path, i):
    """Speed limit [m/s] on leg i (from path[i-1] to path[i])."""
    dn = path[i, 0] - path[i - 1, 0]
    de = path[i, 1] - path[i - 1, 1]
    dd = path[i, 2] - path[i - 1, 2]
    length = math.sqrt(dn * dn + de * de + dd * dd)
    v = g[C.G_WP_SPEED]
    if length <= 1e-6:
        return v
    v_jerk = g[C.G_WP_LEG_K] * (length * math.sqrt(g[C.G_WP_JERK]) / 2.0) ** (2.0 / 3.0)
    v = min(v, v_jerk)
    if dd < -1e-6:  # climbing
        v = min(v, g[C.G_WP_SPEED_UP] * length / -dd)
    elif dd > 1e-6:
        v = min(v, g[C.G_WP_SPEED_DN] * length / dd)
    return max(v, 0.1)


@njit(cache=True, nogil=True)
def _corner_factor(path, i, n):
    """cos of the turn at the end of leg i (0 at the path's end, 0 for turns beyond 90 deg)."""
    if i >= n - 1:
        return 0.0
    a0 = path[i, 0] - path[i - 1, 0]
    a1 = path[i, 1] - path[i - 1, 1]
    a2 = path[i, 2] - path[i - 1, 2]
    b0 = path[i + 1, 0] - path[i, 0]
    b1 = path[i + 1, 1] - path[i, 1]
    b2 = path[i + 1, 2] - path[i, 2]
    na = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
    nb = math.sqrt(b0 * b0 + b1 * b1 + b2 * b2)
    if na < 1e-6 or nb < 1e-6:
        return 1.0
    return max((a0 * b0 + a1 * b1 + a2 * b2) / (na * nb), 0.0)


@njit(cache=True, nogil=True)
def path_start(c):
    """Start following a path from its first point (leg 1), target at rest."""
    c[C.WP_INDEX] = 1.0
    c[C.PATH_S] = 0.0
    c[C.PATH_V] = 0.0
    c[C.PATH_A] = 0.0


@njit(cache=True, nogil=True)
def path_update(c, g, path, n, pos, speed_cap):
    """Advance the target along path[0:n] and set the position controller targets.

    pos: EKF position NED [m]. speed_cap [m/s] (<= 0: none) e.g. RTL_SPEED.
    Returns (leg heading [rad] or nan when the leg is vertical, 1.0 when the end is reached).
    """
    dt = g[C.G_DT]
    i = int(c[C.WP_INDEX])
    if i >= n:
        i = n - 1
    p0n, p0e, p0d = path[i - 1, 0], path[i - 1, 1], path[i - 1, 2]
    dn = path[i, 0] - p0n
    de = path[i, 1] - p0e
    dd = path[i, 2] - p0d
    length = math.sqrt(dn * dn + de * de + dd * dd)
    s = c[C.PATH_S]
    v_leg = leg_speed(g, path, i)
    if speed_cap > 0.0:
        v_leg = min(v_leg, speed_cap)
    a_max = g[C.G_WP_ACCEL]
    # speed allowed from the distance to the next corner / the end (two legs of look-ahead)
    d_rem = max(length - s, 0.0)
    v_corner = v_leg * _corner_factor(path, i, n)
    if i + 1 < n:
        v_corner = min(v_corner, leg_speed(g, path, i + 1))
    v_allow = min(v_leg, math.sqrt(v_corner * v_corner + a_max * d_rem))
    if i + 1 < n:
        dn2 = path[i + 1, 0] - path[i, 0]
        de2 = path[i + 1, 1] - path[i, 1]
        dd2 = path[i + 1, 2] - path[i, 2]
        l2 = math.sqrt(dn2 * dn2 + de2 * de2 + dd2 * dd2)
        v_c2 = leg_speed(g, path, i + 1) * _corner_factor(path, i + 1, n)
        v_allow = min(v_allow, math.sqrt(v_c2 * v_c2 + a_max * (d_rem + l2)))
    # the target waits for a vehicle that falls behind
    tn = p0n + (dn / length * s if length > 1e-9 else 0.0)
    te = p0e + (de / length * s if length > 1e-9 else 0.0)
    td = p0d + (dd / length * s if length > 1e-9 else 0.0)
    en = tn - pos[0]
    ee = te - pos[1]
    ed = td - pos[2]
    err = math.sqrt(en * en + ee * ee + ed * ed)
    if err > 2.0:
        v_allow *= max(0.0, 1.0 - (err - 2.0) / 3.0)
    # speed with accel and jerk limits (jerk only shapes speeding up)
    v = c[C.PATH_V]
    a = c[C.PATH_A]
    if v_allow > v:
        a = min(a + g[C.G_WP_JERK] * dt, a_max)
        a = max(a, 0.0)
        v = min(v + a * dt, v_allow)
    else:
        a = 0.0
        v = max(v_allow, v - 2.0 * a_max * dt)
    c[C.PATH_A] = a
    c[C.PATH_V] = v
    s += v * dt
    done = 0.0
    if s >= length:
        if i < n - 1:
            s -= length
            c[C.WP_INDEX] = i + 1.0
            c[C.WP_REACHED] += 1.0
            i += 1
            p0n, p0e, p0d = path[i - 1, 0], path[i - 1, 1], path[i - 1, 2]
            dn = path[i, 0] - p0n
            de = path[i, 1] - p0e
            dd = path[i, 2] - p0d
            length = math.sqrt(dn * dn + de * de + dd * dd)
            s = min(s, length)
        else:
            s = length
            done = 1.0
    c[C.PATH_S] = s
    if length > 1e-9:
        un = dn / length
        ue = de / length
        ud = dd / length
    else:
        un = 0.0
        ue = 0.0
        ud = 0.0
    c[C.PXY_POS_T] = p0n + un * s
    c[C.PXY_POS_T + 1] = p0e + ue * s
    c[C.PZ_POS_T] = p0d + ud * s
    vff = 0.0 if done > 0.0 else v
    c[C.PXY_VEL_FF] = un * vff
    c[C.PXY_VEL_FF + 1] = ue * vff
    c[C.PZ_VEL_FF] = ud * vff
    c[C.PXY_ACC_FF] = un * a
    c[C.PXY_ACC_FF + 1] = ue * a
    heading = math.nan
    if math.sqrt(dn * dn + de * de) > 0.5:
        heading = math.atan2(de, dn)
    return heading, done
