"""Index constants of the controller state ``c`` and controller configuration ``g`` arrays.

Controller internals use SI units (m, m/s, m/s^2, rad, rad/s), earth frame NED, body FRD;
configuration values are converted from ArduPilot's parameter units when the array is built.
"""

# ---------------------------------------------------------------- controller state c ----------
# rate PIDs, one block per axis (roll, pitch, yaw)
RATE_BASE = 0
R_TF = 0  # filtered target [rad/s]
R_EF = 1  # filtered error [rad/s]
R_DF = 2  # filtered derivative [rad/s^2]
R_EPREV = 3  # previous filtered error
R_I = 4  # integrator (motor units)
R_OUT = 5  # last output (motor units, +-1)
R_TARGET = 6  # unfiltered rate target [rad/s]
R_MEAS = 7  # rate used [rad/s]
RATE_STRIDE = 8
# attitude: target euler angles [rad] and their shaped rates [rad/s]
ATT_ROLL_T = 24
ATT_PITCH_T = 25
ATT_YAW_T = 26
ATT_ROLL_RATE_T = 27
ATT_PITCH_RATE_T = 28
ATT_YAW_RATE_T = 29
ATT_ROLL_CMD = 30  # commanded lean angles and heading [rad] (before shaping)
ATT_PITCH_CMD = 31
ATT_YAW_CMD = 32
# horizontal position controller (N, E)
PXY_POS_T = 33  # target position NE [m] (2)
PXY_VEL_T = 35  # target velocity NE [m/s] (2)
PXY_ACC_T = 37  # target acceleration NE [m/s^2] (2)
PXY_VEL_FF = 39  # feed-forward velocity NE (2)
PXY_ACC_FF = 41  # feed-forward acceleration NE (2)
PXY_I = 43  # velocity PID integrator NE [m/s^2] (2)
PXY_EF = 45  # filtered velocity error (2)
PXY_DF = 47  # filtered derivative (2)
PXY_EPREV = 49  # previous filtered velocity error (2)
# vertical position controller (down positive internally)
PZ_POS_T = 51  # target down position [m]
PZ_VEL_T = 52  # target down velocity [m/s]
PZ_ACC_T = 53  # target "up" acceleration [m/s^2] (ArduPilot's ADes sign)
PZ_VEL_FF = 54  # feed-forward down velocity
PZ_ACC_EF = 55  # filtered acceleration error [m/s^2]
PZ_I = 56  # accel PID integrator (throttle units)
PZ_ACC_MEAS = 57  # measured up acceleration [m/s^2]
THR_OUT = 58  # throttle demand 0..1 to the mixer
THR_HOVER = 59  # learned hover throttle (MOT_THST_HOVER)
THR_OUT_BOOSTED = 60  # throttle after angle boost
# mixer outputs and limit flags
MIX_THRUST = 61  # per-motor thrust fraction 0..1 (4)
MIX_ACT = 65  # per-motor actuator 0..1 (4)
MIX_PWM = 69  # per-motor commanded PWM [us] (4)
LIM_RP = 73  # roll/pitch saturated (1/0)
LIM_YAW = 74
LIM_THR_LO = 75
LIM_THR_HI = 76
# vehicle / mode
MODE = 77  # ArduCopter mode number
SUBMODE = 78  # see the SUB_* constants
ARMED = 79
LANDED = 80  # land-complete flag
LAND_TIMER = 81  # seconds the landing conditions have held
ALP = 82  # 1 Hz low-passed earth accel minus gravity [m/s^2] (3)
WP_INDEX = 85  # index of the next mission waypoint (the end of the current leg)
PATH_S = 86  # target progress along the active path [m]
PATH_V = 87  # target speed along the path [m/s]
PATH_A = 88  # target acceleration along the path [m/s^2]
SUB_TIMER = 89  # time in the current sub-mode [s]
HOME_YAW = 90  # heading at arming [rad]
RC_FAILSAFE = 91  # radio failsafe active
SPOOL = 92  # 0 shut down, 1 ground idle, 2 throttle unlimited
MAYBE_LANDED = 93
WP_REACHED = 94  # waypoints reached so far
TAKEOFF_ALT = 95  # takeoff target altitude above home [m]
LAND_DESCENT_STARTED = 96
CRASH_TIMER = 97
DISARM_TIME = 98  # simulated time of disarm [s] (-1 while armed)
YAW_RATE_CMD = 99  # heading-rate feed-forward of the path's heading [rad/s]
BODY_RATE_T = 100  # attitude controller output: body-rate targets [rad/s] (3)
# vertical complementary filter of the EKF height (EKF3's height-rate output), down positive
VCF_ACC = 103  # learned acceleration offset [m/s^2]
VCF_VEL = 104  # height rate, down [m/s]
VCF_POS = 105  # height, down [m]
VIBE_COMP = 106  # 1 while the vibration failsafe (vibration compensation) is on
VIBE_FAIL_T = 107  # start of the current run of failing vibration checks [s] (-1: passing)
VIBE_LAST_FAIL_T = 108  # last failing vibration check [s]
EKF_FAIL_COUNT = 109  # ekf_check failure counter (0..10)
EKF_FAILSAFE = 110  # 1 while the EKF failsafe is active
EKF_CHECK_OK_ONCE = 111  # 1 once the EKF checks have passed
EKF_VEL_TR_F = 112  # low-passed sqrt velocity test ratio
EKF_POS_TR_F = 113  # low-passed sqrt position test ratio
EKF_POS_OK = 114  # 1 while the EKF reports an absolute horizontal position
LAND_NOGPS = 115  # 1: LAND without position control (level attitude, horizontal drift)
LAND_PAUSE = 116  # seconds left before a failsafe LAND starts descending
CHECK_TIMER = 117  # time of the next 10 Hz failsafe check [s]
THRUST_LOSS_T = 118  # time the thrust-loss symptoms have lasted [s]
THRUST_BOOST = 119  # 1 while the motors' thrust boost is on (after a thrust-loss detection)
PZ_ACC_FF = 120  # feed-forward down acceleration of the path [m/s^2]
PATH_STOP_T = 121  # time into the jerk-limited stop at the path's end [s] (-1: not stopping)
PATH_STOP_V0 = 122  # target speed when that stop began [m/s]
AIR_RHO_RATIO = 123  # air density / 1.225 at the vehicle (motor density compensation; 0: off)
PATH_STOP_A = 124  # acceleration limit of that stop [m/s^2]
ALTHOLD_LEAN = 125  # lean-angle limit from the throttle headroom, filtered [rad] (see position)
PXY_LIMIT = 126  # last horizontal acceleration target before it was limited, NE (2; 0: none)
TRACK_K = 128  # AC_WPNav's S-curve time scaler (track_scalar_dt), 0..1
TAKEOFF_DONE_T = 129  # time since the AUTO takeoff reached its altitude [s] (-1: not yet)
N_CONTROL_STATE = 130

# sub-modes of AUTO / RTL / LAND
SUB_NONE = 0
SUB_TAKEOFF = 1
SUB_WP = 2
SUB_RTL_CLIMB = 3
SUB_RTL_RETURN = 4
SUB_RTL_LOITER = 5
SUB_LAND = 6
SUB_LANDED = 7
SUB_GROUND_IDLE = 8

# ArduCopter mode numbers (ArduCopter/mode.h)
MODE_STABILIZE = 0
MODE_ALT_HOLD = 2
MODE_AUTO = 3
MODE_GUIDED = 4
MODE_LOITER = 5
MODE_RTL = 6
MODE_LAND = 9

# mode-change reasons (AP_Vehicle/ModeReason.h)
RSN_UNKNOWN = 0
RSN_GCS = 2
RSN_RADIO_FAILSAFE = 3
RSN_EKF_FAILSAFE = 6
RSN_MISSION_END = 8
RSN_CRASH_FAILSAFE = 19

# ------------------------------------------------------------ controller configuration g ------
G_DT = 0  # main-loop period [s]
G_RAT_P = 1  # rate PID P per axis (3)
G_RAT_I = 4
G_RAT_D = 7
G_RAT_FF = 10
G_RAT_IMAX = 13
G_RAT_FLTT = 16  # filter alphas at the loop rate (3 each)
G_RAT_FLTE = 19
G_RAT_FLTD = 22
G_ANG_P = 25  # angle P per axis (3) [1/s]
G_ACCEL_MAX = 28  # attitude accel limits per axis [rad/s^2] (3)
G_INPUT_TC = 31  # ATC_INPUT_TC [s]
G_SLEW_YAW = 32  # ATC_SLEW_YAW [rad/s]
G_ANGLE_MAX = 33  # ANGLE_MAX [rad]
G_POSXY_P = 34
G_VELXY_P = 35
G_VELXY_I = 36
G_VELXY_D = 37
G_VELXY_IMAX = 38  # [m/s^2]
G_VELXY_FLTE = 39  # alpha
G_VELXY_FLTD = 40  # alpha
G_POSZ_P = 41
G_VELZ_P = 42
G_ACCZ_P = 43  # throttle per cm/s^2 (ArduPilot units kept: x0.001 applied in code)
G_ACCZ_I = 44
G_ACCZ_D = 45
G_ACCZ_IMAX = 46  # [throttle units * 1000]
G_ACCZ_FLTE = 47  # alpha
G_WP_SPEED = 48  # WPNAV_SPEED [m/s]
G_WP_ACCEL = 49  # WPNAV_ACCEL [m/s^2]
G_WP_SPEED_UP = 50  # [m/s]
G_WP_SPEED_DN = 51  # [m/s]
G_WP_ACCEL_Z = 52  # [m/s^2]
G_WP_RADIUS = 53  # [m]
G_WP_JERK = 54  # [m/s^3]
G_RTL_ALT = 55  # [m]
G_RTL_SPEED = 56  # [m/s] (0 -> WP speed)
G_RTL_LOIT_TIME = 57  # [s]
G_RTL_CONE_SLOPE = 58
G_RTL_CLIMB_MIN = 59  # [m]
G_LAND_SPEED = 60  # [m/s]
G_LAND_SPEED_HIGH = 61  # [m/s] (0 -> WP_SPEED_DN)
G_LAND_ALT_LOW = 62  # [m]
G_MOT_EXPO = 63
G_MOT_HOVER = 64
G_MOT_SPIN_ARM = 65
G_MOT_SPIN_MIN = 66
G_MOT_SPIN_MAX = 67
G_MOT_PWM_MIN = 68
G_MOT_PWM_MAX = 69
G_MOT_BAT_MAX = 70
G_MOT_BAT_MIN = 71
G_MOT_YAW_HEADROOM = 72  # fraction
G_FS_THR_ENABLE = 73
G_RC_FS_TIMEOUT = 74  # [s]
G_FS_THR_VALUE = 75  # [us]
G_ARM_TIME = 76  # [s] simulated time at which the vehicle arms
G_HOVER_LEARN = 77  # MOT_HOVER_LEARN
G_WP_LEG_K = 78  # S-curve leg-speed calibration factor
G_THR_MIX_MIN = 79
G_THR_MIX_MAX = 80
G_FS_CRASH_CHECK = 81
G_DISARM_DELAY = 82  # [s]
G_ACCEL_XY_MAX = 83  # g * tan(ANGLE_MAX): horizontal acceleration limit [m/s^2]
G_HRT_OMEGA = 84  # 2 pi EK3_HRT_FILT: height-rate complementary filter crossover [rad/s]
G_FS_VIBE_ENABLE = 85
G_FS_EKF_THRESH = 86
G_FS_EKF_ACTION = 87
G_FS_EKF_ALPHA = 88  # FS_EKF_FILT low-pass coefficient at the 10 Hz check rate
G_RHO_RATIO_HOME = 89  # air density / 1.225 at home (1976 atmosphere, SIM_OPOS_ALT)
G_RHO_RATIO_GRAD = 90  # its change per metre of height above home [1/m]
G_BATT_SAG_HOVER = 91  # battery monitor's resting-voltage estimate minus voltage at hover [V]
G_ANG_LIM_ALPHA = 92  # ATC_ANG_LIM_TC low-pass coefficient at the loop rate
G_YAW_ERR_MAX = 93  # largest heading error the attitude controller acts on [rad]
G_POSXY_ERR_MAX = 94  # largest horizontal position error the position controller acts on [m]
G_POSZ_ERR_UP = 95  # largest vertical position error (target above) it acts on [m]
G_POSZ_ERR_DN = 96  # largest vertical position error (target below) it acts on [m]
N_CONTROL_CFG = 97
