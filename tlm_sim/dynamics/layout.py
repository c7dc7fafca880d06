"""Slots of the truth state vector ``x`` (one float64 array per flight), declared once
(:class:`tlm_sim.slots.Layout`; ``STATE.describe(x)`` names every value).

Frames: earth NED (x north, y east, z down) relative to home at ground level; body FRD
(x forward, y right, z down). The quaternion rotates body vectors into NED (Hamilton
convention, scalar first): ``v_ned = q * v_body * q^-1``.
"""

from tlm_sim.frames import MAX_MOTORS
from tlm_sim.slots import Layout

STATE = Layout("x", "truth state of the vehicle and its environment")
_x = STATE

PN, PE, PD = _x.vector(("PN", "PE", "PD"), "m",
                       "centre of mass, NED from home; PD = -height above home ground")
VN, VE, VD = _x.vector(("VN", "VE", "VD"), "m/s", "velocity NED")
QW, QX, QY, QZ = _x.vector(("QW", "QX", "QY", "QZ"), "",
                           "attitude quaternion body -> NED, scalar first")
WX, WY, WZ = _x.vector(("WX", "WY", "WZ"), "rad/s", "body angular rate, FRD")
FX, FY, FZ = _x.vector(("FX", "FY", "FZ"), "m/s/s",
                       "specific force, body (what an ideal accelerometer reads; ~(0,0,-g) "
                       "at hover)")
AN, AE, AD = _x.vector(("AN", "AE", "AD"), "m/s/s",
                       "kinematic acceleration NED (gravity included; 0 at hover)")
M1, M2, M3, M4, M5, M6, M7, M8 = _x.vector(
    tuple(f"M{k + 1}" for k in range(MAX_MOTORS)), "",
    "motor commands after the slew limit, 0..1 (ArduPilot's numbering; motors beyond the "
    "frame's count stay 0)")
T1, T2, T3, T4, T5, T6, T7, T8 = _x.vector(tuple(f"T{k + 1}" for k in range(MAX_MOTORS)), "N",
                                           "per-motor thrust")
BATT_V = _x.add("BATT_V", 1, "V", "battery terminal voltage")
BATT_I = _x.add("BATT_I", 1, "A", "battery current")
BATT_AH = _x.add("BATT_AH", 1, "Ah", "charge consumed")
BATT_VREST = _x.add("BATT_VREST", 1, "V", "battery resting voltage")
ON_GROUND = _x.add("ON_GROUND", 1, "", "1.0 while resting on the ground (ground contact active)")
WIND_N, WIND_E, WIND_D = _x.vector(("WIND_N", "WIND_E", "WIND_D"), "m/s",
                                   "wind (velocity of the air mass) NED at the vehicle's height")
WIND_SPD_F = _x.add("WIND_SPD_F", 1, "m/s", "wind model: filtered speed (SIM_WIND_SPD slewed)")
WIND_DIR_F = _x.add("WIND_DIR_F", 1, "deg",
                    "wind model: filtered direction the wind comes from, true, (-180, 180]")
WIND_DIRZ_F = _x.add("WIND_DIRZ_F", 1, "deg",
                     "wind model: filtered vertical angle (SIM_WIND_DIR_Z slewed), 90 = updraft")
GUST_H = _x.add("GUST_H", 1, "m/s", "wind model: horizontal gust speed")
GUST_V = _x.add("GUST_V", 1, "m/s", "wind model: vertical gust speed")
WIND_SLEW_T = _x.add("WIND_SLEW_T", 1, "s",
                     "wind model: simulated time of the slew filters' last update (they advance "
                     "only when more than 1 ms has passed, as SITL's; 0 at boot)")
IMPACT_SPEED = _x.add("IMPACT_SPEED", 1, "m/s",
                      "vertical speed at the last ground impact, down positive")
IMPACT_COUNT = _x.add("IMPACT_COUNT", 1, "", "ground impacts so far")
TIME_LAST_AIRBORNE = _x.add("TIME_LAST_AIRBORNE", 1, "s",
                            "simulated time of the last ground contact start")
VAIR_X, VAIR_Y, VAIR_Z = _x.vector(("VAIR_X", "VAIR_Y", "VAIR_Z"), "m/s", "airspeed, body")
BATT_REM_AH = _x.add("BATT_REM_AH", 1, "Ah", "remaining charge (finite capacity only)")
BATT_VSET = _x.add("BATT_VSET", 1, "V",
                   "SIM_BATT_VOLTAGE the battery was last (re)initialised to (a change of the "
                   "parameter re-initialises the battery, as SITL does)")
RHO = _x.add("RHO", 1, "kg/m^3",
             "air density at the vehicle (1976 standard atmosphere at home_alt - PD)")
WIND_UN, WIND_UE, WIND_UD = _x.vector(("WIND_UN", "WIND_UE", "WIND_UD"), "",
                                      "wind model cache: unit vector NED of the filtered "
                                      "direction the wind comes from")
RHO_ALT = _x.add("RHO_ALT", 1, "m",
                 "air density cache: altitude AMSL of RHO_ANCHOR and RHO_GRAD (RHO is "
                 "interpolated linearly within a few metres of it)")
RHO_ANCHOR = _x.add("RHO_ANCHOR", 1, "kg/m^3", "air density at RHO_ALT")
RHO_GRAD = _x.add("RHO_GRAD", 1, "kg/m^4", "air density gradient at RHO_ALT")
# What the sensors see (SITL's "sensor smoothing", tlm_sim.dynamics.smoothing): a kinematic
# shadow of the truth that follows it with a 0.1 s time constant, so that a ground impact (the
# truth stops instantly) shows up in the IMU as a deceleration. The IMU, GPS and baro read
# these, the SIM log the truth above.
SPN, SPE, SPD = _x.vector(("SPN", "SPE", "SPD"), "m", "sensor shadow: position NED")
SVN, SVE, SVD = _x.vector(("SVN", "SVE", "SVD"), "m/s", "sensor shadow: velocity NED")
SQW, SQX, SQY, SQZ = _x.vector(("SQW", "SQX", "SQY", "SQZ"), "",
                               "sensor shadow: attitude quaternion body -> NED")
SFX, SFY, SFZ = _x.vector(("SFX", "SFY", "SFZ"), "m/s/s",
                          "sensor shadow: specific force in its body frame")
SWX, SWY, SWZ = _x.vector(("SWX", "SWY", "SWZ"), "rad/s", "sensor shadow: body rate")
SMOOTH_ACTIVE = _x.add("SMOOTH_ACTIVE", 1, "",
                       "1.0 while the shadow differs from the truth (after a ground contact); "
                       "else the shadow is the truth itself")
SHOVE_MS = _x.add("SHOVE_MS", 1, "ms",
                  "time the running SIM_SHOVE push has acted (0 when none runs)")
TWIST_MS = _x.add("TWIST_MS", 1, "ms",
                  "time the running SIM_TWIST angular push has acted (0 when none runs)")
WIND_STILL_DT = _x.add("WIND_STILL_DT", 1, "s",
                       "wind model cache: a slew-filter step of exactly this length changed "
                       "nothing at the targets WIND_STILL_KEY (the filters have settled; the "
                       "step is skipped while both repeat); -1 when none")
WIND_STILL_KEY = _x.add("WIND_STILL_KEY", 7, "",
                        "wind model cache: SIM_WIND_SPD [m/s], SIM_WIND_DIR [deg], "
                        "SIM_WIND_DIR_Z [deg], SIM_WIND_TC [s] and WIND_SPD_F, WIND_DIR_F, "
                        "WIND_DIRZ_F when WIND_STILL_DT was found")
GUST_E = _x.add("GUST_E", 1, "m/s",
                "wind model: east gust speed of the correlated gusts (TLM_TURB_TC > 0; GUST_H "
                "is then the north one)")
ROTOR_RND = _x.add("ROTOR_RND", MAX_MOTORS, "",
                   "each rotor's thrust fluctuation, a fraction of its thrust (TLM_ROTOR_RND > 0)")

N_STATE = STATE.close()

#: What the sensors may sense of the truth state: the sensor shadow (SITL's smoothed position,
#: velocity, specific force and body rate), the height and attitude, the battery's terminal
#: voltage and current, the rotors' speeds (as motor commands M1..M8: SITL's state.rpm, which
#: its IMU's motor vibration follows). Nothing above the sensors reads the truth
#: (tests/test_structure_sim.py).
PUBLISHED: frozenset[str] = frozenset({
    "PD", "QW", "QX", "QY", "QZ", "SPN", "SPE", "SPD", "SVN", "SVE", "SVD", "SFX", "SFY", "SFZ",
    "SWX", "SWY", "SWZ", "BATT_V", "BATT_I", "M1",
})
