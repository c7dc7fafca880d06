"""Index constants of the truth state vector ``x`` (one float64 array per flight).

Frames: earth NED (x north, y east, z down) relative to home at ground level; body FRD
(x forward, y right, z down). The quaternion rotates body vectors into NED (Hamilton
convention, scalar first): ``v_ned = q * v_body * q^-1``.
"""

# position of the centre of mass, NED from home [m]; PD = -height above home ground
PN, PE, PD = 0, 1, 2
# velocity NED [m/s]
VN, VE, VD = 3, 4, 5
# attitude quaternion body -> NED, scalar first
QW, QX, QY, QZ = 6, 7, 8, 9
# body angular rate [rad/s], FRD
WX, WY, WZ = 10, 11, 12
# specific force in the body frame [m/s^2] (what an ideal accelerometer reads; ~(0,0,-g) at hover)
FX, FY, FZ = 13, 14, 15
# earth-frame kinematic acceleration NED [m/s^2] (gravity included; 0 at hover)
AN, AE, AD = 16, 17, 18
# motor commands after the slew limit, 0..1 (motor 1..4 in ArduPilot's numbering)
M1, M2, M3, M4 = 19, 20, 21, 22
# per-motor thrust [N]
T1, T2, T3, T4 = 23, 24, 25, 26
# battery: terminal voltage [V], current [A], consumed charge [Ah], resting voltage [V]
BATT_V, BATT_I, BATT_AH, BATT_VREST = 27, 28, 29, 30
# 1.0 while resting on the ground (ground contact active), else 0.0
ON_GROUND = 31
# wind (velocity of the air mass) NED [m/s], as applied at the vehicle's height
WIND_N, WIND_E, WIND_D = 32, 33, 34
# wind model internal state: filtered speed [m/s], direction [deg, from], vertical dir [deg],
# horizontal and vertical gust speeds [m/s]
WIND_SPD_F, WIND_DIR_F, WIND_DIRZ_F, GUST_H, GUST_V = 35, 36, 37, 38, 39
# vertical speed at the last ground impact [m/s, down positive]; impact counter
IMPACT_SPEED, IMPACT_COUNT = 40, 41
# simulated time of the last ground contact start [s]
TIME_LAST_AIRBORNE = 42
# body-frame airspeed vector [m/s]
VAIR_X, VAIR_Y, VAIR_Z = 43, 44, 45
# battery: remaining charge [Ah] (finite capacity only); SIM_BATT_VOLTAGE value the battery was
# last (re)initialised to [V] (a change of the parameter re-initialises the battery, as SITL does)
BATT_REM_AH, BATT_VSET = 46, 47
# air density at the vehicle [kg/m^3] (1976 standard atmosphere at home_alt - PD)
RHO = 48
# wind model cache: unit vector (NED) of the filtered direction the wind comes FROM
WIND_UN, WIND_UE, WIND_UD = 49, 50, 51
# air density cache: altitude [m AMSL] where RHO_ANCHOR [kg/m^3] and its gradient RHO_GRAD
# [kg/m^4] were evaluated (RHO is interpolated linearly within a few metres of it)
RHO_ALT, RHO_ANCHOR, RHO_GRAD = 52, 53, 54
# what the sensors see (SITL's "sensor smoothing", tlm_sim.dynamics.smoothing): a kinematic
# shadow of the truth that follows it with a 0.1 s time constant, so that a ground impact (the
# truth stops instantly) shows up in the IMU as a deceleration. Position NED [m], velocity NED
# [m/s], attitude quaternion body -> NED, specific force in its body frame [m/s^2] and body rate
# [rad/s]; the IMU, GPS and baro read these, the SIM log the truth above.
SPN, SPE, SPD = 55, 56, 57
SVN, SVE, SVD = 58, 59, 60
SQW, SQX, SQY, SQZ = 61, 62, 63, 64
SFX, SFY, SFZ = 65, 66, 67
SWX, SWY, SWZ = 68, 69, 70
# 1.0 while the shadow differs from the truth (after a ground contact), else 0.0: the shadow
# is then the truth itself
SMOOTH_ACTIVE = 71

N_STATE = 72
