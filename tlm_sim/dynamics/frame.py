"""Frame constants of SITL's "+" quad: the model table, the derived constants and PWM helpers.

A flight's frame is ONE float64 array indexed by the ``F_*`` constants below, built once per
flight by :func:`build_frame` from a :class:`~tlm_sim.params.Params` (ArduPilot SITL names
``SIM_*`` plus ``TLM_*`` names for the model struct of ``SIM_Frame.h``; their defaults live in
``tlm_sim.params`` only). It holds the
model values, the constants ``Frame::init`` derives from them (ardupilot-reference.md §1.3),
the motor table and the environment parameters the physics reads (wind, battery, home
altitude). Entries marked *live* may be rewritten by the flight loop while flying (a fault
schedule changing ``SIM_WIND_*`` or ``SIM_BATT_VOLTAGE``); the rest are constants.

The motor table comes from :mod:`tlm_sim.frames` (the frame of ``FRAME_CLASS`` /
``FRAME_TYPE``): ``F_N_MOTORS`` motors, ArduPilot numbering 1..n -> array index 0..n-1, each
with its arm position ``TLM_DIAG (cos theta, sin theta)`` [m, body FRD] and yaw factor (+1
counter-clockwise propeller, -1 clockwise). The "+" quad (FRAME_TYPE 0):

===== ======== ======================= ===== ==========
motor servo    position (unit of diag) spin  yaw factor
===== ======== ======================= ===== ==========
1     SERVO1   (0, +1) right arm       CCW   +1
2     SERVO2   (0, -1) left arm        CCW   +1
3     SERVO3   (+1, 0) front arm       CW    -1
4     SERVO4   (-1, 0) back arm        CW    -1
===== ======== ======================= ===== ==========

The X quad (FRAME_TYPE 1) has motor 1 front-right (45 deg, CCW), 2 back-left (-135 deg, CCW),
3 front-left (-45 deg, CW), 4 back-right (135 deg, CW).
"""

from __future__ import annotations

import math

import numpy as np

from tlm_sim import ardupilot as AP
from tlm_sim._jit import tick_jit
from tlm_sim.dynamics.atmosphere import GRAVITY_MSS, air_density
from tlm_sim.frames import MAX_MOTORS, FrameLayout, frame_for
from tlm_sim.params import Params, require_params
from tlm_sim.slots import Layout

#: the physics step [s] (833 us, SITL's 1200 Hz), for the per-step filter gains
PHYSICS_DT_S = (1_000_000 // AP.SIM_RATE_HZ) * 1e-6

#: the frame configuration array (:func:`build_frame`), declared once
FRAME = Layout("frame", "airframe, motor, environment and battery configuration of the physics")
_f = FRAME
# ---- model values (SIM_Frame.h struct Model) --------------------------------------------
F_MASS = _f.add("F_MASS", 1, "kg", "vehicle mass")
F_DIAG = _f.add("F_DIAG", 1, "m", "diagonal_size, used as the motor arm length")
F_HOVER_THR = _f.add("F_HOVER_THR", 1, "", "hoverThrOut, hover thrust fraction")
F_EXPO = _f.add("F_EXPO", 1, "", "propExpo, thrust curve expo")
F_PWM_MIN, F_PWM_MAX = _f.vector(("F_PWM_MIN", "F_PWM_MAX"), "us",
                                 "reference MOT_PWM_MIN / MOT_PWM_MAX")
F_SPIN_MIN, F_SPIN_MAX = _f.vector(("F_SPIN_MIN", "F_SPIN_MAX"), "",
                                   "reference MOT_SPIN_MIN / MOT_SPIN_MAX")
F_SLEW_MAX = _f.add("F_SLEW_MAX", 1, "1/s", "max motor command rate (0 = no limit)")
F_ROTOR_ALPHA = _f.add("F_ROTOR_ALPHA", 1, "",
                       "per-physics-step gain 1 - exp(-dt / TLM_ROTOR_TC) of the rotor lag; 1 = "
                       "none (SITL)")
F_DISC_AREA = _f.add("F_DISC_AREA", 1, "m^2", "total rotor disc area")
F_MAX_VOLT = _f.add("F_MAX_VOLT", 1, "V", "full-pack voltage, voltage_scale = V / this")
F_FRAME_HEIGHT = _f.add("F_FRAME_HEIGHT", 1, "m",
                        "height of the CG above the ground when resting")
F_PROFILE = _f.add("F_PROFILE", 1, "",
                   "0 = current SITL models, 1 = paper era (yaw torque, frame momentum drag)")
F_GYRO = _f.add("F_GYRO", 1, "", "1 = include the gyroscopic term -w x (I w) (SITL omits it), "
                "0 = SITL-exact")
# ---- derived at start-up (Frame::init) --------------------------------------------------
F_RHO_REF = _f.add("F_RHO_REF", 1, "kg/m^3", "air density at refAlt")
F_D_REF = _f.add("F_D_REF", 1, "N", "drag at the reference test")
F_D_MOM = _f.add("F_D_MOM", 1, "N", "momentum drag at the reference test")
F_AREA_CD = _f.add("F_AREA_CD", 1, "m^2", "body drag area x Cd")
F_MDRAG_COEF = _f.add("F_MDRAG_COEF", 1, "", "momentum drag coefficient (possibly scaled down)")
F_HOVER_POWER = _f.add("F_HOVER_POWER", 1, "W", "P_h = refCurrent * refVoltage")
F_HOVER_VOUT = _f.add("F_HOVER_VOUT", 1, "m/s", "hover outflow speed v_h")
F_AREA_EFF = _f.add("F_AREA_EFF", 1, "m^2", "effective prop area per motor A_e")
F_AREA_TRUE = _f.add("F_AREA_TRUE", 1, "m^2", "true prop area per motor A_p")
F_VEL_MAX = _f.add("F_VEL_MAX", 1, "m/s", "max outflow speed v_max")
F_POWER_FACTOR = _f.add("F_POWER_FACTOR", 1, "W/N", "power per newton of thrust k_P")
F_IXX, F_IYY, F_IZZ = _f.vector(("F_IXX", "F_IYY", "F_IZZ"), "kg m^2",
                                "principal moments of inertia")
F_ROT_DAMP = _f.add("F_ROT_DAMP", 1, "1/s", "rotational air damping rate c_w")
F_PWM_LO, F_PWM_HI = _f.vector(("F_PWM_LO", "F_PWM_HI"), "us",
                               "PWM of command 0 and command 1")
F_HOVER_CMD = _f.add("F_HOVER_CMD", 1, "", "motor command a_h that gives hover thrust at "
                     "rho_ref and full voltage")
# ---- environment and battery (SIM_*); live entries may change in flight ------------------
F_HOME_ALT = _f.add("F_HOME_ALT", 1, "m", "SIM_OPOS_ALT, home ground altitude AMSL")
F_BATT_VOLT = _f.add("F_BATT_VOLT", 1, "V",
                     "SIM_BATT_VOLTAGE (live: a change re-initialises the battery)")
F_BATT_CAP_AH = _f.add("F_BATT_CAP_AH", 1, "Ah", "battery capacity, 0 = infinite")
F_BATT_RES = _f.add("F_BATT_RES", 1, "ohm", "battery internal resistance")
F_WIND_SPD = _f.add("F_WIND_SPD", 1, "m/s", "SIM_WIND_SPD (live)")
F_WIND_DIR = _f.add("F_WIND_DIR", 1, "deg",
                    "SIM_WIND_DIR, direction the wind comes FROM, true (live)")
F_WIND_TURB = _f.add("F_WIND_TURB", 1, "m/s", "SIM_WIND_TURB (live)")
F_WIND_TC = _f.add("F_WIND_TC", 1, "s", "SIM_WIND_TC (live)")
F_GUST_A = _f.add("F_GUST_A", 1, "",
                  "per-physics-step decay exp(-dt / TLM_TURB_TC) of the correlated gusts, 0 = "
                  "SITL's gusts (live)")
F_ROTOR_RND_A = _f.add("F_ROTOR_RND_A", 1, "",
                       "per-physics-step decay exp(-dt / TLM_ROTOR_RND_TC) of the rotors' thrust "
                       "fluctuation (live)")
F_ROTOR_RND_B = _f.add("F_ROTOR_RND_B", 1, "",
                       "its innovation sqrt(1 - a^2) TLM_ROTOR_RND, 0 = steady rotors (live)")
F_WIND_DIR_Z = _f.add("F_WIND_DIR_Z", 1, "deg",
                      "SIM_WIND_DIR_Z, vertical wind angle, 90 = updraft (live)")
F_WIND_T = _f.add("F_WIND_T", 1, "", "SIM_WIND_T: 0 square-root law, 1 none, 2 linear (live)")
F_WIND_T_ALT = _f.add("F_WIND_T_ALT", 1, "m", "SIM_WIND_T_ALT (live)")
F_WIND_T_COEF = _f.add("F_WIND_T_COEF", 1, "1/s", "SIM_WIND_T_COEF (live)")
F_REF_ALT = _f.add("F_REF_ALT", 1, "m", "refAlt AMSL")
# ---- airframe disturbances (SIM_SHOVE_*, SIM_TWIST_*, sitl-faults.md §6.2; live) ----------
F_SHOVE = _f.add("F_SHOVE", 3, "m/s^2", "SIM_SHOVE_X/Y/Z, extra body specific force")
F_SHOVE_TIME = _f.add("F_SHOVE_TIME", 1, "ms",
                      "SIM_SHOVE_TIME; the physics sets it back to 0 once elapsed")
F_TWIST = _f.add("F_TWIST", 3, "rad/s^2", "SIM_TWIST_X/Y/Z, extra body angular acceleration")
F_TWIST_TIME = _f.add("F_TWIST_TIME", 1, "ms",
                      "SIM_TWIST_TIME; the physics sets it back to 0 once elapsed")
# ---- SITL's servo interface: what the motors see of the autopilot's outputs --------------
F_ENGINE_MUL = _f.add("F_ENGINE_MUL", 1, "",
                      "SIM_ENGINE_MUL: PWM multiplier above 1000 us on the failed outputs")
F_ENGINE_MASK = _f.add("F_ENGINE_MASK", 1, "",
                       "SIM_ENGINE_FAIL as a bit mask of outputs (bit 0 = SERVO1 = motor 1)")
# ---- motor table (tlm_sim.frames; positions in metres, body FRD) --------------------------
F_N_MOTORS = _f.add("F_N_MOTORS", 1, "", "number of motors n (FRAME_CLASS / FRAME_TYPE)")
F_MOT_X = _f.add("F_MOT_X", MAX_MOTORS, "m",
                 "per output: motor x from the centre of gravity (the arm less TLM_CG_X; 0 "
                 "beyond n)")
F_MOT_Y = _f.add("F_MOT_Y", MAX_MOTORS, "m",
                 "per output: motor y from the centre of gravity (the arm less TLM_CG_Y)")
F_MOT_YAW = _f.add("F_MOT_YAW", MAX_MOTORS, "",
                   "per output: reaction-torque factor (+1 CCW, -1 CW; plus TLM_YAW_ASYM)")

N_FRAME = FRAME.close()

def _hover_command(hover_thr: float, expo: float) -> float:
    """Command ``a`` in [0, 1] solving ``(1 - e) a + e a^2 = hover_thr``."""
    if expo <= 0.0:
        return hover_thr
    b = 1.0 - expo
    return (-b + math.sqrt(b * b + 4.0 * expo * hover_thr)) / (2.0 * expo)


def build_frame(p: Params) -> np.ndarray:
    """Build the frame-constant array of one flight (run once per flight, in Python).

    Reads the ``TLM_*`` frame model and the ``SIM_*`` environment parameters of ``p`` (see
    ``tlm params TLM_`` for their units and defaults). ``SIM_BATT_CAP_AH`` overrides
    ``TLM_BATT_CAP_AH`` when it is positive (SITL sets the parameter's default to the model
    capacity). Returns a float64 array of length :data:`N_FRAME` indexed by the ``F_*``
    constants.
    """
    require_params(p, "build_frame")

    def get(name: str) -> float:
        return float(p[name])

    f = np.zeros(N_FRAME, dtype=np.float64)
    layout = frame_for(p["FRAME_CLASS"], p["FRAME_TYPE"])
    n_motors = layout.n_motors
    mass = get("TLM_MASS")
    diag = get("TLM_DIAG")
    hover_thr = get("TLM_HOVER_THR")
    expo = get("TLM_PROP_EXPO")
    f[F_MASS] = mass
    f[F_DIAG] = diag
    f[F_HOVER_THR] = hover_thr
    f[F_EXPO] = expo
    f[F_PWM_MIN] = get("TLM_PWM_MIN")
    f[F_PWM_MAX] = get("TLM_PWM_MAX")
    f[F_SPIN_MIN] = get("TLM_SPIN_MIN")
    f[F_SPIN_MAX] = get("TLM_SPIN_MAX")
    f[F_SLEW_MAX] = get("TLM_SLEW_MAX")
    tc = get("TLM_ROTOR_TC")
    f[F_ROTOR_ALPHA] = -math.expm1(-PHYSICS_DT_S / tc) if tc > 0.0 else 1.0
    f[F_DISC_AREA] = get("TLM_DISC_AREA")
    f[F_MAX_VOLT] = get("TLM_MAX_VOLT")
    f[F_FRAME_HEIGHT] = get("TLM_FRAME_HEIGHT")
    f[F_PROFILE] = get("TLM_PROFILE")
    f[F_GYRO] = get("TLM_GYRO_CPL")
    f[F_REF_ALT] = get("TLM_REF_ALT")

    # drag calibration from the reference test (lean refAngle at refSpd)
    g = GRAVITY_MSS
    theta = math.radians(get("TLM_REF_ANGLE"))
    rho_ref = air_density(f[F_REF_ALT])
    d_ref = mass * g * math.tan(theta)
    v_bx = get("TLM_REF_SPD") * math.cos(theta)
    t_ref = mass * g / math.cos(theta)
    mdrag = get("TLM_MDRAG_COEF")
    d_mom = math.cos(theta) * mdrag * v_bx * math.sqrt(t_ref * rho_ref * f[F_DISC_AREA])
    if d_mom > d_ref:
        mdrag *= d_ref / d_mom
        area_cd = 0.0
    else:
        ref_spd = get("TLM_REF_SPD")
        area_cd = (d_ref - d_mom) / (0.5 * rho_ref * ref_spd * ref_spd)
    f[F_RHO_REF] = rho_ref
    f[F_D_REF] = d_ref
    f[F_D_MOM] = d_mom
    f[F_AREA_CD] = area_cd
    f[F_MDRAG_COEF] = mdrag

    # momentum-theory motor constants from the hover reference
    t_hover = mass * g
    p_hover = get("TLM_REF_CURR") * get("TLM_REF_VOLT")
    v_h = 2.0 * p_hover / t_hover
    a_eff = t_hover / (0.5 * rho_ref * v_h * v_h)
    f[F_HOVER_POWER] = p_hover
    f[F_HOVER_VOUT] = v_h
    f[F_AREA_EFF] = a_eff / n_motors
    f[F_AREA_TRUE] = f[F_DISC_AREA] / n_motors
    f[F_VEL_MAX] = v_h / math.sqrt(hover_thr)
    f[F_POWER_FACTOR] = p_hover / t_hover

    # each moment of inertia as given, or (0) that of half the mass on a ring of radius diag/2
    ring_xy = mass * 0.25 * (0.5 * diag) ** 2
    ring_z = mass * 0.5 * (0.5 * diag) ** 2
    f[F_IXX] = get("TLM_IXX") or ring_xy
    f[F_IYY] = get("TLM_IYY") or ring_xy
    f[F_IZZ] = get("TLM_IZZ") or ring_z
    rot_rate = get("TLM_REF_ROT_RATE")
    f[F_ROT_DAMP] = math.radians(400.0) / rot_rate if rot_rate > 0.0 else 0.0

    span = f[F_PWM_MAX] - f[F_PWM_MIN]
    f[F_PWM_LO] = f[F_PWM_MIN] + f[F_SPIN_MIN] * span
    f[F_PWM_HI] = f[F_PWM_MIN] + f[F_SPIN_MAX] * span
    f[F_HOVER_CMD] = _hover_command(hover_thr, expo)

    _motor_table(f, layout, diag, (get("TLM_CG_X"), get("TLM_CG_Y")), get("TLM_YAW_ASYM"))
    _environment(f, p)
    _engine_fault(f, p)
    return f


def _engine_fault(f: np.ndarray, p: Params) -> None:
    """SIM_ENGINE_MUL and SIM_ENGINE_FAIL: SITL applies them where the autopilot's outputs
    reach the simulated motors (sitl-faults.md §6.1). SIM_ENGINE_FAIL is a bit mask of outputs;
    in the paper-era profile (TLM_PROFILE 1) the index of one output, 0 = motor 1."""
    f[F_ENGINE_MUL] = p["SIM_ENGINE_MUL"]
    fail = p["SIM_ENGINE_FAIL"]
    if p["TLM_PROFILE"] >= 0.5:
        fail = float(1 << int(fail)) if 0 <= fail < 31 else 0.0
    f[F_ENGINE_MASK] = fail


def _motor_table(f: np.ndarray, layout: FrameLayout, diag: float,
                 cg: tuple[float, float] = (0.0, 0.0), yaw_asym: float = 0.0) -> None:
    """The motor slots of frame array ``f``: count, positions [m, body FRD] from the centre of
    gravity ``cg`` (TLM_CG_X / _Y from the motors' centre: the thrust, the air at the rotors
    and the momentum drag act about it), reaction-torque factors: the yaw factor (+1
    counter-clockwise, -1 clockwise) plus ``yaw_asym`` (TLM_YAW_ASYM: counter-clockwise
    rotors' torque 1 + it, clockwise ones' 1 - it)."""
    f[F_N_MOTORS] = layout.n_motors
    for i, ((ux, uy), m) in enumerate(zip(layout.arm_unit(), layout.motors, strict=True)):
        f[F_MOT_X + i] = diag * ux - cg[0]
        f[F_MOT_Y + i] = diag * uy - cg[1]
        f[F_MOT_YAW + i] = m.yaw_factor + yaw_asym


def _environment(f: np.ndarray, p: Params) -> None:
    """The ``SIM_*`` environment slots of frame array ``f``: home altitude, battery, wind,
    shove and twist."""
    f[F_HOME_ALT] = float(p["SIM_OPOS_ALT"])
    f[F_BATT_VOLT] = float(p["SIM_BATT_VOLTAGE"])
    cap = float(p["SIM_BATT_CAP_AH"])
    f[F_BATT_CAP_AH] = cap if cap > 0.0 else float(p["TLM_BATT_CAP_AH"])
    f[F_BATT_RES] = float(p["TLM_BAT_RES"])
    for slot, name in ((F_WIND_SPD, "SIM_WIND_SPD"), (F_WIND_DIR, "SIM_WIND_DIR"),
                       (F_WIND_TURB, "SIM_WIND_TURB"), (F_WIND_TC, "SIM_WIND_TC"),
                       (F_WIND_DIR_Z, "SIM_WIND_DIR_Z"), (F_WIND_T, "SIM_WIND_T"),
                       (F_WIND_T_ALT, "SIM_WIND_T_ALT"), (F_WIND_T_COEF, "SIM_WIND_T_COEF")):
        f[slot] = float(p[name])
    tc = float(p["TLM_TURB_TC"])
    f[F_GUST_A] = math.exp(-PHYSICS_DT_S / tc) if tc > 0.0 else 0.0
    rnd, rnd_tc = float(p["TLM_ROTOR_RND"]), float(p["TLM_ROTOR_RND_TC"])
    a = math.exp(-PHYSICS_DT_S / rnd_tc)
    f[F_ROTOR_RND_A] = a
    f[F_ROTOR_RND_B] = math.sqrt(1.0 - a * a) * rnd
    for k, axis in enumerate("XYZ"):
        f[F_SHOVE + k] = float(p[f"SIM_SHOVE_{axis}"])
        f[F_TWIST + k] = float(p[f"SIM_TWIST_{axis}"])
    f[F_SHOVE_TIME] = float(p["SIM_SHOVE_TIME"])
    f[F_TWIST_TIME] = float(p["SIM_TWIST_TIME"])


def hover_command(frame: np.ndarray) -> float:
    """Motor command ``a_h`` (0..1) whose thrust equals the weight at rho_ref and full voltage.

    Solves ``(1 - e) a + e a^2 = hover_thr``; about 0.5505 for the default frame.
    """
    return _hover_command(float(frame[F_HOVER_THR]), float(frame[F_EXPO]))


@tick_jit
def pwm_to_command(pwm: float, frame: np.ndarray) -> float:
    """Motor command 0..1 for a servo PWM [us] (SITL ``Motor::pwm_to_command``)."""
    lo = frame[F_PWM_LO]
    a = (pwm - lo) / (frame[F_PWM_HI] - lo)
    if a < 0.0:
        return 0.0
    if a > 1.0:
        return 1.0
    return a


@tick_jit
def command_to_pwm(a: float, frame: np.ndarray) -> float:
    """Servo PWM [us] that gives motor command ``a`` (0..1): the inverse of pwm_to_command."""
    return frame[F_PWM_LO] + a * (frame[F_PWM_HI] - frame[F_PWM_LO])


def frame_copy(frame: np.ndarray, **changes: float) -> np.ndarray:
    """Return a copy of ``frame`` with entries replaced, e.g. ``frame_copy(f, F_ROT_DAMP=0.0)``."""
    out = frame.copy()
    names = globals()
    for name, value in changes.items():
        out[int(names[name])] = value
    return out
