"""ArduPilot's vocabulary, declared once: the numbers an ArduCopter log and a mission speak.

Every module of ``tlm_sim`` and ``tlm_process`` that writes or reads one of these codes imports
it from here (``tests/test_ardupilot_vocabulary.py`` greps the sources for stray literals):

* physical constants: :data:`GRAVITY_MSS`, :data:`M_PER_DEG_LAT`;
* the scheduler: the physics and main-loop rates, the main loop's task rates
  (:data:`TASK_RATES_HZ`);
* DataFlash framing: the message header bytes and the FMT message's type id;
* MAVLink mission vocabulary: ``MAV_CMD_*`` ids and ``MAV_FRAME_*`` frames;
* ArduCopter flight modes (``MODE.ModeNum``) and mode-change reasons (``MODE.Rsn``,
  ``ModeReason``);
* log events (``EV.Id``, AP_Logger's ``LogEvent``);
* error subsystems and codes (``ERR.Subsys`` / ``ERR.ECode``, ``LogErrorSubsystem`` /
  ``LogErrorCode``);
* ``ARMING_CHECK`` bits, and tlm's text log: the failing pre-arm / arm check bits of a text
  row's mask, the row's columns and kinds (the flight loop writes the rows,
  :mod:`tlm_sim.flightlog.texts` renders them as ArduCopter's MSG lines).

All values are plain ``int``/``float`` module constants, so numba folds them into the flight
loop's machine code; the ``*_NAMES`` tables are for Python (readers, reports, plots). The
numbers are facts of ArduPilot's public interfaces (log messages, MAVLink), restated here.
"""

from __future__ import annotations

from tlm_sim.slots import Layout

# ----------------------------------------------------------------------- physical constants
#: standard gravity [m/s²] (AP_Math GRAVITY_MSS)
GRAVITY_MSS: float = 9.80665
#: metres per degree of latitude (ArduPilot's LOCATION_SCALING_FACTOR x 1e7) [m/deg]
M_PER_DEG_LAT: float = 111318.84502145034

# ----------------------------------------------------------------------- the scheduler
#: SITL's physics rate [Hz] (SIM_RATE_HZ: 833 us ticks) and ArduCopter's main-loop rate [Hz]
#: (SCHED_LOOP_RATE): the only rates tlm runs (tlm_sim.params pins both parameters to them)
SIM_RATE_HZ = 1200
LOOP_RATE_HZ = 400
#: SITL's RC input when no pilot sends anything: channels 1..8 [us PWM] (roll, pitch centred,
#: throttle down, yaw centred, the mode switch at position 6, then 1000, 1000, 1800)
RC_IDLE_PWM = (1500.0, 1500.0, 1000.0, 1500.0, 1800.0, 1000.0, 1000.0, 1800.0)
#: The periodic tasks of tlm's main loop and their rates [Hz] (ArduCopter's scheduler table
#: names where it has the task). Each runs every ``LOOP_RATE_HZ / rate`` main-loop ticks:
#: tlm_sim.flight's ``*_TICKS`` / ``*_PERIOD_US`` constants come from here, and each logged
#: message's schema rate (tlm_sim.flightlog.schema ``rate_hz``) is the rate of the task that
#: writes it (tests/test_log_messages.py checks both against a flight).
TASK_RATES_HZ: dict[str, int] = {
    "gpsglitch_check": 10,  # the GPS glitch ERR check
    "update_altitude": 10,  # the barometers read
    "update_batt_compass": 10,  # the compasses read
    "sim_state_logging": 50,  # SITL's SIM2, at LOG_FILE_RATEMAX
    "twentyfive_hz_logging": 25,  # IMU, both instances
    "ten_hz_logging_loop": 10,  # every other periodic message (ATT, RATE, XKF*, CTUN, ...)
    "ekf_variance_logging": 2,  # XKV1/XKV2 (EKF3 logs them from the 10 Hz logging once its
    # last are older than tlm_sim.ekf.log.XKV_INTERVAL_S)
}

# ----------------------------------------------------------------------- DataFlash framing
#: the two bytes that start every DataFlash message
HEAD1, HEAD2 = 0xA3, 0x95
#: message type id of FMT, the message that describes every other message
FMT_TYPE = 128

# ----------------------------------------------------------------------- MAVLink missions
MAV_CMD_NAV_WAYPOINT = 16
MAV_CMD_NAV_LOITER_TIME = 19
MAV_CMD_NAV_RETURN_TO_LAUNCH = 20
MAV_CMD_NAV_LAND = 21
MAV_CMD_NAV_TAKEOFF = 22
MAV_CMD_DO_CHANGE_SPEED = 178
#: AP_Mission's short names of the commands tlm's missions hold (the "Mission: k <type>" text)
MAV_CMD_TYPES: dict[int, str] = {
    MAV_CMD_NAV_WAYPOINT: "WP", MAV_CMD_NAV_LOITER_TIME: "LoitTime",
    MAV_CMD_NAV_RETURN_TO_LAUNCH: "RTL", MAV_CMD_NAV_LAND: "Land",
    MAV_CMD_NAV_TAKEOFF: "Takeoff", MAV_CMD_DO_CHANGE_SPEED: "ChangeSpeed"}

MAV_FRAME_GLOBAL = 0
MAV_FRAME_GLOBAL_RELATIVE_ALT = 3
MAV_FRAME_GLOBAL_INT = 5
MAV_FRAME_GLOBAL_RELATIVE_ALT_INT = 6

# ----------------------------------------------------------------------- flight modes
MODE_STABILIZE = 0
MODE_ACRO = 1
MODE_ALT_HOLD = 2
MODE_AUTO = 3
MODE_GUIDED = 4
MODE_LOITER = 5
MODE_RTL = 6
MODE_LAND = 9
MODE_POSHOLD = 16
#: ArduCopter's mode numbers -> names (as pymavlink and Mission Planner print them)
MODE_NAMES: dict[int, str] = {
    0: "STABILIZE", 1: "ACRO", 2: "ALT_HOLD", 3: "AUTO", 4: "GUIDED", 5: "LOITER", 6: "RTL",
    7: "CIRCLE", 8: "POSITION", 9: "LAND", 10: "OF_LOITER", 11: "DRIFT", 13: "SPORT",
    14: "FLIP", 15: "AUTOTUNE", 16: "POSHOLD", 17: "BRAKE", 18: "THROW", 19: "AVOID_ADSB",
    20: "GUIDED_NOGPS", 21: "SMART_RTL", 22: "FLOWHOLD", 23: "FOLLOW", 24: "ZIGZAG",
    25: "SYSTEMID", 26: "AUTOROTATE", 27: "AUTO_RTL", 28: "TURTLE", 29: "RATE_ACRO"}

# mode-change reasons (ModeReason)
RSN_UNKNOWN = 0
RSN_RC_COMMAND = 1
RSN_GCS = 2
RSN_RADIO_FAILSAFE = 3
RSN_BATTERY_FAILSAFE = 4
RSN_EKF_FAILSAFE = 6
RSN_MISSION_END = 8
RSN_CRASH_FAILSAFE = 19
RSN_INITIALISED = 26  # the boot mode
#: the mode-change reasons ArduCopter uses -> names
MODE_REASONS: dict[int, str] = {
    0: "UNKNOWN", 1: "RC_COMMAND", 2: "GCS_COMMAND", 3: "RADIO_FAILSAFE",
    4: "BATTERY_FAILSAFE", 5: "GCS_FAILSAFE", 6: "EKF_FAILSAFE", 7: "GPS_GLITCH",
    8: "MISSION_END", 9: "THROTTLE_LAND_ESCAPE", 10: "FENCE_BREACHED", 11: "TERRAIN_FAILSAFE",
    19: "CRASH_FAILSAFE", 25: "FAILSAFE", 26: "INITIALISED", 50: "DEADRECKON_FAILSAFE",
}

# AP_Arming::Method (ARM.Method)
ARM_METHOD_RUDDER = 0  # the yaw-stick gesture (pilot-flown flights)
ARM_METHOD_MAVLINK = 1  # the GCS arms (the reference driver, tlm's TLM_ARM_TIME)
ARM_METHOD_BATTERYFAILSAFE = 7
ARM_METHOD_CRASH = 12
ARM_METHOD_LANDED = 13  # LAND / RTL mode: the land detector
ARM_METHOD_MISSIONEXIT = 14  # AUTO: landed at the end of the mission (its RTL item)
ARM_METHOD_RADIOFAILSAFE = 16  # the radio failsafe on the ground (should_disarm_on_failsafe)
ARM_METHOD_DISARMDELAY = 17  # auto-disarm: landed with the throttle low for DISARM_DELAY
ARM_METHOD_TERMINATE = 20  # FAILSAFE_ACTION_TERMINATE

# Copter::LandDetectorLoggingFlag (LDET.Flags bits)
LDET_LANDED = 1
LDET_LANDED_MAYBE = 2
LDET_WOW = 16  # no weight-on-wheels sensor: always set while the detector runs
LDET_RANGEFINDER_BELOW_2M = 32  # no rangefinder: always set while the detector runs
LDET_DESCENT_RATE_LOW = 64
LDET_ACCEL_STATIONARY = 128
LDET_LARGE_ANGLE = 256  # large angle request or large angle error (one bit in ArduCopter)
LDET_MOTOR_AT_LOWER_LIMIT = 512
LDET_THROTTLE_MIX_AT_MIN = 1024

# ----------------------------------------------------------------------- log events (EV.Id)
EV_ARMED = 10
EV_DISARMED = 11
EV_AUTO_ARMED = 15
EV_LAND_COMPLETE_MAYBE = 17
EV_LAND_COMPLETE = 18
EV_SET_HOME = 25
EV_NOT_LANDED = 28
EV_EKF_YAW_RESET = 62
#: the events tlm writes or reads -> names
EV_NAMES: dict[int, str] = {
    EV_ARMED: "ARMED", EV_DISARMED: "DISARMED", EV_AUTO_ARMED: "AUTO_ARMED",
    EV_LAND_COMPLETE_MAYBE: "LAND_COMPLETE_MAYBE", EV_LAND_COMPLETE: "LAND_COMPLETE",
    EV_SET_HOME: "SET_HOME", EV_NOT_LANDED: "NOT_LANDED", EV_EKF_YAW_RESET: "EKF_YAW_RESET"}

# ----------------------------------------------------------------------- errors (ERR)
# subsystems (LogErrorSubsystem)
ERR_RADIO = 2
ERR_COMPASS = 3
ERR_FAILSAFE_RADIO = 5
ERR_FAILSAFE_BATT = 6
ERR_FAILSAFE_GPS = 7
ERR_GPS = 11
ERR_CRASH_CHECK = 12
ERR_EKFCHECK = 16
ERR_FAILSAFE_EKFINAV = 17
ERR_BARO = 18
ERR_EKF_PRIMARY = 24  # ECode: the new primary lane
ERR_THRUST_LOSS_CHECK = 25
ERR_FAILSAFE_VIBE = 29
#: the subsystems tlm writes or follows -> names
ERR_SUBSYSTEM_NAMES: dict[int, str] = {
    ERR_RADIO: "RADIO", ERR_COMPASS: "COMPASS", ERR_FAILSAFE_RADIO: "FAILSAFE_RADIO",
    ERR_FAILSAFE_BATT: "FAILSAFE_BATT", ERR_FAILSAFE_GPS: "FAILSAFE_GPS", ERR_GPS: "GPS",
    ERR_CRASH_CHECK: "CRASH_CHECK", ERR_EKFCHECK: "EKFCHECK",
    ERR_FAILSAFE_EKFINAV: "FAILSAFE_EKFINAV", ERR_BARO: "BARO", ERR_EKF_PRIMARY: "EKF_PRIMARY",
    ERR_THRUST_LOSS_CHECK: "THRUST_LOSS_CHECK", ERR_FAILSAFE_VIBE: "FAILSAFE_VIBE"}
# codes (LogErrorCode); their meaning depends on the subsystem
ERR_CODE_RESOLVED = 0  # ERROR_RESOLVED, FAILSAFE_RESOLVED
ERR_CODE_FAILSAFE = 1  # FAILSAFE_OCCURRED (FAILED_TO_INITIALISE, CRASH_CHECK_CRASH)
ERR_CODE_LATE_FRAME = 2  # RADIO_LATE_FRAME
ERR_CODE_GPS_GLITCH = 2  # GPS_GLITCH
ERR_CODE_EKF_BAD_VARIANCE = 2  # EKFCHECK_BAD_VARIANCE
ERR_CODE_UNHEALTHY = 4  # UNHEALTHY

# ----------------------------------------------------------------------- arming
# ARMING_CHECK bits (AP_Arming::Check)
CHK_ALL, CHK_BARO, CHK_COMPASS, CHK_GPS, CHK_INS = 1, 2, 4, 8, 16
CHK_RC, CHK_VOLTAGE, CHK_BATTERY = 64, 128, 256

# failing checks: bits of a text row's mask, in the order ArduCopter reports them
F_RC_NOT_FOUND = 1 << 0  # "RC not found"
F_THR_LOW = 1 << 1  # "Throttle below failsafe"
F_NEED_ALT = 1 << 2  # "Need Alt Estimate"
F_BARO = 1 << 3  # "Baro: not healthy"
F_ALT_DISPARITY = 1 << 4  # "Altitude disparity"
F_GYRO_HEALTH = 1 << 5  # "Gyros not healthy"
F_ACC_HEALTH = 1 << 6  # "Accels not healthy"
F_ACC_INCONS = 1 << 7  # "Accels inconsistent"
F_GYRO_INCONS = 1 << 8  # "Gyros inconsistent"
F_EKF_ATTITUDE = 1 << 9  # "EKF attitude is bad"
F_COMPASS_HEALTH = 1 << 10  # "Compass not healthy"
F_MAG_FIELD = 1 << 11  # "Check mag field: %4.0f, max 875, min 185" (A_MAG_FIELD)
F_COMPASS_INCONS = 1 << 12  # "Compasses inconsistent"
F_GPS_FIX = 1 << 13  # "GPS 1: Bad fix"
F_WAIT_HOME = 1 << 14  # "AHRS: waiting for home"
F_GPS_AHRS = 1 << 15  # "GPS and AHRS differ by %4.1fm" (A_GPS_AHRS)
F_AHRS = 1 << 16  # "AHRS: EKF3 not started" / "AHRS: EKF3 core %d unhealthy" (A_LANE)
F_NEED_POS = 1 << 17  # "Need Position Estimate"
F_GPS_GLITCH = 1 << 18  # "GPS glitching"
F_EKF_VARIANCE = 1 << 19  # "EKF %s variance" (A_VARIANCE)
F_HDOP = 1 << 20  # "High GPS HDOP"
F_BATTERY = 1 << 21  # "Battery 1 %s" (A_BATTERY)
F_BATT_FS = 1 << 22  # "Battery failsafe"
F_ARM_AHRS = 1 << 23  # arm only: "AHRS not healthy"
F_ARM_COMPASS = 1 << 24  # arm only: "Compass not healthy"
F_ARM_LEANING = 1 << 25  # arm only: "Leaning"
N_FAIL_BITS = 26

#: the compass field strength the arming check accepts [mGauss]
#: (AP_ARMING_COMPASS_MAGFIELD_MIN / _MAX)
MAG_FIELD_MIN = 185.0
MAG_FIELD_MAX = 875.0

# ----------------------------------------------------------------------- tlm's text log
#: a row's columns: (TimeUS, kind, mask, then the aux values A_*, the row's tail);
#: FlightLog.meta["texts"]
TEXT_ROW = Layout("txt", "a row of tlm's text log (the flight loop's txt array)")
TXT_TIME = TEXT_ROW.add("TXT_TIME", 1, "us", "time of the text")
TXT_KIND = TEXT_ROW.add("TXT_KIND", 1, "", "what the row reports (KIND_*)")
TXT_MASK = TEXT_ROW.add("TXT_MASK", 1, "", "the failing checks (F_* bits), or a KIND_EKF "
                        "row's EKF_EVT_* bit")
A_GPS_AHRS = TEXT_ROW.add("A_GPS_AHRS", 1, "m", "aux: distance of GPS and AHRS (F_GPS_AHRS)")
A_MAG_FIELD = TEXT_ROW.add("A_MAG_FIELD", 1, "mGauss", "aux: the compass field strength "
                           "(F_MAG_FIELD); a KIND_EKF row's compass, KIND_FIELD_ELEV's "
                           "elevation [m]")
A_LANE = TEXT_ROW.add("A_LANE", 1, "", "aux: the unhealthy EKF lane (F_AHRS, or "
                      "AHRS_NOT_STARTED); a KIND_EKF row's IMU")
A_VARIANCE = TEXT_ROW.add("A_VARIANCE", 1, "", "aux: which EKF variance (F_EKF_VARIANCE, "
                          "VAR_*)")
A_BATTERY = TEXT_ROW.add("A_BATTERY", 1, "", "aux: the battery failsafe level (F_BATTERY, "
                         "BATT_*)")
N_TXT_COLS = TEXT_ROW.close()
TXT_ROWS = 512
KIND_ARM = 0  # a failed arm attempt: "Arm: ..." per failing check
KIND_PREARM = 1  # the periodic report: "PreArm: ..."
KIND_EKF = 2  # an EKF lifecycle event: mask = its EKF_EVT_* bit, A_LANE the lane's IMU,
# A_MAG_FIELD its compass
KIND_AHRS_ACTIVE = 3  # "AHRS: EKF3 active"
KIND_FIELD_ELEV = 4  # "Field Elevation Set: %.0fm" (A_MAG_FIELD: the elevation [m])
# A_VARIANCE codes: which EKF variance (ArduCopter's order); A_BATTERY codes
VAR_COMPASS, VAR_POSITION, VAR_VELOCITY, VAR_HEIGHT = 0, 1, 2, 3
BATT_BELOW_ARM_VOLT, BATT_LOW_VOLT, BATT_LOW_CAP, BATT_CRT_VOLT, BATT_CRT_CAP = 0, 1, 2, 3, 4
# A_LANE codes of F_AHRS beyond the lane index
AHRS_NOT_STARTED = -1.0

# EKF3 lifecycle events of a lane (bits; the mask of a KIND_EKF text row)
EKF_EVT_INIT = 1  # "EKF3 IMU%d initialised"
EKF_EVT_TILT = 2  # "EKF3 IMU%d tilt alignment complete"
EKF_EVT_YAW = 4  # "EKF3 IMU%d MAG%d initial yaw alignment complete"
EKF_EVT_ORIGIN = 8  # "EKF3 IMU%d origin set"
EKF_EVT_USING_GPS = 16  # "EKF3 IMU%d is using GPS"
EKF_EVT_STOPPED = 32  # "EKF3 IMU%d stopped aiding"
EKF_EVT_INFLIGHT_YAW = 64  # "EKF3 IMU%d MAG%d in-flight yaw alignment complete"
N_EKF_EVT = 7
