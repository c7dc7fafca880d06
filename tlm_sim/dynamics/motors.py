"""Motor and frame force model of SITL's multicopter (ardupilot-reference.md §1.4-§1.8).

Per motor: PWM -> command with a slew limit (and the rotor lag, TLM_ROTOR_TC), thrust from
momentum theory with inflow, rotor reaction (yaw) torque, per-motor momentum drag and
current. Frame sum: total body force (thrust, momentum drag, parasitic body drag) and torque.
All vectors are body FRD; every motor's thrust axis is body -z.
"""

from __future__ import annotations

import math

import numpy as np

from tlm_sim._jit import tick_jit
from tlm_sim.dynamics import layout as X
from tlm_sim.dynamics.frame import (
    F_AREA_CD,
    F_AREA_EFF,
    F_AREA_TRUE,
    F_DIAG,
    F_DISC_AREA,
    F_EXPO,
    F_MAX_VOLT,
    F_MDRAG_COEF,
    F_MOT_X,
    F_MOT_Y,
    F_MOT_YAW,
    F_N_MOTORS,
    F_POWER_FACTOR,
    F_PROFILE,
    F_PWM_HI,
    F_PWM_LO,
    F_ROTOR_ALPHA,
    F_ROTOR_RND_B,
    F_SLEW_MAX,
    F_VEL_MAX,
)

#: paper-era rotor torque per unit command and voltage scale [N m] (radians(40))
PAPER_YAW_SCALE: float = math.radians(40.0)


@tick_jit
def slew_command(pwm: float, last: float, pwm_lo: float, per_us: float, step: float,
                 lag: float = 1.0) -> float:
    """Motor command 0..1 for ``pwm`` [us] (SITL ``pwm_to_command``: ``(pwm - pwm_lo) *
    per_us`` clamped, ``per_us = 1 / (pwm_hi - pwm_lo)``), moved from ``last`` by the rotor
    lag's per-step gain ``lag`` (TLM_ROTOR_TC; 1: no lag, SITL) and rate limited to ``step``
    (``step = slew_max * dt``; no limit when 0)."""
    a = min(max((pwm - pwm_lo) * per_us, 0.0), 1.0)
    if lag < 1.0:
        a = last + (a - last) * lag
    if step > 0.0:
        a = min(max(a, last - step), last + step)
    return a


@tick_jit
def motor_forces(
    x: np.ndarray, pwm: np.ndarray, frame: np.ndarray, dt: float
) -> tuple[float, float, float, float, float, float, float]:
    """Advance the motor commands and return the frame's total force and torque.

    Reads the body rates ``W*``, body airspeed ``VAIR_*``, air density ``RHO`` and battery
    voltage ``BATT_V`` from ``x``; ``pwm[0..n-1]`` are motors 1..n [us] (n = ``F_N_MOTORS``).
    Writes the slewed commands ``M1..Mn`` and the thrusts ``T1..Tn`` [N] into ``x``.

    Returns ``(fx, fy, fz, tx, ty, tz, current)``: body force [N] (thrust, momentum drag and
    parasitic drag, gravity excluded), body torque [N m] and total motor current [A].
    """
    rho = x[X.RHO]
    wx, wy, wz = x[X.WX], x[X.WY], x[X.WZ]
    vax, vay, vaz = x[X.VAIR_X], x[X.VAIR_Y], x[X.VAIR_Z]
    volt = x[X.BATT_V]
    vscale = volt / frame[F_MAX_VOLT]
    dead = vscale < 0.1
    paper = frame[F_PROFILE] >= 0.5
    expo = frame[F_EXPO]
    # thrust = k_thr * (s^2 v_max^2 g(a) - v_in^2), k_thr = rho A_e / 2
    k_thr = 0.5 * rho * frame[F_AREA_EFF]
    vout2_full = (vscale * frame[F_VEL_MAX]) ** 2
    k_mom = frame[F_MDRAG_COEF] * math.sqrt(rho * frame[F_AREA_TRUE])
    k_yaw = 0.05 * frame[F_DIAG]
    k_cur = frame[F_POWER_FACTOR] / max(volt, 0.1)

    fx = 0.0
    fy = 0.0
    fz = 0.0
    tx = 0.0
    ty = 0.0
    tz = 0.0
    thrust_sum = 0.0
    current = 0.0
    pwm_lo = frame[F_PWM_LO]
    per_us = 1.0 / (frame[F_PWM_HI] - pwm_lo)
    step = frame[F_SLEW_MAX] * dt
    lag = frame[F_ROTOR_ALPHA]
    unsteady = frame[F_ROTOR_RND_B] > 0.0
    for i in range(int(frame[F_N_MOTORS])):
        a = slew_command(pwm[i], x[X.M1 + i], pwm_lo, per_us, step, lag)
        x[X.M1 + i] = a
        if dead:
            x[X.T1 + i] = 0.0
            continue
        rx = frame[F_MOT_X + i]
        ry = frame[F_MOT_Y + i]
        # air velocity at the motor: v_air_b + w x r (r_z = 0)
        vmx = vax - wz * ry
        vmy = vay + wz * rx
        vmz = vaz + wx * ry - wy * rx
        v_in = -vmz if vmz < 0.0 else 0.0
        thrust = k_thr * (vout2_full * ((1.0 - expo) * a + expo * a * a) - v_in * v_in)
        if unsteady:
            thrust *= 1.0 + x[X.ROTOR_RND + i]  # TLM_ROTOR_RND: the rotor in disturbed air
        x[X.T1 + i] = thrust
        thrust_sum += thrust
        # r x (0, 0, -T) = (-r_y T, r_x T, 0)
        tx -= ry * thrust
        ty += rx * thrust
        if paper:
            tz += frame[F_MOT_YAW + i] * a * PAPER_YAW_SCALE * vscale
        else:
            tz += frame[F_MOT_YAW + i] * a * k_yaw * thrust
            # per-motor momentum drag: thrust vector (0, 0, -T) has only a z component. It acts
            # at the motor, so it adds r x D to the torque (SITL sums r_i x F_i with the drag in
            # F_i): with w x r in v_m this damps the body rates, ~1.9 /s on every axis for the
            # default frame at hover (normal_s11: yaw acceleration = 2.0 deg/s^2 per us of
            # differential PWM - 1.92 /s x yaw rate, fitted on the cruise IMU and RCOU data)
            kd = k_mom * math.sqrt(abs(thrust))
            dx = kd * vmx
            dy = kd * vmy
            dz = kd * vmz
            fx -= dx
            fy -= dy
            fz -= dz
            # r x (-D) with r = (rx, ry, 0)
            tx -= ry * dz
            ty += rx * dz
            tz -= rx * dy - ry * dx
        current += k_cur * abs(thrust)
    fz -= thrust_sum

    # parasitic body drag, quadratic with sign
    k_body = frame[F_AREA_CD] * 0.5 * rho
    fx -= k_body * vax * abs(vax)
    fy -= k_body * vay * abs(vay)
    fz -= k_body * vaz * abs(vaz)
    if paper and not dead:
        # paper era: frame-level momentum drag, linear in airspeed
        km = frame[F_MDRAG_COEF] * math.sqrt(abs(thrust_sum) * rho * frame[F_DISC_AREA])
        fx -= km * vax
        fy -= km * vay
        fz -= km * vaz
    return fx, fy, fz, tx, ty, tz, current
