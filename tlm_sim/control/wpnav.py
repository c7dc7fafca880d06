"""Waypoint navigation along a polyline (AC_WPNav behaviour, our implementation).

A target point moves along the legs of a path (NED, m) at a speed limited per leg, with the
acceleration limit along the leg (WPNAV_ACCEL and WPNAV_ACCEL_Z, as AC_WPNav's S-curve takes
them along the track) and jerk limit WPNAV_JERK, and stops at the path's end with the S-curve's
jerk-limited deceleration. ArduCopter plans every leg as an S-curve that could stop at its
end; on the short (~13 m) legs of Algorithm 1 missions that caps the cruise speed well below
WPNAV_SPEED (the reference SITL logs cruise at ~3.4 m/s with WPNAV_SPEED 6 m/s). We model
that cap as v_leg = K * (L * sqrt(J) / 2)^(2/3), the peak speed of a jerk-limited rest-to-rest
move over the leg length L, with K (TLM_WP_LEG_K) fitted to the reference logs.
When the vehicle falls behind, the target's progress slows as AC_WPNav's S-curve time does
(its track scaler, see :func:`path_update`); the feed-forwards keep their values.

Corners. ArduCopter does not stop at an intermediate waypoint: it starts the next leg's S-curve
while the current one decelerates, so that the current leg's speed ramps down (jerk-limited)
while the next one's ramps up and the velocity vector turns smoothly from one leg's direction to
the next (the speed dips to v cos(turn/2) half-way). We reproduce that overlap geometrically:
around each corner the path is blended over +-b along the legs, b = v T / 2 with T the
jerk-limited time to reach the corner speed v from rest (2 sqrt(v/J), or v/A + A/J above
A^2/J), at most half of either leg. With the blend weight w rising along the distance x from
-b to +b as the S-curve's (2 sigma^2, then 1 - 2 (1 - sigma)^2, sigma = (x + b)/(2b); the jerk
changes spread over pi/2 ATC_INPUT_TC as ArduPilot's snap limit does, see smooth_step), the
target's direction is (1 - w) u_in + w u_out, its position the integral of that (the blended
path leaves and rejoins the legs at +-b), and at constant speed the target's acceleration
rises and falls linearly in time as in the overlapping S-curves. The reference logs show it:
normal_s11 turns 95 deg at ~128-132 s with the speed dipping from 3.39 to 2.31 m/s
(3.39 cos 47.5 deg = 2.29) over 3.9 s (T = 3.7 s), and its vertical velocity target changes
smoothly across every waypoint instead of stepping.

Position, velocity and acceleration targets (the S-curve's feed-forwards) all come from the
blended path: velocity = v dp/ds, acceleration = a dp/ds + v^2 d2p/ds2, and the heading is
the direction of the horizontal velocity with its rate as feed-forward (AC_WPNav's yaw and
yaw rate, as ArduCopter's AUTO yaw follows them).
"""

import math

from tlm_sim._jit import inline_jit, tick_jit
from tlm_sim.control import layout as C

# path rows: (pn, pe, pd) of the point, then data of the leg that ENDS at that point
P_LEN = 3  # leg length [m]
P_UN, P_UE, P_UD = 4, 5, 6  # leg unit vector NED
P_VLEG = 7  # leg speed limit [m/s]
P_CORNER = 8  # 1 if the path goes on after this leg, 0 at the path's end
P_BLEND = 9  # half-length [m] of the corner blend at the END of this leg (0: none)
P_RAMP = 10  # jerk ramp of that blend as a fraction of its duration (see smooth_step)
P_ALEG = 11  # acceleration limit along this leg [m/s^2] (WPNAV_ACCEL, WPNAV_ACCEL_Z)
P_RAMP_C = 12  # normalisation of that blend's S-curve (step_norm(P_RAMP))
P_DEND = 13  # path length from this leg's end point to the next stop [m]
# inputs set with the points (0 in a plain path: defaults), from the mission's items
P_SPEED = 14  # speed limit of this leg [m/s] (DO_CHANGE_SPEED; 0: WPNAV_SPEED)
P_STOP = 15  # 1: the path stops at this point (a hold, LOITER_TIME, the point before a LAND)
P_HOLD = 16  # time held at this point once reached [s] (ModeAuto's loiter_time_max)
P_CMD = 17  # MAV_CMD of this point's navigation item (0: none)
P_CNUM = 18  # its mission item number (CMD / MISE CNum)
PATH_COLS = 19


@tick_jit
def leg_speed(g, length, dd):
    """Speed limit [m/s] of a leg of 3-D length [m] and down displacement dd [m]."""
    return leg_speed_max(g, g[C.G_WP_SPEED], length, dd)


@tick_jit
def leg_speed_max(g, v, length, dd):
    """Speed limit [m/s] of a leg of 3-D length [m] and down displacement dd [m] whose speed
    is set to v [m/s] (WPNAV_SPEED, or a DO_CHANGE_SPEED's)."""
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
def _step_half(sig, r):
    """Jerk shape j and its integrals J1, J2, J3 from 0 to sig (0 <= sig <= 0.5) of the
    snap-limited profile of :func:`smooth_step` (unnormalised)."""
    pi = math.pi
    if r <= 0.0:
        return 1.0, sig, 0.5 * sig * sig, sig * sig * sig / 6.0
    if sig <= r:
        a = pi * sig / r
        q = r * r / (2.0 * pi * pi)
        return (0.5 * (1.0 - math.cos(a)), 0.5 * sig - r / (2.0 * pi) * math.sin(a),
                0.25 * sig * sig + q * (math.cos(a) - 1.0),
                sig * sig * sig / 12.0 + q * (r / pi * math.sin(a) - sig))
    j1 = 0.5 * r
    j2 = r * r * (0.25 - 1.0 / (pi * pi))
    j3 = r * r * r * (1.0 / 12.0 - 0.5 / (pi * pi))
    s3 = 0.5 - r
    u = min(sig, s3) - r
    # constant jerk from r to s3
    j1, j2, j3 = j1 + u, j2 + j1 * u + 0.5 * u * u, j3 + j2 * u + 0.5 * j1 * u * u + u * u * u / 6.0
    if sig <= s3:
        return 1.0, j1, j2, j3
    k = pi / (2.0 * r)
    u = sig - s3
    sk = math.sin(k * u)
    ck = math.cos(k * u)
    return (ck, j1 + sk / k, j2 + j1 * u + (1.0 - ck) / (k * k),
            j3 + j2 * u + 0.5 * j1 * u * u + (u - sk / k) / (k * k))


@tick_jit
def step_norm(r):
    """Normalisation constant of :func:`smooth_step` for the jerk ramp r (0..0.25)."""
    return 0.5 / _step_half(0.5, min(max(r, 0.0), 0.25))[2]


@tick_jit
def smooth_step(sig, r, c):
    """A rest-to-rest S-curve of unit length and unit duration at time sig (0..1).

    Returns (w, dw, ddw, W): position, speed, acceleration and the integral of w from 0. The
    jerk is +J for the first half and -J for the second, each change of jerk spread over a
    raised-cosine ramp of r (0..0.25) of the duration: ArduPilot's S-curves limit the snap to
    jerk / ATC_INPUT_TC, a ramp of pi/2 ATC_INPUT_TC (0.24 s). r = 0 gives the constant-jerk
    curve (w = 2 sig^2 on the first half). w(sig) + w(1 - sig) = 1. c: step_norm(r).
    """
    r = min(max(r, 0.0), 0.25)
    if sig <= 0.5:
        j, j1, j2, j3 = _step_half(max(sig, 0.0), r)
        return c * j2, c * j1, c * j, c * j3
    j, j1, j2, j3 = _step_half(max(1.0 - sig, 0.0), r)
    return 1.0 - c * j2, c * j1, -c * j, sig - 0.5 + c * j3


@tick_jit
def jerk_ramp(g, duration):
    """Fraction r of an S-curve of ``duration`` [s] spent ramping the jerk (pi/2 ATC_INPUT_TC
    each), for :func:`smooth_step`."""
    if duration <= 0.0:
        return 0.25
    return min(0.5 * math.pi * g[C.G_INPUT_TC] / duration, 0.25)


@tick_jit
def leg_accel(g, un, ue, ud):
    """Acceleration limit [m/s^2] along a leg of unit direction (un, ue, ud): the largest whose
    horizontal and vertical parts stay within WPNAV_ACCEL and WPNAV_ACCEL_Z (AC_WPNav's S-curve
    takes its limits along the track this way)."""
    a = g[C.G_WP_ACCEL]
    h = math.sqrt(un * un + ue * ue)
    if h > 1e-9:
        a = a / h
    az = g[C.G_WP_ACCEL_Z]
    if abs(ud) > 1e-9 and az > 0.0:
        a = min(a, az / abs(ud))
    return a


@tick_jit
def blend_half_length(g, v, a):
    """Half-length b [m] of a corner blend at speed v [m/s]: v T / 2, T the jerk-limited time
    (WPNAV_JERK, acceleration limit a [m/s^2]) to reach v from rest; also the distance of a
    jerk-limited stop from v."""
    j = g[C.G_WP_JERK]
    if v <= 0.0 or j <= 0.0:
        return 0.0
    if a <= 0.0 or v <= a * a / j:
        t = 2.0 * math.sqrt(v / j)
    else:
        t = v / a + a / j
    return 0.5 * v * t


@tick_jit
def prepare_path(path, n, g):
    """Fill the leg columns (P_LEN..P_DEND) of path[0:n] from its points (NED in 0:3) and the
    input columns P_SPEED (a leg's set speed) and P_STOP (the path stops at a point as at its
    end: no corner blend there, the target comes to rest)."""
    path[0, P_LEN] = 0.0
    path[0, P_UN] = 0.0
    path[0, P_UE] = 0.0
    path[0, P_UD] = 0.0
    path[0, P_VLEG] = g[C.G_WP_SPEED]
    path[0, P_CORNER] = 1.0
    path[0, P_ALEG] = g[C.G_WP_ACCEL]
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
        v_set = path[i, P_SPEED] if path[i, P_SPEED] > 0.0 else g[C.G_WP_SPEED]
        path[i, P_VLEG] = leg_speed_max(g, v_set, length, dd)
        path[i, P_ALEG] = leg_accel(g, path[i, P_UN], path[i, P_UE], path[i, P_UD])
    path[0, P_BLEND] = 0.0
    path[0, P_RAMP] = 0.0
    path[0, P_RAMP_C] = step_norm(0.0)
    for i in range(1, n):
        path[i, P_BLEND] = 0.0
        path[i, P_RAMP] = 0.0
        path[i, P_RAMP_C] = step_norm(0.0)
        if i >= n - 1 or path[i, P_STOP] != 0.0:
            path[i, P_CORNER] = 0.0
            continue
        path[i, P_CORNER] = 1.0
        if path[i, P_LEN] > 1e-6 and path[i + 1, P_LEN] > 1e-6:
            v_c = min(path[i, P_VLEG], path[i + 1, P_VLEG])
            a_c = min(path[i, P_ALEG], path[i + 1, P_ALEG])
            b = min(blend_half_length(g, v_c, a_c), 0.5 * path[i, P_LEN],
                    0.5 * path[i + 1, P_LEN])
            path[i, P_BLEND] = b
            path[i, P_RAMP] = jerk_ramp(g, 2.0 * b / v_c)
            path[i, P_RAMP_C] = step_norm(path[i, P_RAMP])
    rest = 0.0
    for i in range(n - 1, -1, -1):
        if path[i, P_CORNER] == 0.0:
            rest = 0.0
        path[i, P_DEND] = rest
        rest += path[i, P_LEN]


@tick_jit
def path_point(path, n, i, s):
    """Point of the blended path at distance s [m] along leg i of path[0:n] (prepared).

    Returns (pn, pe, pd, dn, de, dd, kn, ke, kd): the position [m], its derivative dp/ds (the
    direction, unit length outside the blends) and second derivative d2p/ds2 [1/m].
    """
    length = path[i, P_LEN]
    un = path[i, P_UN]
    ue = path[i, P_UE]
    ud = path[i, P_UD]
    b_end = path[i, P_BLEND]
    b_start = path[i - 1, P_BLEND] if i >= 2 else 0.0
    if b_end > 0.0 and s > length - b_end and i + 1 < n:
        b = b_end
        ramp = path[i, P_RAMP]
        norm = path[i, P_RAMP_C]
        x = s - length
        cn, ce, cd = path[i, 0], path[i, 1], path[i, 2]
        an, ae, ad = un, ue, ud
        bn, be, bd = path[i + 1, P_UN], path[i + 1, P_UE], path[i + 1, P_UD]
    elif b_start > 0.0 and s < b_start:
        b = b_start
        ramp = path[i - 1, P_RAMP]
        norm = path[i - 1, P_RAMP_C]
        x = s
        cn, ce, cd = path[i - 1, 0], path[i - 1, 1], path[i - 1, 2]
        an, ae, ad = path[i - 1, P_UN], path[i - 1, P_UE], path[i - 1, P_UD]
        bn, be, bd = un, ue, ud
    else:
        return (path[i - 1, 0] + un * s, path[i - 1, 1] + ue * s, path[i - 1, 2] + ud * s,
                un, ue, ud, 0.0, 0.0, 0.0)
    sig = min(max((x + b) / (2.0 * b), 0.0), 1.0)
    w, w1, _, w_int = smooth_step(sig, ramp, norm)
    big_w = 2.0 * b * w_int
    wp = w1 / (2.0 * b)
    jn, je, jd = bn - an, be - ae, bd - ad
    return (cn + an * x + jn * big_w, ce + ae * x + je * big_w, cd + ad * x + jd * big_w,
            an + jn * w, ae + je * w, ad + jd * w, jn * wp, je * wp, jd * wp)


@tick_jit
def path_start(c):
    """Start following a path from its first point (leg 1), target at rest."""
    c[C.WP_INDEX] = 1.0
    c[C.PATH_S] = 0.0
    c[C.PATH_V] = 0.0
    c[C.PATH_A] = 0.0
    c[C.PATH_STOP_T] = -1.0
    c[C.TRACK_K] = 1.0


@tick_jit
def path_resume(c, i):
    """Go on from the stop at point i along leg i + 1, the target at rest (AC_WPNav's next
    destination after a waypoint the copter stopped at)."""
    c[C.WP_INDEX] = i + 1.0
    c[C.PATH_S] = 0.0
    c[C.PATH_V] = 0.0
    c[C.PATH_A] = 0.0
    c[C.PATH_STOP_T] = -1.0


@tick_jit
def track_scaler(c, g, pos, vel):
    """AC_WPNav's S-curve time scaler: the fraction of real time [0..1] by which the target's
    progress advances this tick.

    Along the desired (feed-forward) velocity u: 0.05 + (vehicle speed along u - PSC_POSXY_P x
    position error along u) / |u|, kept within 0..1 and low-passed with the time constant
    WPNAV_ACCEL / WPNAV_JERK (2.5 s). A vehicle that keeps up gives 1; one that lags gives
    less, and when the position error is large (after a jump of the position estimate) the
    target stops while the feed-forward velocity keeps its value: gps_s12.bin's PSCN shows the
    desired position frozen and DVN held at -3.21 m/s for the 19 s the EKF had no position.
    Written without a square root: the ratio is (v.u - P e.u) / |u|^2.
    """
    un = c[C.PXY_VEL_FF]
    ue = c[C.PXY_VEL_FF + 1]
    ud = c[C.PZ_VEL_FF]
    u2 = un * un + ue * ue + ud * ud
    k = 1.0
    if u2 > 1e-12:
        e_u = ((c[C.PXY_POS_T] - pos[0]) * un + (c[C.PXY_POS_T + 1] - pos[1]) * ue
               + (c[C.PZ_POS_T] - pos[2]) * ud)
        v_u = vel[0] * un + vel[1] * ue + vel[2] * ud
        k = min(max(0.05 + (v_u - g[C.G_POSXY_P] * e_u) / u2, 0.0), 1.0)
    tc = g[C.G_WP_ACCEL] / g[C.G_WP_JERK] if g[C.G_WP_JERK] > 0.0 else 1.0
    c[C.TRACK_K] += (k - c[C.TRACK_K]) * min(g[C.G_DT] / tc, 1.0)
    return c[C.TRACK_K]


@tick_jit
def stop_profile(g, v0, tau, amax):
    """Speed [m/s] and acceleration [m/s^2] at time tau [s] into a jerk-limited stop from v0
    (WPNAV_JERK, acceleration limit amax): the decelerating half of an S-curve, which covers
    blend_half_length(g, v0, amax) metres."""
    j = g[C.G_WP_JERK]
    if amax <= 0.0 or v0 <= amax * amax / j:
        # constant-jerk halves with snap-limited jerk changes: v = v0 (1 - w(tau / T))
        t_end = 2.0 * math.sqrt(v0 / j)
        if tau >= t_end:
            return 0.0, 0.0
        r = jerk_ramp(g, t_end)
        w, w1, _, _ = smooth_step(tau / t_end, r, step_norm(r))
        return v0 * (1.0 - w), -v0 * w1 / t_end
    else:
        t1 = amax / j
        t_end = v0 / amax + t1
        t2 = t_end - t1
    if tau < t1:
        return v0 - 0.5 * j * tau * tau, -j * tau
    if tau < t2:
        return v0 - 0.5 * amax * t1 - amax * (tau - t1), -amax
    if tau < t_end:
        r = t_end - tau
        return 0.5 * j * r * r, -j * r
    return 0.0, 0.0


@tick_jit
def path_update(c, g, path, n, nav, speed_cap, scale_time):
    """Advance the target along path[0:n] (prepared by prepare_path) and set the position
    controller targets and feed-forwards. nav: (pos, vel), the position controller's position
    and velocity estimates NED [m, m/s]; speed_cap [m/s] (<= 0: none). Sets c[YAW_RATE_CMD] to the
    heading's rate [rad/s] (0 without a heading).

    With scale_time (AC_WPNav legs) the target's speed profile runs on the S-curve time of
    :func:`track_scaler`; the feed-forwards are the profile's speed and acceleration at that
    time.

    The target stops at the path's end and at every point marked P_STOP (P_CORNER 0), where
    it reports 1.0 until the caller moves it on (:func:`path_resume`). Each point it passes
    counts in c[WP_REACHED], with the next point's P_CNUM in c[NAV_CNUM].

    Returns (heading of the horizontal velocity [rad], nan for a vertical leg; 1.0 when the end
    or a stop is reached).
    """
    pos, vel = nav
    dt = g[C.G_DT] * track_scaler(c, g, pos, vel) if scale_time else g[C.G_DT]
    i = int(c[C.WP_INDEX])
    if i >= n:
        i = n - 1
    length = path[i, P_LEN]
    s = c[C.PATH_S]
    v_allow, a_max = _allowed_speed(path, n, i, s, speed_cap)
    _start_stop(c, g, path, i, s, a_max, dt)
    v, a, stopped = _speed_step(c, g, v_allow, a_max, dt)
    c[C.PATH_A] = a
    c[C.PATH_V] = v
    s += v * dt
    done = 0.0
    if stopped:
        # the stop is complete: the target is at the stop (to within a tick's travel)
        while path[i, P_CORNER] != 0.0:
            i += 1
            c[C.WP_REACHED] += 1.0
            c[C.NAV_CNUM] = path[i, P_CNUM]
        c[C.WP_INDEX] = float(i)
        length = path[i, P_LEN]
        s = length
    if s >= length:
        if path[i, P_CORNER] != 0.0:
            s -= length
            c[C.WP_INDEX] = i + 1.0
            c[C.WP_REACHED] += 1.0
            i += 1
            c[C.NAV_CNUM] = path[i, P_CNUM]
            length = path[i, P_LEN]
            s = min(s, length)
        else:
            s = length
            done = 1.0
    c[C.PATH_S] = s
    vff = 0.0 if done > 0.0 else v
    aff = 0.0 if done > 0.0 else a
    return _set_targets(c, path, n, i, s, vff, aff), done


@inline_jit
def _allowed_speed(path, n, i, s, speed_cap):
    """(speed [m/s] allowed at arc length s [m] of leg i by the next legs' speeds and corners
    and by the path's end, two legs of look-ahead; the leg's acceleration [m/s^2])."""
    length = path[i, P_LEN]
    v_leg = path[i, P_VLEG]
    if speed_cap > 0.0:
        v_leg = min(v_leg, speed_cap)
    a_max = path[i, P_ALEG]
    d_rem = max(length - s, 0.0)
    v_corner = v_leg * path[i, P_CORNER]
    if i + 1 < n:
        v_corner = min(v_corner, path[i + 1, P_VLEG])
    v_allow = v_leg
    q = v_corner * v_corner + a_max * d_rem
    if q < v_allow * v_allow:
        v_allow = math.sqrt(q)
    if i + 1 < n:
        v_c2 = path[i + 1, P_VLEG] * path[i + 1, P_CORNER]
        if i + 2 < n:
            v_c2 = min(v_c2, path[i + 2, P_VLEG])
        q = v_c2 * v_c2 + a_max * (d_rem + path[i + 1, P_LEN])
        if q < v_allow * v_allow:
            v_allow = math.sqrt(q)
    return v_allow, a_max


@inline_jit
def _start_stop(c, g, path, i, s, a_max, dt):
    """Start the S-curve's own jerk-limited stop (PATH_STOP_*) when the path's end is its
    stopping distance away (s: arc length on leg i [m]; a_max [m/s^2]; dt [s])."""
    v = c[C.PATH_V]
    jerk = g[C.G_WP_JERK]
    if c[C.PATH_STOP_T] < 0.0 and jerk > 0.0 and v > 0.0:
        d_end = path[i, P_LEN] - s + path[i, P_DEND]
        # (a bound of the stopping distance without the square root first)
        if a_max > 0.0 and d_end <= v * (max(a_max / jerk, 0.5 * (v / a_max + a_max / jerk))
                                         + dt):
            if d_end <= blend_half_length(g, v, a_max) + v * dt:
                c[C.PATH_STOP_T] = 0.0
                c[C.PATH_STOP_V0] = v
                c[C.PATH_STOP_A] = a_max


@inline_jit
def _speed_step(c, g, v_allow, a_max, dt):
    """One step of the target's speed: the stop profile once started, else a jerk-limited
    (WPNAV_JERK) tracker of v_allow [m/s] (acceleration-limited without a jerk limit).
    Returns (speed [m/s], acceleration [m/s^2], whether the stop is complete)."""
    v = c[C.PATH_V]
    a = c[C.PATH_A]
    jerk = g[C.G_WP_JERK]
    if c[C.PATH_STOP_T] >= 0.0:
        c[C.PATH_STOP_T] += dt
        v_new, a = stop_profile(g, c[C.PATH_STOP_V0], c[C.PATH_STOP_T], c[C.PATH_STOP_A])
        return v_new, a, v_new <= 0.0
    if jerk > 0.0 and a == 0.0 and v == v_allow:
        return v, a, False  # cruising at the allowed speed
    if jerk > 0.0:
        e = v_allow - v
        if e >= 0.0:
            a_des = min(math.sqrt(2.0 * jerk * e), a_max)
        else:
            a_des = -min(math.sqrt(-2.0 * jerk * e), a_max)
        a += min(max(a_des - a, -jerk * dt), jerk * dt)
        v_new = v + a * dt
        if (v_new - v_allow) * e >= 0.0 and abs(a) <= jerk * dt:
            v_new = v_allow  # arrived (or passed by less than a tick's jerk): settle exactly
            a = 0.0
        if v_new < 0.0:
            v_new = 0.0
            a = 0.0
        return v_new, a, False
    v_new = min(v_allow, v + a_max * dt) if v_allow > v else max(v_allow, v - a_max * dt)
    a = (v_new - v) / dt if dt > 0.0 else 0.0
    return v_new, a, False


@inline_jit
def _set_targets(c, path, n, i, s, vff, aff):
    """Position-controller targets at arc length s [m] of leg i, velocity and acceleration
    feed-forwards for the target's speed vff [m/s] and acceleration aff [m/s^2] along the path
    (with its curvature), the heading's rate in YAW_RATE_CMD. Returns the heading of the
    horizontal velocity [rad] (nan for a vertical or short leg)."""
    pn, pe, pd, dn, de, dd, kn, ke, kd = path_point(path, n, i, s)
    c[C.PXY_POS_T] = pn
    c[C.PXY_POS_T + 1] = pe
    c[C.PZ_POS_T] = pd
    v2 = vff * vff
    c[C.PXY_VEL_FF] = dn * vff
    c[C.PXY_VEL_FF + 1] = de * vff
    c[C.PZ_VEL_FF] = dd * vff
    c[C.PXY_ACC_FF] = dn * aff + kn * v2
    c[C.PXY_ACC_FF + 1] = de * aff + ke * v2
    c[C.PZ_ACC_FF] = dd * aff + kd * v2
    heading = math.nan
    c[C.YAW_RATE_CMD] = 0.0
    hh = dn * dn + de * de
    if hh > 0.01 and path[i, P_LEN] * math.sqrt(path[i, P_UN] ** 2 + path[i, P_UE] ** 2) > 0.5:
        heading = math.atan2(de, dn)
        c[C.YAW_RATE_CMD] = vff * (dn * ke - de * kn) / hh
    return heading
