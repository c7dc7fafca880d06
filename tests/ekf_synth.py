"""Synthetic flights for the EKF tests: analytic truth trajectory and SITL-like sensor samples.

Truth (NED, body FRD): rest on the ground, smooth climb to 15 m, then a figure-eight at up to
about 6 m/s (banked turns both ways) with climbs/descents and a slowly varying heading. The IMU
deltas are exact kinematic increments of that truth plus SITL's base noise (accel 0.01 m/s^2,
gyro 0.04 deg/s uniform) and a constant gyro bias; GPS at 5 Hz lagged 0.1 s without position
noise; baro and compass at 10 Hz.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from tlm_sim.bundles import EkfInputs
from tlm_sim.ekf import layout as L
from tlm_sim.ekf.lanes import ekf_output, ekf_update
from tlm_sim.sensors.mag import healthy_compasses

G = 9.80665
DT = 0.0025  # main loop [s]


def _smooth(u: np.ndarray) -> np.ndarray:
    """Smootherstep 0 -> 1 on u in [0, 1] (C2)."""
    u = np.clip(u, 0.0, 1.0)
    return u * u * u * (u * (6.0 * u - 15.0) + 10.0)


def _smooth_int(u: np.ndarray) -> np.ndarray:
    """Integral of the smootherstep from 0 to u (u may exceed 1)."""
    c = np.clip(u, 0.0, 1.0)
    base = c**6 - 3.0 * c**5 + 2.5 * c**4
    return base + np.maximum(u - 1.0, 0.0)


def truth_position(t: np.ndarray) -> np.ndarray:
    """Position NED [m] at times t [s], shape (n, 3)."""
    h = 15.0 * _smooth((t - 8.0) / 8.0) + 5.0 * _smooth((t - 40.0) / 6.0)
    h -= 5.0 * _smooth((t - 70.0) / 6.0)
    amp = 40.0
    omega = 6.0 / (amp * math.sqrt(2.0))  # peak speed about 6 m/s
    ramp = 6.0
    phase = omega * ramp * _smooth_int((t - 18.0) / ramp)
    n = amp * np.sin(phase)
    e = 0.5 * amp * np.sin(2.0 * phase)
    return np.stack([n, e, -h], axis=1)


def truth_yaw(t: np.ndarray) -> np.ndarray:
    """Heading [rad]: constant on the ground, slowly varying in flight."""
    s = _smooth((t - 8.0) / 4.0)
    return 0.3 + s * (1.2 * np.sin(0.05 * (t - 8.0)) + 0.3 * np.sin(0.23 * (t - 8.0)))


def _vel_acc(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    ev = 1e-4
    ea = 1e-3
    v = (truth_position(t + ev) - truth_position(t - ev)) / (2.0 * ev)
    p0 = truth_position(t)
    a = (truth_position(t + ea) - 2.0 * p0 + truth_position(t - ea)) / (ea * ea)
    return v, a


def _rot_from_acc_yaw(a: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """Body -> NED rotation matrices (n, 3, 3): thrust axis opposite the specific force."""
    f = a - np.array([0.0, 0.0, G])
    zb = -f / np.linalg.norm(f, axis=1, keepdims=True)
    xc = np.stack([np.cos(yaw), np.sin(yaw), np.zeros_like(yaw)], axis=1)
    yb = np.cross(zb, xc)
    yb /= np.linalg.norm(yb, axis=1, keepdims=True)
    xb = np.cross(yb, zb)
    return np.stack([xb, yb, zb], axis=2)


def rot_to_quat(r: np.ndarray) -> np.ndarray:
    """Quaternions (w, x, y, z) of rotation matrices (n, 3, 3), sign-continuous."""
    n = r.shape[0]
    q = np.empty((n, 4))
    tr = r[:, 0, 0] + r[:, 1, 1] + r[:, 2, 2]
    q[:, 0] = 0.5 * np.sqrt(np.maximum(1.0 + tr, 1e-12))
    q[:, 1] = (r[:, 2, 1] - r[:, 1, 2]) / (4.0 * q[:, 0])
    q[:, 2] = (r[:, 0, 2] - r[:, 2, 0]) / (4.0 * q[:, 0])
    q[:, 3] = (r[:, 1, 0] - r[:, 0, 1]) / (4.0 * q[:, 0])
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product of quaternion arrays (n, 4)."""
    aw, ax, ay, az = a.T
    bw, bx, by, bz = b.T
    return np.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=1,
    )


def quat_conj(q: np.ndarray) -> np.ndarray:
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def quat_angle_deg(q1: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """Rotation angle [deg] between quaternion arrays (n, 4)."""
    d = np.abs(np.sum(q1 * q2, axis=1))
    return np.degrees(2.0 * np.arccos(np.clip(d, 0.0, 1.0)))


def _rotvec(q: np.ndarray) -> np.ndarray:
    q = np.where(q[:, :1] < 0.0, -q, q)
    s = np.linalg.norm(q[:, 1:], axis=1)
    ang = 2.0 * np.arctan2(s, q[:, 0])
    k = np.where(s > 1e-15, ang / np.maximum(s, 1e-300), 2.0)
    return q[:, 1:] * k[:, None]


@dataclass
class Flight:
    """Per-tick inputs for the EKF and the truth to compare against (arrays over n ticks)."""

    t_us: np.ndarray
    dang: np.ndarray  # (n, 2, 3)
    dvel: np.ndarray  # (n, 2, 3)
    imu_ok: np.ndarray  # (n, 2)
    gps_new: np.ndarray  # (n,)
    gps_pos: np.ndarray  # (n, 3)
    gps_vel: np.ndarray  # (n, 3)
    gps_fix: np.ndarray  # (n,)
    baro_new: np.ndarray
    baro: np.ndarray
    mag_new: np.ndarray
    mag: np.ndarray  # (n, N_MAG * MAG_STRIDE): the compass block (sensors.layout MAG records)
    armed: np.ndarray
    pos: np.ndarray  # truth at each tick (n, 3)
    vel: np.ndarray
    quat: np.ndarray  # (n, 4)
    gyro_bias: np.ndarray  # (2, 3) [rad/s]


def make_flight(
    duration: float = 100.0,
    seed: int = 0,
    gps_lag: float = 0.1,
    gyro_bias_deg: tuple[float, float, float] = (0.3, -0.2, 0.4),
    mag_earth: np.ndarray | None = None,
) -> Flight:
    """Synthetic flight sampled at the 400 Hz main loop (tick k ends at t = (k + 1) * DT)."""
    rng = np.random.default_rng(seed)
    n = int(round(duration / DT))
    tk = np.arange(n + 1) * DT  # tick boundaries
    tm = tk[:-1] + 0.5 * DT  # midpoints
    v_k, a_k = _vel_acc(tk)
    _, a_m = _vel_acc(tm)
    r_k = _rot_from_acc_yaw(a_k, truth_yaw(tk))
    r_m = _rot_from_acc_yaw(a_m, truth_yaw(tm))
    q_k = rot_to_quat(r_k)
    dq = quat_mul(quat_conj(q_k[:-1]), q_k[1:])
    dang_true = _rotvec(dq)
    dv_n = v_k[1:] - v_k[:-1] - np.array([0.0, 0.0, G * DT])
    dvel_true = np.einsum("nji,nj->ni", r_m, dv_n)
    bias = np.radians(np.array(gyro_bias_deg))
    dang = np.empty((n, 2, 3))
    dvel = np.empty((n, 2, 3))
    gyro_bias = np.empty((2, 3))
    for i in range(2):
        b = bias * (1.0 if i == 0 else -0.5)
        gyro_bias[i] = b
        dang[:, i] = dang_true + (b + math.radians(0.04) * rng.uniform(-1, 1, (n, 3))) * DT
        dvel[:, i] = dvel_true + 0.01 * rng.uniform(-1, 1, (n, 3)) * DT
    t_end = tk[1:]
    t_us = np.round(t_end * 1e6).astype(np.int64)
    k_idx = np.arange(n)
    gps_new = ((k_idx + 1) % 80 == 0) & (t_end >= 2.0)
    gps_t = t_end - gps_lag
    gps_pos = truth_position(gps_t)
    gps_vel, _ = _vel_acc(gps_t)
    gps_fix = gps_new.copy()
    baro_new = (k_idx + 1) % 40 == 0
    p_k = truth_position(t_end)
    baro = -p_k[:, 2] + 0.1 * rng.uniform(-1, 1, n)
    mag_new = (k_idx + 1) % 40 == 20
    if mag_earth is None:  # the field the EKF assumes
        from tlm_sim.params import Params, earth_field

        mag_earth = earth_field(Params())
    field = np.einsum("nji,j->ni", r_k[1:], mag_earth) + 0.005 * rng.uniform(-1, 1, (n, 3))
    mag = np.array([healthy_compasses(f) for f in field])  # the compass block per tick
    return Flight(
        t_us=t_us,
        dang=dang,
        dvel=dvel,
        imu_ok=np.ones((n, 2)),
        gps_new=gps_new,
        gps_pos=gps_pos,
        gps_vel=gps_vel,
        gps_fix=gps_fix,
        baro_new=baro_new,
        baro=baro,
        mag_new=mag_new,
        mag=mag,
        armed=(t_end >= 10.0),
        pos=p_k,
        vel=v_k[1:],
        quat=q_k[1:],
        gyro_bias=gyro_bias,
    )


@njit(nogil=True)  # not cached: a cached caller would keep stale copies of the EKF kernels
def run_ekf(
    ekf, sel, cfg, t_us, dang, dvel, imu_ok, gps_new, gps_pos, gps_vel, gps_fix,
    baro_new, baro, mag_new, mag, armed, out, lanes_pos
):  # fmt: skip
    """Run the EKF over all ticks; out[k] = ekf_output after tick k, lanes_pos[k, lane, 0:3]."""
    n = t_us.shape[0]
    o = np.zeros(L.N_OUT)
    for k in range(n):
        ekf_update(ekf, sel, cfg, t_us[k], EkfInputs(
            dang[k], dvel[k], imu_ok[k],
            gps_new[k], gps_pos[k], gps_vel[k], gps_fix[k],
            baro_new[k], baro[k], mag_new[k], mag[k], armed[k],
        ))  # fmt: skip
        ekf_output(ekf, sel, o)
        for j in range(L.N_OUT):
            out[k, j] = o[j]
        for ln in range(ekf.shape[0]):
            for j in range(3):
                lanes_pos[k, ln, j] = ekf[ln, L.PN + j]


def fly_ekf(flight: Flight, ekf: np.ndarray, sel: np.ndarray, cfg: np.ndarray):
    """Run :func:`run_ekf` over a :class:`Flight`; returns (out[n, N_OUT], lanes_pos)."""
    n = flight.t_us.shape[0]
    out = np.zeros((n, L.N_OUT))
    lanes_pos = np.zeros((n, ekf.shape[0], 3))
    run_ekf(
        ekf, sel, cfg, flight.t_us, flight.dang, flight.dvel, flight.imu_ok,
        flight.gps_new, flight.gps_pos, flight.gps_vel, flight.gps_fix,
        flight.baro_new, flight.baro, flight.mag_new, flight.mag, flight.armed,
        out, lanes_pos,
    )  # fmt: skip
    return out, lanes_pos
