"""Rigid-body step of SITL's multicopter: one 1200 Hz physics tick (ardupilot-reference.md §1.9).

Sequence of :func:`physics_step`: wind -> body airspeed and air density -> motors and frame
sum (plus SIM_SHOVE / SIM_TWIST while they run) -> semi-implicit Euler (rates first, attitude
with the new rates, then velocity and position) -> accelerometer specific force -> ground
contact -> battery -> the sensors' view of the truth (SITL's sensor smoothing,
:mod:`tlm_sim.dynamics.smoothing`).

Differences from SITL, on purpose:

* attitude is a unit quaternion (body -> NED) advanced with the exact exponential of the
  body rate over the step and renormalised, instead of a first-order DCM update;
* with ``F_GYRO = 1`` (``TLM_GYRO_CPL`` 1; the default 0 drops it, as SITL does) the
  gyroscopic term ``-w x (I w)`` is included, integrated by rotating the body angular momentum
  with the same rotation as the attitude, so that a torque-free body keeps its earth-frame
  angular momentum exactly. Off by default because it changes how a copter tumbles after a
  motor loss: with it, tlm's copter landed ~60 deg further round than SITL's and hopped on
  its three motors where SITL's lies still (docs/fidelity-faults.md, "Engine fault on the
  ground");
* the body airspeed is recomputed at the start of the tick from the current wind.
"""

from __future__ import annotations

import math

import numpy as np

from tlm_sim._jit import inline_jit, loop_jit, tick_jit
from tlm_sim.dynamics import layout as X
from tlm_sim.dynamics.atmosphere import GRAVITY_MSS, air_density, air_density_gradient
from tlm_sim.dynamics.battery import init_battery, update_battery
from tlm_sim.dynamics.frame import (
    F_FRAME_HEIGHT,
    F_GYRO,
    F_HOME_ALT,
    F_IXX,
    F_IYY,
    F_IZZ,
    F_MASS,
    F_N_MOTORS,
    F_ROT_DAMP,
    F_ROTOR_RND_A,
    F_ROTOR_RND_B,
    F_SHOVE,
    F_SHOVE_TIME,
    F_TWIST,
    F_TWIST_TIME,
)
from tlm_sim.dynamics.kinematics import step_translation
from tlm_sim.dynamics.motors import motor_forces
from tlm_sim.dynamics.smoothing import smooth_sensors, smoothing_reset
from tlm_sim.dynamics.wind import init_wind, update_wind
from tlm_sim.rng import normal_pair
from tlm_sim.rotation import quat_mul_normalised, quat_to_dcm, rotation_half_angle

#: body-rate limit per axis [rad/s] (2000 deg/s)
GYRO_LIMIT: float = math.radians(2000.0)
#: specific-force limit per axis [m/s^2] (64 g)
ACCEL_LIMIT: float = 64.0 * GRAVITY_MSS
#: height above ground below which the vehicle counts as on the ground [m]
GROUND_EPS_M: float = 0.001
#: minimum time between two recorded ground impacts [s]
IMPACT_HOLDOFF_S: float = 1.0
#: the air density is interpolated linearly within this distance of its anchor altitude [m]
#: (relative error below 1e-7, against a pow() per tick)
RHO_SPAN_M: float = 5.0


@tick_jit
def _clamp(v: float, lim: float) -> float:
    if v > lim:
        return lim
    if v < -lim:
        return -lim
    return v


@tick_jit
def update_air_density(x: np.ndarray, frame: np.ndarray) -> None:
    """Set ``RHO`` to the air density at the vehicle, altitude ``home_alt - PD`` [m AMSL].

    The 1976 atmosphere is evaluated at an anchor altitude and interpolated linearly within
    RHO_SPAN_M of it; the anchor moves when the vehicle leaves that span.
    """
    alt = frame[F_HOME_ALT] - x[X.PD]
    dh = alt - x[X.RHO_ALT]
    if dh > RHO_SPAN_M or dh < -RHO_SPAN_M or x[X.RHO_ANCHOR] <= 0.0:
        x[X.RHO_ALT] = alt
        x[X.RHO_ANCHOR] = air_density(alt)
        x[X.RHO_GRAD] = air_density_gradient(alt)
        dh = 0.0
    x[X.RHO] = x[X.RHO_ANCHOR] + x[X.RHO_GRAD] * dh


@tick_jit
def height_above_ground(x: np.ndarray, frame: np.ndarray) -> float:
    """Height of the ground-contact point above home ground [m] (0 when resting)."""
    return -x[X.PD] - frame[F_FRAME_HEIGHT]


@tick_jit
def set_yaw_level(x: np.ndarray, yaw_rad: float) -> None:
    """Set the attitude to level with heading ``yaw_rad`` [rad]."""
    x[X.QW] = math.cos(0.5 * yaw_rad)
    x[X.QX] = 0.0
    x[X.QY] = 0.0
    x[X.QZ] = math.sin(0.5 * yaw_rad)


@tick_jit
def yaw_of(x: np.ndarray) -> float:
    """Heading [rad] of the attitude quaternion in ``x`` (ZYX Euler yaw)."""
    qw, qx, qy, qz = x[X.QW], x[X.QX], x[X.QY], x[X.QZ]
    return math.atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))


@tick_jit
def init_state(x: np.ndarray, frame: np.ndarray, yaw_rad: float) -> None:
    """Initialise ``x`` to a vehicle resting on the pad at home, motors stopped, facing yaw.

    Position (0, 0, -frame_height), zero velocity and rates, level attitude with heading
    ``yaw_rad`` [rad], accelerometer reading (0, 0, -g), battery full at SIM_BATT_VOLTAGE,
    no wind.
    """
    for i in range(x.shape[0]):
        x[i] = 0.0
    x[X.PD] = -frame[F_FRAME_HEIGHT]
    set_yaw_level(x, yaw_rad)
    x[X.FZ] = -GRAVITY_MSS
    x[X.ON_GROUND] = 1.0
    x[X.TIME_LAST_AIRBORNE] = 0.0
    update_air_density(x, frame)
    init_battery(x, frame)
    init_wind(x, frame)
    smoothing_reset(x)


@tick_jit
def set_airborne(x: np.ndarray, frame: np.ndarray, height_m: float, command: float) -> None:
    """Put the vehicle ``height_m`` [m] above ground, at rest, motors settled at ``command``.

    For tests and for flights that start in the air; call after :func:`init_state`.
    """
    x[X.PD] = -frame[F_FRAME_HEIGHT] - height_m
    x[X.ON_GROUND] = 0.0
    x[X.TIME_LAST_AIRBORNE] = -1.0e9
    for i in range(int(frame[F_N_MOTORS])):
        x[X.M1 + i] = command
    x[X.RHO_ANCHOR] = 0.0
    update_air_density(x, frame)
    smoothing_reset(x)


@tick_jit
def _one_shot(x: np.ndarray, frame: np.ndarray, slot_ms: int, slot_t: int, dt: float) -> bool:
    """SITL's one-shot SIM_SHOVE / SIM_TWIST timer (sitl-faults.md §6.2): True while the
    push acts this tick. It starts at the first tick after ``frame[slot_t]`` [ms] becomes
    non-zero and acts while the time it has run (``x[slot_ms]``) is below it; then the
    simulator sets the parameter back to 0 (the X/Y/Z values stay)."""
    dur = frame[slot_t]
    if dur <= 0.0:
        x[slot_ms] = 0.0
        return False
    if x[slot_ms] < dur:
        x[slot_ms] += dt * 1000.0
        return True
    x[slot_ms] = 0.0
    frame[slot_t] = 0.0
    return False


@inline_jit
def _disturbances(x: np.ndarray, frame: np.ndarray, dt: float
                  ) -> tuple[float, float, float, float, float, float]:
    """This tick's SIM_TWIST angular acceleration [rad/s^2] and SIM_SHOVE specific force
    [m/s^2], body axes (zeros when neither runs)."""
    twx = twy = twz = shx = shy = shz = 0.0
    if frame[F_TWIST_TIME] > 0.0 or x[X.TWIST_MS] > 0.0:
        if _one_shot(x, frame, X.TWIST_MS, F_TWIST_TIME, dt):
            twx, twy, twz = frame[F_TWIST], frame[F_TWIST + 1], frame[F_TWIST + 2]
    if frame[F_SHOVE_TIME] > 0.0 or x[X.SHOVE_MS] > 0.0:
        if _one_shot(x, frame, X.SHOVE_MS, F_SHOVE_TIME, dt):
            shx, shy, shz = frame[F_SHOVE], frame[F_SHOVE + 1], frame[F_SHOVE + 2]
    return twx, twy, twz, shx, shy, shz


@inline_jit
def _rotor_noise(x: np.ndarray, frame: np.ndarray, rng: np.ndarray) -> None:
    """One physics step of the rotors' thrust fluctuation (TLM_ROTOR_RND > 0): per rotor a
    first-order Gauss-Markov fraction n <- a n + b N(0, 1) (a = exp(-dt / TLM_ROTOR_RND_TC),
    b = sqrt(1 - a^2) TLM_ROTOR_RND), so each rotor's thrust is (1 + n) times its steady one
    (motors.motor_forces). Drawn from the airframe's generator (the wind's)."""
    a = frame[F_ROTOR_RND_A]
    b = frame[F_ROTOR_RND_B]
    n = int(frame[F_N_MOTORS])
    for i in range(0, n, 2):
        n0, n1 = normal_pair(rng)
        x[X.ROTOR_RND + i] = a * x[X.ROTOR_RND + i] + b * n0
        if i + 1 < n:
            x[X.ROTOR_RND + i + 1] = a * x[X.ROTOR_RND + i + 1] + b * n1


@inline_jit
def _ground_contact(x: np.ndarray, fh: float, was_on_ground: bool, vd: float,
                    t_s: float) -> None:
    """Ground contact (SITL's NO_MOVEMENT behaviour) after a step: on the ground (frame height
    fh [m]) the copter sits level at its yaw, at rest (a downward velocity vd [m/s] cleared);
    landing on it after IMPACT_HOLDOFF_S airborne counts an impact at vd."""
    if -x[X.PD] - fh <= GROUND_EPS_M:
        if not was_on_ground and t_s - x[X.TIME_LAST_AIRBORNE] > IMPACT_HOLDOFF_S:
            x[X.IMPACT_SPEED] = vd
            x[X.IMPACT_COUNT] += 1.0
            x[X.TIME_LAST_AIRBORNE] = t_s
        x[X.PD] = -fh
        if x[X.QX] != 0.0 or x[X.QY] != 0.0:
            set_yaw_level(x, yaw_of(x))
        x[X.VN] = 0.0
        x[X.VE] = 0.0
        if vd > 0.0:
            x[X.VD] = 0.0
        x[X.WX] = 0.0
        x[X.WY] = 0.0
        x[X.WZ] = 0.0
        x[X.ON_GROUND] = 1.0
    else:
        x[X.ON_GROUND] = 0.0


@tick_jit
def physics_step(x: np.ndarray, pwm: np.ndarray, frame: np.ndarray, dt: float, t_s: float,
                 rng: np.ndarray) -> None:
    """Advance the truth state ``x`` by one physics tick of ``dt`` [s] (in place).

    ``pwm[0..3]``: motor 1..4 PWM [us] as the motors see it (after any SIM_ENGINE_* fault
    transform). ``t_s``: simulated time since boot at the start of the tick [s] (wind start
    delay and slew-filter cadence, ground impact hold-off). ``rng``: the airframe's
    generator state (:mod:`tlm_sim.rng`): the wind's turbulence and the rotors' fluctuation.
    Allocation-free.
    """
    g = GRAVITY_MSS
    # --- environment -------------------------------------------------------------------
    update_wind(x, frame, t_s, rng)
    update_air_density(x, frame)

    qw, qx, qy, qz = x[X.QW], x[X.QX], x[X.QY], x[X.QZ]
    # DCM body -> NED of the current attitude
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = quat_to_dcm(qw, qx, qy, qz)
    an = x[X.VN] - x[X.WIND_N]
    ae = x[X.VE] - x[X.WIND_E]
    ad = x[X.VD] - x[X.WIND_D]
    x[X.VAIR_X] = r00 * an + r10 * ae + r20 * ad
    x[X.VAIR_Y] = r01 * an + r11 * ae + r21 * ad
    x[X.VAIR_Z] = r02 * an + r12 * ae + r22 * ad

    # --- forces and torques --------------------------------------------------------------
    if frame[F_ROTOR_RND_B] > 0.0:
        _rotor_noise(x, frame, rng)
    fx, fy, fz, tx, ty, tz, current = motor_forces(x, pwm, frame, dt)
    ixx, iyy, izz = frame[F_IXX], frame[F_IYY], frame[F_IZZ]
    rxx, ryy, rzz = 1.0 / ixx, 1.0 / iyy, 1.0 / izz  # three divisions instead of six
    damp = frame[F_ROT_DAMP]
    twx, twy, twz, shx, shy, shz = _disturbances(x, frame, dt)

    # --- rates (semi-implicit: rates first, attitude with the new rates) ---------------------
    wx = _clamp(x[X.WX] + (tx * rxx - damp * x[X.WX] + twx) * dt, GYRO_LIMIT)
    wy = _clamp(x[X.WY] + (ty * ryy - damp * x[X.WY] + twy) * dt, GYRO_LIMIT)
    wz = _clamp(x[X.WZ] + (tz * rzz - damp * x[X.WZ] + twz) * dt, GYRO_LIMIT)

    # rotation over the step: dq = (c, u) = (cos(th/2), w_hat sin(th/2)), th = |w| dt
    c, k = rotation_half_angle(wx, wy, wz, dt)
    ux, uy, uz = k * wx, k * wy, k * wz
    qw, qx, qy, qz = quat_mul_normalised((qw, qx, qy, qz), (c, ux, uy, uz))
    x[X.QW], x[X.QX], x[X.QY], x[X.QZ] = qw, qx, qy, qz

    if frame[F_GYRO] >= 0.5:
        # gyroscopic coupling: body angular momentum rotates by -th about w_hat
        lx, ly, lz = ixx * wx, iyy * wy, izz * wz
        cx = uy * lz - uz * ly
        cy = uz * lx - ux * lz
        cz = ux * ly - uy * lx
        ccx = uy * cz - uz * cy
        ccy = uz * cx - ux * cz
        ccz = ux * cy - uy * cx
        wx = (lx - 2.0 * c * cx + 2.0 * ccx) * rxx
        wy = (ly - 2.0 * c * cy + 2.0 * ccy) * ryy
        wz = (lz - 2.0 * c * cz + 2.0 * ccz) * rzz
    x[X.WX], x[X.WY], x[X.WZ] = wx, wy, wz

    # --- translation -------------------------------------------------------------------
    rm = 1.0 / frame[F_MASS]
    bx = _clamp(fx * rm + shx, ACCEL_LIMIT)
    by = _clamp(fy * rm + shy, ACCEL_LIMIT)
    bz = _clamp(fz * rm + shz, ACCEL_LIMIT)
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = quat_to_dcm(qw, qx, qy, qz)
    aen = r00 * bx + r01 * by + r02 * bz
    aee = r10 * bx + r11 * by + r12 * bz
    aed = r20 * bx + r21 * by + r22 * bz + g
    fh = frame[F_FRAME_HEIGHT]
    was_on_ground = -x[X.PD] - fh <= GROUND_EPS_M
    if was_on_ground and aed > 0.0:
        aed = 0.0  # the ground pushes back
    x[X.AN], x[X.AE], x[X.AD] = aen, aee, aed
    # what an ideal accelerometer senses: R^T (a_e - g)
    sd = aed - g
    x[X.FX] = r00 * aen + r10 * aee + r20 * sd
    x[X.FY] = r01 * aen + r11 * aee + r21 * sd
    x[X.FZ] = r02 * aen + r12 * aee + r22 * sd

    _, _, vd = step_translation(x, X.PN, aen, aee, aed, dt)

    _ground_contact(x, fh, was_on_ground, vd, t_s)

    # --- battery ------------------------------------------------------------------------
    update_battery(x, frame, current, dt)

    # --- what the sensors see ------------------------------------------------------------
    smooth_sensors(x, dt)


@loop_jit
def run_ticks(
    x: np.ndarray, pwm: np.ndarray, frame: np.ndarray, dt: float, t_s: float, n: int,
    rng: np.ndarray,
) -> float:
    """Run ``n`` physics ticks of ``dt`` [s] with constant ``pwm`` from time ``t_s`` [s]
    (``rng``: the wind's generator state, see :func:`physics_step`).

    Returns the simulated time after the last tick [s]. For tests, benchmarks and open-loop
    experiments; the flight loop calls :func:`physics_step` itself.
    """
    for _ in range(n):
        physics_step(x, pwm, frame, dt, t_s, rng)
        t_s += dt
    return t_s
