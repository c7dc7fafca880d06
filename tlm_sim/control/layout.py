"""Slots of the controller state ``c`` and controller configuration ``g`` arrays, declared once
(:class:`tlm_sim.slots.Layout`; ``STATE.describe(c)``, ``CONFIG.describe(g)``).

Controller internals use SI units (m, m/s, m/s^2, rad, rad/s), earth frame NED, body FRD;
configuration values are converted from ArduPilot's parameter units when the array is built.
"""

from tlm_sim.frames import MAX_MOTORS
from tlm_sim.slots import Layout

# ---------------------------------------------------------------- controller state c ----------
# rate PIDs: one record per axis (roll, pitch, yaw) at RATE_BASE + axis * RATE_STRIDE
RATE = Layout("rate", "rate PID of one axis")
R_TF = RATE.add("R_TF", 1, "rad/s", "filtered target")
R_EF = RATE.add("R_EF", 1, "rad/s", "filtered error")
R_DF = RATE.add("R_DF", 1, "rad/s^2", "filtered derivative")
R_EPREV = RATE.add("R_EPREV", 1, "", "previous filtered error")
R_I = RATE.add("R_I", 1, "", "integrator (motor units)")
R_OUT = RATE.add("R_OUT", 1, "", "last output (motor units, +-1)")
R_TARGET = RATE.add("R_TARGET", 1, "rad/s", "unfiltered rate target")
R_MEAS = RATE.add("R_MEAS", 1, "rad/s", "rate used")
RATE_STRIDE = RATE.close()

STATE = Layout("c", "controller state")
_c = STATE
RATE_BASE = _c.block("RATE", RATE, 3)
ATT_ROLL_T = _c.add("ATT_ROLL_T", 1, "rad", "attitude target: roll")
ATT_PITCH_T = _c.add("ATT_PITCH_T", 1, "rad", "attitude target: pitch")
ATT_YAW_T = _c.add("ATT_YAW_T", 1, "rad", "attitude target: heading")
ATT_ROLL_RATE_T = _c.add("ATT_ROLL_RATE_T", 1, "rad/s", "shaped rate of the roll target")
ATT_PITCH_RATE_T = _c.add("ATT_PITCH_RATE_T", 1, "rad/s", "shaped rate of the pitch target")
ATT_YAW_RATE_T = _c.add("ATT_YAW_RATE_T", 1, "rad/s", "shaped rate of the heading target")
ATT_ROLL_CMD = _c.add("ATT_ROLL_CMD", 1, "rad", "commanded roll (before shaping)")
ATT_PITCH_CMD = _c.add("ATT_PITCH_CMD", 1, "rad", "commanded pitch (before shaping)")
ATT_YAW_CMD = _c.add("ATT_YAW_CMD", 1, "rad", "commanded heading (before shaping)")
# horizontal position controller (N, E)
PXY_POS_T = _c.add("PXY_POS_T", 2, "m", "target position NE")
PXY_VEL_T = _c.add("PXY_VEL_T", 2, "m/s", "target velocity NE")
PXY_ACC_T = _c.add("PXY_ACC_T", 2, "m/s^2", "target acceleration NE")
PXY_VEL_FF = _c.add("PXY_VEL_FF", 2, "", "feed-forward velocity NE")
PXY_ACC_FF = _c.add("PXY_ACC_FF", 2, "", "feed-forward acceleration NE")
PXY_I = _c.add("PXY_I", 2, "m/s^2", "velocity PID integrator NE")
PXY_EF = _c.add("PXY_EF", 2, "", "filtered velocity error")
PXY_DF = _c.add("PXY_DF", 2, "", "filtered derivative")
PXY_EPREV = _c.add("PXY_EPREV", 2, "", "previous filtered velocity error")
# vertical position controller (down positive internally)
PZ_POS_T = _c.add("PZ_POS_T", 1, "m", "target down position")
PZ_VEL_T = _c.add("PZ_VEL_T", 1, "m/s", "target down velocity")
PZ_ACC_T = _c.add("PZ_ACC_T", 1, "m/s^2", "target 'up' acceleration (ArduPilot's ADes sign)")
PZ_VEL_FF = _c.add("PZ_VEL_FF", 1, "", "feed-forward down velocity")
PZ_ACC_EF = _c.add("PZ_ACC_EF", 1, "m/s^2", "filtered acceleration error")
PZ_I = _c.add("PZ_I", 1, "", "accel PID integrator (throttle units)")
PZ_ACC_MEAS = _c.add("PZ_ACC_MEAS", 1, "m/s^2", "measured up acceleration")
THR_OUT = _c.add("THR_OUT", 1, "", "throttle demand 0..1 to the mixer")
THR_HOVER = _c.add("THR_HOVER", 1, "", "learned hover throttle (MOT_THST_HOVER)")
THR_OUT_BOOSTED = _c.add("THR_OUT_BOOSTED", 1, "", "throttle after angle boost")
# mixer outputs and limit flags
MIX_THRUST = _c.add("MIX_THRUST", MAX_MOTORS, "",
                    "per-motor thrust fraction 0..1 (motors 1..G_N_MOTORS; the rest 0)")
MIX_ACT = _c.add("MIX_ACT", MAX_MOTORS, "", "per-motor actuator 0..1")
MIX_PWM = _c.add("MIX_PWM", MAX_MOTORS, "us", "per-motor commanded PWM (SERVOn, RCOU Cn)")
LIM_RP = _c.add("LIM_RP", 1, "", "roll/pitch saturated (1/0)")
LIM_YAW = _c.add("LIM_YAW", 1, "", "yaw saturated (1/0)")
LIM_THR_LO = _c.add("LIM_THR_LO", 1, "", "throttle at its lower limit (1/0)")
LIM_THR_HI = _c.add("LIM_THR_HI", 1, "", "throttle at its upper limit (1/0)")
# vehicle / mode
MODE = _c.add("MODE", 1, "", "ArduCopter mode number")
SUBMODE = _c.add("SUBMODE", 1, "", "see the SUB_* constants")
ARMED = _c.add("ARMED", 1, "", "1 while armed")
LANDED = _c.add("LANDED", 1, "", "land-complete flag")
LAND_TIMER = _c.add("LAND_TIMER", 1, "", "seconds the landing conditions have held")
ALP = _c.add("ALP", 3, "m/s^2", "1 Hz low-passed earth accel minus gravity")
WP_INDEX = _c.add("WP_INDEX", 1, "",
                  "index of the next mission waypoint (the end of the current leg)")
PATH_S = _c.add("PATH_S", 1, "m", "target progress along the active path")
PATH_V = _c.add("PATH_V", 1, "m/s", "target speed along the path")
PATH_A = _c.add("PATH_A", 1, "m/s^2", "target acceleration along the path")
SUB_TIMER = _c.add("SUB_TIMER", 1, "s", "time in the current sub-mode")
HOME_YAW = _c.add("HOME_YAW", 1, "rad", "heading at arming")
RC_FAILSAFE = _c.add("RC_FAILSAFE", 1, "", "radio failsafe active")
SPOOL = _c.add("SPOOL", 1, "", "0 shut down, 1 ground idle, 2 throttle unlimited")
MAYBE_LANDED = _c.add("MAYBE_LANDED", 1, "", "land detector's maybe-landed flag")
WP_REACHED = _c.add("WP_REACHED", 1, "",
                    "waypoints reached so far (one with a hold time once the hold is over)")
TAKEOFF_ALT = _c.add("TAKEOFF_ALT", 1, "m", "takeoff target altitude above home")
LAND_DESCENT_STARTED = _c.add("LAND_DESCENT_STARTED", 1, "", "1 once the LAND descent has begun")
CRASH_TIMER = _c.add("CRASH_TIMER", 1, "s", "time the crash-check conditions have held")
DISARM_TIME = _c.add("DISARM_TIME", 1, "s", "simulated time of disarm (-1 while armed)")
YAW_RATE_CMD = _c.add("YAW_RATE_CMD", 1, "rad/s", "heading-rate feed-forward of the path's heading")
BODY_RATE_T = _c.add("BODY_RATE_T", 3, "rad/s", "attitude controller output: body-rate targets")
# vertical complementary filter of the EKF height (EKF3's height-rate output), down positive
VCF_ACC = _c.add("VCF_ACC", 1, "m/s^2", "learned acceleration offset")
VCF_VEL = _c.add("VCF_VEL", 1, "m/s", "height rate, down")
VCF_POS = _c.add("VCF_POS", 1, "m", "height, down")
VIBE_COMP = _c.add("VIBE_COMP", 1, "",
                   "1 while the vibration failsafe (vibration compensation) is on")
VIBE_FAIL_T = _c.add("VIBE_FAIL_T", 1, "s",
                     "start of the current run of failing vibration checks (-1: passing)")
VIBE_LAST_FAIL_T = _c.add("VIBE_LAST_FAIL_T", 1, "s", "last failing vibration check")
EKF_FAIL_COUNT = _c.add("EKF_FAIL_COUNT", 1, "", "ekf_check failure counter (0..10)")
EKF_FAILSAFE = _c.add("EKF_FAILSAFE", 1, "", "1 while the EKF failsafe is active")
EKF_CHECK_OK_ONCE = _c.add("EKF_CHECK_OK_ONCE", 1, "", "1 once the EKF checks have passed")
EKF_VEL_TR_F = _c.add("EKF_VEL_TR_F", 1, "", "low-passed sqrt velocity test ratio")
EKF_POS_TR_F = _c.add("EKF_POS_TR_F", 1, "", "low-passed sqrt position test ratio")
EKF_POS_OK = _c.add("EKF_POS_OK", 1, "", "1 while the EKF reports an absolute horizontal position")
LAND_NOGPS = _c.add("LAND_NOGPS", 1, "",
                    "1: LAND without position control (level attitude, horizontal drift)")
LAND_PAUSE = _c.add("LAND_PAUSE", 1, "", "seconds left before a failsafe LAND starts descending")
CHECK_TIMER = _c.add("CHECK_TIMER", 1, "s", "time of the next 10 Hz failsafe check")
THRUST_LOSS_T = _c.add("THRUST_LOSS_T", 1, "s", "time the thrust-loss symptoms have lasted")
THRUST_BOOST = _c.add("THRUST_BOOST", 1, "",
                      "1 while the motors' thrust boost is on (after a thrust-loss detection)")
MIX_THRUST_FILT = _c.add("MIX_THRUST_FILT", MAX_MOTORS, "",
                         "per-motor thrust output before the 0..1 clip, low-passed with 0.5 s "
                         "(the motor-loss monitor's _thrust_rpyt_out_filt)")
MOTOR_LOST = _c.add("MOTOR_LOST", 1, "",
                    "index (0-based) of the motor with the highest filtered output: the lost "
                    "motor (held while THRUST_BOOST)")
THRUST_UNBALANCED = _c.add("THRUST_UNBALANCED", 1, "",
                           "1 while the motor-loss monitor finds the thrust unbalanced (not "
                           "_thrust_balanced; needs 6 or more motors)")
THRUST_BOOST_RATIO = _c.add("THRUST_BOOST_RATIO", 1, "",
                            "0..1: how far the mixer has taken the lost motor out of its limits "
                            "(_thrust_boost_ratio; 0 = normal mixing)")
THR_RPY_MIX = _c.add("THR_RPY_MIX", 1, "",
                     "throttle vs attitude priority (_throttle_rpy_mix, 0.1..5), slewed towards "
                     "ATC_THR_MIX_MIN or ATC_THR_MIX_MAX")
THR_AVG_MAX = _c.add("THR_AVG_MAX", 1, "",
                     "highest average throttle the mixer may raise the motors to for attitude "
                     "control (_throttle_avg_max, before compensation)")
MOT_THR_OUT = _c.add("MOT_THR_OUT", 1, "",
                     "throttle the mixer placed, before compensation (the motors' _throttle_out)")
ATT_THRUST_ERR = _c.add("ATT_THRUST_ERR", 1, "rad",
                        "angle between the thrust vector and its target (att_error_angle)")
PZ_ACC_FF = _c.add("PZ_ACC_FF", 1, "m/s^2", "feed-forward down acceleration of the path")
PATH_STOP_T = _c.add("PATH_STOP_T", 1, "s",
                     "time into the jerk-limited stop at the path's end (-1: not stopping)")
PATH_STOP_V0 = _c.add("PATH_STOP_V0", 1, "m/s", "target speed when that stop began")
AIR_RHO_RATIO = _c.add("AIR_RHO_RATIO", 1, "",
                       "air density / 1.225 at the vehicle (motor density compensation; 0: off)")
PATH_STOP_A = _c.add("PATH_STOP_A", 1, "m/s^2", "acceleration limit of that stop")
ALTHOLD_LEAN = _c.add("ALTHOLD_LEAN", 1, "rad",
                      "lean-angle limit from the throttle headroom, filtered (see position)")
PXY_LIMIT = _c.add("PXY_LIMIT", 2, "",
                   "last horizontal acceleration target before it was limited, NE (0: none)")
TRACK_K = _c.add("TRACK_K", 1, "", "AC_WPNav's S-curve time scaler (track_scalar_dt), 0..1")
TAKEOFF_DONE_T = _c.add("TAKEOFF_DONE_T", 1, "s",
                        "time since the AUTO takeoff reached its altitude (-1: not yet)")
# battery monitor (AP_BattMonitor, 10 Hz) and its failsafe (tlm_sim.control.battery)
BM_NEXT_T = _c.add("BM_NEXT_T", 1, "s", "time of the next battery monitor update")
BM_LAST_T = _c.add("BM_LAST_T", 1, "s", "time of the last battery monitor update (-1: none)")
BM_VOLT = _c.add("BM_VOLT", 1, "V", "battery monitor: voltage")
BM_CURR = _c.add("BM_CURR", 1, "A", "battery monitor: current")
BM_MAH = _c.add("BM_MAH", 1, "mAh", "battery monitor: charge consumed")
BM_WH = _c.add("BM_WH", 1, "Wh", "battery monitor: energy consumed")
BM_REMPCT = _c.add("BM_REMPCT", 1, "%", "battery monitor: remaining capacity (100: unknown)")
BM_RES = _c.add("BM_RES", 1, "ohm", "battery monitor: internal resistance estimate")
BM_VFILT = _c.add("BM_VFILT", 1, "V", "resistance estimator: low-passed voltage")
BM_IFILT = _c.add("BM_IFILT", 1, "A", "resistance estimator: low-passed current")
BM_IMAX = _c.add("BM_IMAX", 1, "A", "resistance estimator: largest current seen")
BM_VREF = _c.add("BM_VREF", 1, "V", "resistance estimator: highest voltage seen")
BM_IREF = _c.add("BM_IREF", 1, "A", "resistance estimator: current when BM_VREF was seen")
BATT_FS = _c.add("BATT_FS", 1, "", "battery failsafe state: 0 none, 1 low, 2 critical (latched)")
BATT_FS_RANK = _c.add("BATT_FS_RANK", 1, "",
                      "priority rank of the last battery failsafe action taken (lower = "
                      "more severe; 99 before any)")
BATT_LOW_T0 = _c.add("BATT_LOW_T0", 1, "s", "start of the voltage below BATT_LOW_VOLT (-1: not)")
BATT_CRT_T0 = _c.add("BATT_CRT_T0", 1, "s", "start of the voltage below BATT_CRT_VOLT (-1: not)")
BATT_FS_ACT = _c.add("BATT_FS_ACT", 1, "",
                     "battery failsafe action for the vehicle logic to take (-1: none pending)")
RC_THR_LOW_N = _c.add("RC_THR_LOW_N", 1, "",
                      "radio failsafe counter: RC frames with throttle below FS_THR_VALUE (0..3)")
RC_LAST_SEEN_US = _c.add("RC_LAST_SEEN_US", 1, "us", "time of the last RC frame processed")
# the arming driver, the pre-arm checks and the boot texts (tlm_sim.control.arming)
ARM_NEXT_T = _c.add("ARM_NEXT_T", 1, "s", "time of the driver's next arm attempt")
ARM_TIME_S = _c.add("ARM_TIME_S", 1, "s", "time the vehicle armed (-1: not yet)")
ARM_GAVE_UP = _c.add("ARM_GAVE_UP", 1, "", "1 once the driver stopped trying to arm")
PREARM_NEXT_T = _c.add("PREARM_NEXT_T", 1, "s", "time of the next 1 Hz pre-arm check")
PREARM_SHOWN_T = _c.add("PREARM_SHOWN_T", 1, "s", "last time the pre-arm failures were shown")
PREARM_LAST_OK = _c.add("PREARM_LAST_OK", 1, "", "result of the last 1 Hz pre-arm check")
PREARM_REPORT = _c.add("PREARM_REPORT", 1, "",
                       "1: the checks failed after passing, show them within 4 s")
ACC_PASS_T = _c.add("ACC_PASS_T", 1, "s",
                    "accelerometers consistent since (-1: not yet seen consistent)")
GYR_PASS_T = _c.add("GYR_PASS_T", 1, "s", "gyros consistent since (-1: not yet)")
HOME_SET = _c.add("HOME_SET", 1, "", "1 once home is set (from the EKF origin, EV SET_HOME)")
FIELD_SET = _c.add("FIELD_SET", 1, "", "1 once the baro's field elevation is set")
TXT_N = _c.add("TXT_N", 1, "", "rows used in the flight's text log")
# logged evidence (issue 21: MOTB, LDET, ARM)
MOT_BATT_RATIO = _c.add("MOT_BATT_RATIO", 1, "",
                        "motors' voltage compensation: resting-voltage estimate clamped to "
                        "MOT_BAT_VOLT_MIN..MAX over MOT_BAT_VOLT_MAX (MOTB.BatVolt)")
MOT_LIFT_MAX = _c.add("MOT_LIFT_MAX", 1, "",
                      "motors' maximum lift ratio at that voltage (thrust curve; MOTB.LiftMax)")
LDET_FLAGS = _c.add("LDET_FLAGS", 1, "",
                    "land detector condition bits of this tick (LDET.Flags, LDET_* constants)")
LDET_COUNT = _c.add("LDET_COUNT", 1, "",
                    "land detector pass count in main-loop ticks (LDET.Count; 0 once landed)")
DISARM_METHOD = _c.add("DISARM_METHOD", 1, "",
                       "AP_Arming::Method of the last disarm (ARM.Method; ARM_METHOD_*)")
ARM_LOGGED = _c.add("ARM_LOGGED", 1, "", "armed state of the last ARM row (0 before any)")
LDET_LOG_FLAGS = _c.add("LDET_LOG_FLAGS", 1, "", "LDET.Flags of the last LDET row")
LDET_LOG_COUNT = _c.add("LDET_LOG_COUNT", 1, "", "LDET.Count of the last LDET row")
LDET_LOG_MS = _c.add("LDET_LOG_MS", 1, "ms", "time of the last LDET row (whole milliseconds)")
MISE_LOGGED = _c.add("MISE_LOGGED", 1, "", "mission item index of the last MISE row (0: none)")
# issue 22: the mission items AUTO flies (hold times, LOITER_TIME, LAND, speed changes)
NAV_CNUM = _c.add("NAV_CNUM", 1, "",
                  "mission item number (CNum) of the navigation item AUTO flies to (the end "
                  "item's once the last waypoint is done); the path's P_CNUM")
HOLD_START_MS = _c.add("HOLD_START_MS", 1, "ms",
                       "when the copter reached the waypoint it holds at (whole milliseconds, "
                       "ModeAuto's loiter_time; 0: not reached yet)")
MISSION_LAND = _c.add("MISSION_LAND", 1, "", "1 once AUTO lands at the mission's NAV_LAND item")
# the motors' throttle filter and its slew detector (issue 23: RATE.AOutSlew)
THR_IN_RAW = _c.add("THR_IN_RAW", 1, "",
                    "the vertical controller's throttle demand before its 0..1 clamp (what "
                    "AC_PosControl hands the attitude controller: above 1 while it asks for "
                    "more than full throttle)")
THR_FILT = _c.add("THR_FILT", 1, "",
                  "AP_Motors' throttle filter: the unclamped demand with ArduPilot's angle "
                  "boost, low-passed at the position controller's 2 Hz, clamped to 0..1, 0 "
                  "while disarmed or at ground idle (tlm's mixer takes the clamped, unfiltered "
                  "throttle; this feeds the slew detector only)")
SLEW_SAMPLES = _c.add("SLEW_SAMPLES", 7, "",
                      "throttle slew detector (DerivativeFilter, 7 points): THR_FILT samples, "
                      "a ring written at SLEW_IDX")
SLEW_TIMES = _c.add("SLEW_TIMES", 7, "us", "throttle slew detector: the samples' times")
SLEW_IDX = _c.add("SLEW_IDX", 1, "", "throttle slew detector: next ring slot (0..6)")
SLEW_NEW = _c.add("SLEW_NEW", 1, "", "throttle slew detector: 1 when a sample came since the "
                  "last slope (else the last slope is reused)")
SLEW_LAST = _c.add("SLEW_LAST", 1, "1/us", "throttle slew detector: the last slope")
THR_SLEW_RATE = _c.add("THR_SLEW_RATE", 1, "1/s",
                       "throttle slew rate: |slope| low-passed at 50 Hz (RATE.AOutSlew)")
# the pilot (tlm_sim.control.pilot, tlm_sim.control.pilot_modes; flights flown from sticks)
PIL_ROLL = _c.add("PIL_ROLL", 1, "", "roll stick, -1..1 outside its dead zone (norm_input_dz)")
PIL_PITCH = _c.add("PIL_PITCH", 1, "", "pitch stick, -1..1, + = nose up (stick back)")
PIL_YAW = _c.add("PIL_YAW", 1, "", "yaw stick, -1..1, + = yaw right")
PIL_THR = _c.add("PIL_THR", 1, "", "throttle control_in, 0..1000 (pwm_to_range_dz)")
PIL_YAW_ANGLE = _c.add("PIL_YAW_ANGLE", 1, "", "yaw stick as an angle control_in, +-4500")
PIL_THR_ZERO = _c.add("PIL_THR_ZERO", 1, "", "throttle_zero flag (set 400 ms after the stick is 0)")
PIL_THR_ZERO_T = _c.add("PIL_THR_ZERO_T", 1, "s", "when the throttle stick last came to 0 (-1: up)")
PIL_SW_POS = _c.add("PIL_SW_POS", 1, "", "mode switch position in force (-1: none yet)")
PIL_SW_NEW = _c.add("PIL_SW_NEW", 1, "", "position being debounced (-1: none)")
PIL_SW_T = _c.add("PIL_SW_T", 1, "s", "when that position was first read")
PIL_RUDDER_T = _c.add("PIL_RUDDER_T", 1, "s", "start of the rudder arm gesture (-1: none)")
PIL_RUDDER_DIS_T = _c.add("PIL_RUDDER_DIS_T", 1, "s",
                          "start of the rudder disarm gesture (-1: none)")
PIL_GCS_ROW = _c.add("PIL_GCS_ROW", 1, "", "next row of the ground station's mode requests")
PIL_ARM_REQ = _c.add("PIL_ARM_REQ", 1, "", "1: the rudder gesture asks for an arm attempt")
PIL_AUTO_ARMED = _c.add("PIL_AUTO_ARMED", 1, "", "auto_armed: armed and the throttle raised once")
PIL_DISARM_T = _c.add("PIL_DISARM_T", 1, "s", "auto-disarm: landed with the throttle low since")
PIL_TKOFF = _c.add("PIL_TKOFF", 1, "",
                   "pilot takeoff: 0 none, 1 throttle rising on the ground, 2 airborne")
PIL_TKOFF_THR = _c.add("PIL_TKOFF_THR", 1, "", "takeoff throttle ramp (0..1)")
PIL_TKOFF_ALT = _c.add("PIL_TKOFF_ALT", 1, "m", "takeoff target height, down (NED)")
PIL_CLIMB = _c.add("PIL_CLIMB", 1, "m/s", "pilot's desired climb rate (up)")
PIL_VEL_D = _c.add("PIL_VEL_D", 1, "m/s", "shaped desired vertical velocity, down")
PIL_ACC_D = _c.add("PIL_ACC_D", 1, "m/s^2", "shaped desired vertical acceleration, down")
MODE_RSN = _c.add("MODE_RSN", 1, "", "reason of the last mode change (ModeReason)")
ARM_METHOD = _c.add("ARM_METHOD", 1, "", "AP_Arming::Method of the arming (ARM.Method)")
ATT_YAW_RATE_IN = _c.add("ATT_YAW_RATE_IN", 1, "",
                         "1: the heading follows a rate input (YAW_RATE_CMD), as the pilot's yaw "
                         "stick (input_shaping_ang_vel); 0: a heading command")
# LOITER (AC_Loiter)
LOIT_VEL = _c.add("LOIT_VEL", 2, "m/s", "loiter's desired velocity NE")
LOIT_ACC = _c.add("LOIT_ACC", 2, "m/s^2", "pilot's desired acceleration NE")
LOIT_PRED = _c.add("LOIT_PRED", 2, "rad", "predicted roll, pitch (input shaping predictor)")
LOIT_PRED_RATE = _c.add("LOIT_PRED_RATE", 2, "rad/s", "their rates")
LOIT_BRK = _c.add("LOIT_BRK", 1, "m/s^2", "applied braking acceleration")
LOIT_BRK_T = _c.add("LOIT_BRK_T", 1, "s", "when the stick last asked for an acceleration")
# POSHOLD per axis (0 roll, 1 pitch)
PH_STATE = _c.add("PH_STATE", 2, "", "axis state (pilot_modes PH_*)")
PH_PILOT = _c.add("PH_PILOT", 2, "cdeg", "smoothed pilot lean angle")
PH_BRAKE = _c.add("PH_BRAKE", 2, "cdeg", "brake angle")
PH_BRAKE_PEAK = _c.add("PH_BRAKE_PEAK", 2, "cdeg", "largest brake angle of this brake")
PH_BRAKE_T0 = _c.add("PH_BRAKE_T0", 2, "ms", "brake timer start")
PH_BRAKE_UPD = _c.add("PH_BRAKE_UPD", 2, "",
                      "1 once the brake angle has peaked (the brake time re-estimated from it)")
PH_C2P_T0 = _c.add("PH_C2P_T0", 2, "ms", "controller-to-pilot blend start")
PH_CTRL_OUT = _c.add("PH_CTRL_OUT", 2, "cdeg", "controller output kept for that blend")
PH_OUT = _c.add("PH_OUT", 2, "cdeg", "the axis' last output angle")
PH_B2L_T0 = _c.add("PH_B2L_T0", 1, "ms", "brake-to-loiter blend start")
PH_WIND = _c.add("PH_WIND", 2, "cm/s^2", "wind compensation, earth-frame acceleration NE")
PH_WIND_T0 = _c.add("PH_WIND_T0", 1, "ms", "wind compensation may learn after this")
PH_WIND_ANG = _c.add("PH_WIND_ANG", 2, "cdeg", "wind compensation as body roll, pitch")
# ACRO (body-rate input, AC_AttitudeControl::input_rate_bf_roll_pitch_yaw)
ATT_RATE_BF_IN = _c.add("ATT_RATE_BF_IN", 1, "",
                        "1: the attitude target turns at body rates (ACRO); 0: angle targets")
ATT_ANG_VEL_T = _c.add("ATT_ANG_VEL_T", 3, "rad/s",
                       "shaped body-rate target (roll, pitch, yaw; the target's frame, FRD)")
ACRO_RATE_CMD = _c.add("ACRO_RATE_CMD", 3, "rad/s",
                       "ACRO's desired body rates from the sticks and the trainer")
ACRO_LEVEL = _c.add("ACRO_LEVEL", 3, "rad/s", "ACRO trainer's levelling as body rates")
N_CONTROL_STATE = STATE.close()

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
SUB_PILOT = 9  # a pilot mode (STABILIZE, ALT_HOLD, LOITER, POSHOLD) flown from the sticks

# ------------------------------------------------------------ controller configuration g ------
CONFIG = Layout("g", "controller configuration")
_g = CONFIG
G_DT = _g.add("G_DT", 1, "s", "main-loop period")
G_RAT_P = _g.add("G_RAT_P", 3, "", "rate PID P per axis")
G_RAT_I = _g.add("G_RAT_I", 3, "", "rate PID I per axis")
G_RAT_D = _g.add("G_RAT_D", 3, "", "rate PID D per axis")
G_RAT_FF = _g.add("G_RAT_FF", 3, "", "rate PID feed-forward per axis")
G_RAT_IMAX = _g.add("G_RAT_IMAX", 3, "", "rate PID IMAX per axis")
G_RAT_FLTT = _g.add("G_RAT_FLTT", 3, "", "target filter alphas at the loop rate")
G_RAT_FLTE = _g.add("G_RAT_FLTE", 3, "", "error filter alphas at the loop rate")
G_RAT_FLTD = _g.add("G_RAT_FLTD", 3, "", "derivative filter alphas at the loop rate")
G_ANG_P = _g.add("G_ANG_P", 3, "1/s", "angle P per axis")
G_ACCEL_MAX = _g.add("G_ACCEL_MAX", 3, "rad/s^2",
                     "ATC_ACCEL_R/P/Y_MAX: input-shaping accel limits per axis (0 = none)")
G_ANG_ACCEL = _g.add("G_ANG_ACCEL", 3, "rad/s^2",
                     "angle controller's square-root accel limit per axis: half ATC_ACCEL_*_MAX "
                     "within 40..720 (roll, pitch) or 10..120 deg/s^2 (yaw); 0 = linear P")
G_INPUT_TC = _g.add("G_INPUT_TC", 1, "s", "ATC_INPUT_TC")
G_SLEW_YAW = _g.add("G_SLEW_YAW", 1, "rad/s", "ATC_SLEW_YAW")
G_ANGLE_MAX = _g.add("G_ANGLE_MAX", 1, "rad", "ANGLE_MAX")
G_THR_MIX_MIN = _g.add("G_THR_MIX_MIN", 1, "",
                       "ATC_THR_MIX_MIN: throttle vs attitude priority landed or descending")
G_THR_MIX_MAX = _g.add("G_THR_MIX_MAX", 1, "",
                       "ATC_THR_MIX_MAX: throttle vs attitude priority in active flight")
G_POSXY_P = _g.add("G_POSXY_P", 1, "1/s", "PSC_POSXY_P")
G_VELXY_P = _g.add("G_VELXY_P", 1, "1/s", "PSC_VELXY_P")
G_VELXY_I = _g.add("G_VELXY_I", 1, "", "PSC_VELXY_I")
G_VELXY_D = _g.add("G_VELXY_D", 1, "", "PSC_VELXY_D")
G_VELXY_IMAX = _g.add("G_VELXY_IMAX", 1, "m/s^2", "PSC_VELXY_IMAX")
G_VELXY_FLTE = _g.add("G_VELXY_FLTE", 1, "", "alpha")
G_VELXY_FLTD = _g.add("G_VELXY_FLTD", 1, "", "alpha")
G_POSZ_P = _g.add("G_POSZ_P", 1, "1/s", "PSC_POSZ_P")
G_VELZ_P = _g.add("G_VELZ_P", 1, "1/s", "PSC_VELZ_P")
G_ACCZ_P = _g.add("G_ACCZ_P", 1, "",
                  "throttle per cm/s^2 (ArduPilot units kept: x0.001 applied in code)")
G_ACCZ_I = _g.add("G_ACCZ_I", 1, "", "PSC_ACCZ_I")
G_ACCZ_IMAX = _g.add("G_ACCZ_IMAX", 1, "throttle units * 1000", "PSC_ACCZ_IMAX")
G_ACCZ_FLTE = _g.add("G_ACCZ_FLTE", 1, "", "alpha")
G_WP_SPEED = _g.add("G_WP_SPEED", 1, "m/s", "WPNAV_SPEED")
G_WP_ACCEL = _g.add("G_WP_ACCEL", 1, "m/s^2", "WPNAV_ACCEL")
G_WP_SPEED_UP = _g.add("G_WP_SPEED_UP", 1, "m/s", "WPNAV_SPEED_UP")
G_WP_SPEED_DN = _g.add("G_WP_SPEED_DN", 1, "m/s", "WPNAV_SPEED_DN")
G_WP_ACCEL_Z = _g.add("G_WP_ACCEL_Z", 1, "m/s^2", "WPNAV_ACCEL_Z")
G_WP_RADIUS = _g.add("G_WP_RADIUS", 1, "m", "WPNAV_RADIUS")
G_WP_JERK = _g.add("G_WP_JERK", 1, "m/s^3", "WPNAV_JERK")
G_RTL_ALT = _g.add("G_RTL_ALT", 1, "m", "RTL_ALT")
G_RTL_SPEED = _g.add("G_RTL_SPEED", 1, "m/s", "(0 -> WP speed)")
G_RTL_LOIT_TIME = _g.add("G_RTL_LOIT_TIME", 1, "s", "RTL_LOIT_TIME")
G_RTL_CONE_SLOPE = _g.add("G_RTL_CONE_SLOPE", 1, "", "RTL_CONE_SLOPE")
G_RTL_CLIMB_MIN = _g.add("G_RTL_CLIMB_MIN", 1, "m", "RTL_CLIMB_MIN")
G_LAND_SPEED = _g.add("G_LAND_SPEED", 1, "m/s", "LAND_SPEED")
G_LAND_SPEED_HIGH = _g.add("G_LAND_SPEED_HIGH", 1, "m/s", "(0 -> WP_SPEED_DN)")
G_LAND_ALT_LOW = _g.add("G_LAND_ALT_LOW", 1, "m", "LAND_ALT_LOW")
G_MOT_EXPO = _g.add("G_MOT_EXPO", 1, "", "MOT_THST_EXPO")
G_MOT_HOVER = _g.add("G_MOT_HOVER", 1, "", "MOT_THST_HOVER")
G_MOT_SPIN_ARM = _g.add("G_MOT_SPIN_ARM", 1, "", "MOT_SPIN_ARM")
G_MOT_SPIN_MIN = _g.add("G_MOT_SPIN_MIN", 1, "", "MOT_SPIN_MIN")
G_MOT_SPIN_MAX = _g.add("G_MOT_SPIN_MAX", 1, "", "MOT_SPIN_MAX")
G_MOT_PWM_MIN = _g.add("G_MOT_PWM_MIN", 1, "us", "MOT_PWM_MIN")
G_MOT_PWM_MAX = _g.add("G_MOT_PWM_MAX", 1, "us", "MOT_PWM_MAX")
G_MOT_BAT_MAX = _g.add("G_MOT_BAT_MAX", 1, "V", "MOT_BAT_VOLT_MAX")
G_MOT_BAT_MIN = _g.add("G_MOT_BAT_MIN", 1, "V", "MOT_BAT_VOLT_MIN")
G_MOT_YAW_HEADROOM = _g.add("G_MOT_YAW_HEADROOM", 1, "", "fraction")
G_N_MOTORS = _g.add("G_N_MOTORS", 1, "", "motors of the frame (FRAME_CLASS / FRAME_TYPE)")
G_MIX_ROLL = _g.add("G_MIX_ROLL", MAX_MOTORS, "",
                    "mixer roll factor per motor, largest magnitude 0.5 (tlm_sim.frames)")
G_MIX_PITCH = _g.add("G_MIX_PITCH", MAX_MOTORS, "", "mixer pitch factor per motor")
G_MIX_YAW = _g.add("G_MIX_YAW", MAX_MOTORS, "", "mixer yaw factor per motor (+0.5 CCW)")
G_FS_THR_ENABLE = _g.add("G_FS_THR_ENABLE", 1, "", "FS_THR_ENABLE")
G_RC_FS_TIMEOUT = _g.add("G_RC_FS_TIMEOUT", 1, "s", "RC_FS_TIMEOUT")
G_ARM_TIME = _g.add("G_ARM_TIME", 1, "s", "simulated time at which the vehicle arms")
G_HOVER_LEARN = _g.add("G_HOVER_LEARN", 1, "", "MOT_HOVER_LEARN")
G_WP_LEG_K = _g.add("G_WP_LEG_K", 1, "", "S-curve leg-speed calibration factor")
G_FS_CRASH_CHECK = _g.add("G_FS_CRASH_CHECK", 1, "", "FS_CRASH_CHECK")
G_ACCEL_XY_MAX = _g.add("G_ACCEL_XY_MAX", 1, "m/s^2",
                        "g * tan(ANGLE_MAX): horizontal acceleration limit")
G_HRT_OMEGA = _g.add("G_HRT_OMEGA", 1, "rad/s",
                     "2 pi EK3_HRT_FILT: height-rate complementary filter crossover")
G_FS_VIBE_ENABLE = _g.add("G_FS_VIBE_ENABLE", 1, "", "FS_VIBE_ENABLE")
G_FS_EKF_THRESH = _g.add("G_FS_EKF_THRESH", 1, "", "FS_EKF_THRESH")
G_FS_EKF_ACTION = _g.add("G_FS_EKF_ACTION", 1, "", "FS_EKF_ACTION")
G_FS_EKF_ALPHA = _g.add("G_FS_EKF_ALPHA", 1, "",
                        "FS_EKF_FILT low-pass coefficient at the 10 Hz check rate")
G_RHO_RATIO_HOME = _g.add("G_RHO_RATIO_HOME", 1, "",
                          "air density / 1.225 at home (1976 atmosphere, SIM_OPOS_ALT)")
G_RHO_RATIO_GRAD = _g.add("G_RHO_RATIO_GRAD", 1, "1/m", "its change per metre of height above home")
G_BATT_SAG_HOVER = _g.add("G_BATT_SAG_HOVER", 1, "V",
                          "battery monitor's resting-voltage estimate minus voltage at hover")
G_ANG_LIM_ALPHA = _g.add("G_ANG_LIM_ALPHA", 1, "",
                         "ATC_ANG_LIM_TC low-pass coefficient at the loop rate")
G_YAW_ERR_MAX = _g.add("G_YAW_ERR_MAX", 1, "rad",
                       "largest heading error the attitude controller acts on")
G_POSXY_ERR_MAX = _g.add("G_POSXY_ERR_MAX", 1, "m",
                         "largest horizontal position error the position controller acts on")
G_POSZ_ERR_UP = _g.add("G_POSZ_ERR_UP", 1, "m",
                       "largest vertical position error (target above) it acts on")
G_POSZ_ERR_DN = _g.add("G_POSZ_ERR_DN", 1, "m",
                       "largest vertical position error (target below) it acts on")
G_FS_THR_VALUE = _g.add("G_FS_THR_VALUE", 1, "us", "FS_THR_VALUE")
G_BATT_CAPACITY = _g.add("G_BATT_CAPACITY", 1, "mAh", "BATT_CAPACITY")
G_BATT_LOW_VOLT = _g.add("G_BATT_LOW_VOLT", 1, "V", "BATT_LOW_VOLT")
G_BATT_CRT_VOLT = _g.add("G_BATT_CRT_VOLT", 1, "V", "BATT_CRT_VOLT")
G_BATT_LOW_TIMER = _g.add("G_BATT_LOW_TIMER", 1, "s", "BATT_LOW_TIMER")
G_BATT_LOW_MAH = _g.add("G_BATT_LOW_MAH", 1, "mAh", "BATT_LOW_MAH")
G_BATT_CRT_MAH = _g.add("G_BATT_CRT_MAH", 1, "mAh", "BATT_CRT_MAH")
G_BATT_FS_LOW_ACT = _g.add("G_BATT_FS_LOW_ACT", 1, "", "BATT_FS_LOW_ACT")
G_BATT_FS_CRT_ACT = _g.add("G_BATT_FS_CRT_ACT", 1, "", "BATT_FS_CRT_ACT")
G_BATT_RES0 = _g.add("G_BATT_RES0", 1, "ohm",
                     "battery monitor's starting resistance estimate: TLM_BATT_SAG_HOV at the "
                     "frame's hover current TLM_REF_CURR")
G_BOOT = _g.add("G_BOOT", 1, "", "TLM_BOOT_PHASE")
G_DRIVER_T = _g.add("G_DRIVER_T", 1, "s", "the driver switches to GUIDED")
G_ARM_FIRST = _g.add("G_ARM_FIRST", 1, "s", "the driver's first arm attempt")
G_ARM_SECOND = _g.add("G_ARM_SECOND", 1, "s", "its second; then one every ARM_RETRY_S")
G_ARM_GIVE_UP = _g.add("G_ARM_GIVE_UP", 1, "s", "no attempt after this: the flight ends unarmed")
G_PREARM_FIRST = _g.add("G_PREARM_FIRST", 1, "s", "first 1 Hz pre-arm check")
G_ARMING_CHECK = _g.add("G_ARMING_CHECK", 1, "", "ARMING_CHECK bit mask")
G_ACC_THRESH = _g.add("G_ACC_THRESH", 1, "m/s^2", "ARMING_ACCTHRESH")
G_HDOP_GOOD = _g.add("G_HDOP_GOOD", 1, "", "GPS_HDOP_GOOD / 100")
G_BATT_ARM_VOLT = _g.add("G_BATT_ARM_VOLT", 1, "V", "BATT_ARM_VOLT")
# the DCM attitude estimator (tlm_sim.control.dcm)
G_AHRS_RP_P = _g.add("G_AHRS_RP_P", 1, "", "AHRS_RP_P (DCM roll/pitch gain, floor 0.05)")
G_AHRS_YAW_P = _g.add("G_AHRS_YAW_P", 1, "", "AHRS_YAW_P (DCM yaw gain, floor 0.05)")
G_AHRS_GPS_GAIN = _g.add("G_AHRS_GPS_GAIN", 1, "", "AHRS_GPS_GAIN")
G_AHRS_GPS_MINSATS = _g.add("G_AHRS_GPS_MINSATS", 1, "", "AHRS_GPS_MINSATS")
G_AHRS_GPS_USE = _g.add("G_AHRS_GPS_USE", 1, "", "AHRS_GPS_USE (0 none, 1, 2 also height)")
G_MAG_DEC = _g.add("G_MAG_DEC", 1, "rad",
                   "magnetic declination the compass library applies (COMPASS_AUTODEC: the "
                   "field's, TLM_MAG_DEC_DEG)")
G_GPS_LAG = _g.add("G_GPS_LAG", 1, "s", "GPS lag the AHRS assumes (GPS1_DELAY_MS or 120 ms)")
G_THR_FILT_A = _g.add("G_THR_FILT_A", 1, "",
                      "motors' throttle filter alpha per main-loop tick (2 Hz: "
                      "POSCONTROL_THROTTLE_CUTOFF_FREQ_HZ)")
G_SLEW_FILT_A = _g.add("G_SLEW_FILT_A", 1, "",
                       "throttle slew-rate filter alpha per main-loop tick (50 Hz: "
                       "AP_MOTORS_SLEW_FILTER_CUTOFF)")
# the pilot's modes and receiver (tlm_sim.control.pilot; used when G_PILOT is 1)
G_PILOT = _g.add("G_PILOT", 1, "", "1: flown from the RC input (a stick script or RCIN replay)")
G_RC_MAP = _g.add("G_RC_MAP", 4, "", "0-based channel of roll, pitch, throttle, yaw (RCMAP_*)")
G_RC_MIN = _g.add("G_RC_MIN", 4, "us", "RCn_MIN of roll, pitch, throttle, yaw")
G_RC_MAX = _g.add("G_RC_MAX", 4, "us", "RCn_MAX")
G_RC_TRIM = _g.add("G_RC_TRIM", 4, "us", "RCn_TRIM")
G_RC_DZ = _g.add("G_RC_DZ", 4, "us", "RCn_DZ")
G_RC_REV = _g.add("G_RC_REV", 4, "", "RCn_REVERSED")
G_FLTMODE = _g.add("G_FLTMODE", 6, "", "FLTMODE1..6")
G_FLTMODE_CH = _g.add("G_FLTMODE_CH", 1, "", "FLTMODE_CH, 0-based (-1: none)")
G_PILOT_SPEED_UP = _g.add("G_PILOT_SPEED_UP", 1, "m/s", "PILOT_SPEED_UP")
G_PILOT_SPEED_DN = _g.add("G_PILOT_SPEED_DN", 1, "m/s", "PILOT_SPEED_DN (0 -> PILOT_SPEED_UP)")
G_PILOT_ACCEL_Z = _g.add("G_PILOT_ACCEL_Z", 1, "m/s^2", "PILOT_ACCEL_Z")
G_PILOT_JERK_Z = _g.add("G_PILOT_JERK_Z", 1, "m/s^3", "PSC_JERK_Z")
G_PILOT_POSZ_ERR_UP = _g.add("G_PILOT_POSZ_ERR_UP", 1, "m",
                             "largest vertical position error (target above) in pilot modes")
G_PILOT_POSZ_ERR_DN = _g.add("G_PILOT_POSZ_ERR_DN", 1, "m", "... (target below)")
G_PILOT_Y_RATE = _g.add("G_PILOT_Y_RATE", 1, "rad/s", "PILOT_Y_RATE")
G_PILOT_Y_EXPO = _g.add("G_PILOT_Y_EXPO", 1, "", "PILOT_Y_EXPO")
G_PILOT_Y_TC = _g.add("G_PILOT_Y_TC", 1, "s", "PILOT_Y_RATE_TC")
G_THR_DZ = _g.add("G_THR_DZ", 1, "", "THR_DZ in throttle control_in units (0..400)")
G_THR_MID = _g.add("G_THR_MID", 1, "", "mid-stick throttle control_in (get_control_mid)")
G_TKOFF_ALT = _g.add("G_TKOFF_ALT", 1, "m", "PILOT_TKOFF_ALT")
G_TKOFF_SLEW = _g.add("G_TKOFF_SLEW", 1, "s", "TKOFF_SLEW_TIME")
G_TKOFF_THR_MAX = _g.add("G_TKOFF_THR_MAX", 1, "", "TKOFF_THR_MAX")
G_ARMING_RUDDER = _g.add("G_ARMING_RUDDER", 1, "", "ARMING_RUDDER (0 off, 1 arm, 2 arm/disarm)")
G_DISARM_DELAY = _g.add("G_DISARM_DELAY", 1, "s", "DISARM_DELAY (0: no auto-disarm)")
G_LOIT_ANG_MAX = _g.add("G_LOIT_ANG_MAX", 1, "rad", "LOITER's lean angle limit")
G_LOIT_SPEED = _g.add("G_LOIT_SPEED", 1, "m/s", "LOIT_SPEED")
G_LOIT_ACC_MAX = _g.add("G_LOIT_ACC_MAX", 1, "m/s^2", "LOIT_ACC_MAX (position correction)")
G_LOIT_BRK_ACCEL = _g.add("G_LOIT_BRK_ACCEL", 1, "m/s^2", "LOIT_BRK_ACCEL")
G_LOIT_BRK_JERK = _g.add("G_LOIT_BRK_JERK", 1, "m/s^3", "LOIT_BRK_JERK")
G_LOIT_BRK_DELAY = _g.add("G_LOIT_BRK_DELAY", 1, "s", "LOIT_BRK_DELAY")
G_LOIT_ERR_MAX = _g.add("G_LOIT_ERR_MAX", 1, "m", "LOITER's largest position error acted on")
G_THR_MIX_MAN = _g.add("G_THR_MIX_MAN", 1, "", "ATC_THR_MIX_MAN")
G_PHLD_BRAKE_RATE = _g.add("G_PHLD_BRAKE_RATE", 1, "deg/s", "PHLD_BRAKE_RATE (at least 4)")
G_PHLD_BRAKE_ANGLE = _g.add("G_PHLD_BRAKE_ANGLE", 1, "cdeg", "PHLD_BRAKE_ANGLE")
G_ACRO_RP_RATE = _g.add("G_ACRO_RP_RATE", 1, "rad/s", "ACRO_RP_RATE")
G_ACRO_RP_EXPO = _g.add("G_ACRO_RP_EXPO", 1, "", "ACRO_RP_EXPO")
G_ACRO_Y_RATE = _g.add("G_ACRO_Y_RATE", 1, "rad/s", "ACRO_Y_RATE")
G_ACRO_Y_EXPO = _g.add("G_ACRO_Y_EXPO", 1, "", "ACRO_Y_EXPO")
G_ACRO_TC = _g.add("G_ACRO_TC", 3, "s",
                   "body-rate input time constants: ACRO_RP_RATE_TC (roll, pitch), ACRO_Y_RATE_TC")
G_ACRO_TRAINER = _g.add("G_ACRO_TRAINER", 1, "", "ACRO_TRAINER (0 off, 1 leveling, 2 limited)")
G_ACRO_BAL = _g.add("G_ACRO_BAL", 2, "1/s", "ACRO_BAL_ROLL, ACRO_BAL_PITCH")
G_ACRO_THR_MID = _g.add("G_ACRO_THR_MID", 1, "", "ACRO_THR_MID (0: the hover throttle)")
N_CONTROL_CFG = CONFIG.close()
