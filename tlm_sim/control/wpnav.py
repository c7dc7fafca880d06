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

from tlm_sim._jit import tick_jit
from tlm_sim.control import layout as C

# path rows: (pn, pe, pd) of the point, then data of the leg that ENDS at that point
P_LEN = 3  # leg length [m]
P_UN, P_UE, P_UD = 4, 5, 6  # leg unit vector NED
P_VLEG = 7  # leg speed limit [m/s]
P_CORNER = 8  # cos of the turn at the end of the leg (0 at the path's end / beyond 90 deg)
PATH_COLS = 9


@tick_jit
def leg_speed(g, length, dd):
    """Speed limit [m/s] of a leg of 3-D length [m] and down displacement dd [m]."""
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


@tick_jit
def prepare_path(path, n, g):
    """Fill the leg columns (P_LEN..P_CORNER) of path[0:n] from its points (NED in 0:3)."""
    path[0, P_LEN] = 0.0
    path[0, P_UN] = 0.0
    path[0, P_UE] = 0.0
    path[0, P_UD] = 0.0
    path[0, P_VLEG] = g[C.G_WP_SPEED]
    path[0, P_CORNER] = 1.0
    for i in range(1, n):
        dn = path[i, 0] - path[i - 1, 0]
        de = path[i, 1] - path[i - 1, 1]
        dd = path[i, 2] - path[i - 1, 2]
        length = math.sqrt(dn * dn + de * de + dd * dd)
        path[i, P_LEN] = length
        if length > 1e-9:
            path[i, P_UN] = dn / length
            path[i, P_UE] = de / length
            path[i, P_UD] = dd / length
        else:
            path[i, P_UN] = 0.0
            path[i, P_UE] = 0.0
            path[i, P_UD] = 0.0
        path[i, P_VLEG] = leg_speed(g, length, dd)
    for i in range(1, n):
        if i >= n - 1:
            path[i, P_CORNER] = 0.0
        elif path[i, P_LEN] < 1e-6 or path[i + 1, P_LEN] < 1e-6:
            path[i, P_CORNER] = 1.0
        else:
            cosang = (path[i, P_UN] * path[i + 1, P_UN] + path[i, P_UE] * path[i + 1, P_UE]
                      + path[i, P_UD] * path[i + 1, P_UD])
            path[i, P_CORNER] = max(cosang, 0.0)


@tick_jit
def path_start(c):
    """Start following a path from its first point (leg 1), target at rest."""
    c[C.WP_INDEX] = 1.0
    c[C.PATH_S] = 0.0
    c[C.PATH_V] = 0.0
    c[C.PATH_A] = 0.0


@tick_jit
def path_update(c, g, path, n, pos, speed_cap):
    """Advance the target along path[0:n] (prepared by prepare_path) and set the position
    controller targets. pos: EKF position NED [m]; speed_cap [m/s] (<= 0: none).

    Returns (leg heading [rad], nan for a vertical leg; 1.0 when the end is reached).
    """
    dt = g[C.G_DT]
    i = int(c[C.WP_INDEX])
    if i >= n:
        i = n - 1
    length = path[i, P_LEN]
    s = c[C.PATH_S]
    v_leg = path[i, P_VLEG]
    if speed_cap > 0.0:
        v_leg = min(v_leg, speed_cap)
    a_max = g[C.G_WP_ACCEL]
    # speed allowed by the distance to the next corner / the end (two legs of look-ahead)
    d_rem = max(length - s, 0.0)
    v_corner = v_leg * path[i, P_CORNER]
    if i + 1 < n:
        v_corner = min(v_corner, path[i + 1, P_VLEG])
    v_allow = min(v_leg, math.sqrt(v_corner * v_corner + a_max * d_rem))
    if i + 1 < n:
        v_c2 = path[i + 1, P_VLEG] * path[i + 1, P_CORNER]
        v_allow = min(v_allow, math.sqrt(v_c2 * v_c2 + a_max * (d_rem + path[i + 1, P_LEN])))
    # the target waits for a vehicle that falls behind
    en = path[i - 1, 0] + path[i, P_UN] * s - pos[0]
    ee = path[i - 1, 1] + path[i, P_UE] * s - pos[1]
    ed = path[i - 1, 2] + path[i, P_UD] * s - pos[2]
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
            length = path[i, P_LEN]
            s = min(s, length)
        else:
            s = length
            done = 1.0
    c[C.PATH_S] = s
    un = path[i, P_UN]
    ue = path[i, P_UE]
    ud = path[i, P_UD]
    c[C.PXY_POS_T] = path[i - 1, 0] + un * s
    c[C.PXY_POS_T + 1] = path[i - 1, 1] + ue * s
    c[C.PZ_POS_T] = path[i - 1, 2] + ud * s
    vff = 0.0 if done > 0.0 else v
    c[C.PXY_VEL_FF] = un * vff
    c[C.PXY_VEL_FF + 1] = ue * vff
    c[C.PZ_VEL_FF] = ud * vff
    c[C.PXY_ACC_FF] = un * a
    c[C.PXY_ACC_FF + 1] = ue * a
    heading = math.nan
    if length * math.sqrt(un * un + ue * ue) > 0.5:
        heading = math.atan2(ue, un)
    return heading, done
