"""Slots of the sensor state ``s`` and sensor configuration ``scfg`` arrays, declared once
(:class:`tlm_sim.slots.Layout`; ``STATE.describe(s)``, ``CONFIG.describe(scfg)``).

The sensor state holds, per IMU instance, the accumulators handed to the EKF each main-loop tick,
the autopilot's 20 Hz low-pass filter states, the VIBE metric filters and the clip counters; plus
the GPS delay line, baro, the three compasses (one record each: what the EKF reads) and RC
receiver state. Units: SI (m, m/s, m/s^2, rad, rad/s),
body frame FRD, earth frame NED.
"""

from tlm_sim.frames import MAX_MOTORS
from tlm_sim.slots import Layout

N_IMU = 2
N_BARO = 2  # SIM_BARO_COUNT 2: BARO 1 (SIM_BARO_*) and BARO 2 (SIM_BAR2_*); BARO 3 is not modelled
N_MAG = 3  # compasses, as SITL's copter has them

# ---- per-IMU record (at IMU_BASE + i * IMU_STRIDE) -------------------------------------------
IMU = Layout("imu", "one IMU instance")
_i = IMU
I_DANG = _i.add("I_DANG", 3, "rad", "accumulated delta angle since the last main-loop tick")
I_DVEL = _i.add("I_DVEL", 3, "m/s", "accumulated delta velocity since the last main-loop tick")
I_GYR_F = _i.add("I_GYR_F", 3, "rad/s",
                 "low-pass filtered gyro: what controllers and the IMU log see")
I_ACC_F = _i.add("I_ACC_F", 3, "m/s/s", "low-pass filtered accel")
I_GYR_LPF = _i.add("I_GYR_LPF", 6, "", "biquad delay elements, gyro (3 axes x 2)")
I_ACC_LPF = _i.add("I_ACC_LPF", 6, "", "biquad delay elements, accel (3 axes x 2)")
I_VIB_FLOOR = _i.add("I_VIB_FLOOR", 3, "m/s/s", "VIBE 5 Hz floor filter")
I_VIB_SQ = _i.add("I_VIB_SQ", 3, "m^2/s^4", "VIBE 2 Hz filter of the squared deviation")
I_CLIP = _i.add("I_CLIP", 1, "", "accel clip count")
I_NEXT_GYR_US = _i.add("I_NEXT_GYR_US", 1, "us", "time of the next gyro sample")
I_NEXT_ACC_US = _i.add("I_NEXT_ACC_US", 1, "us", "time of the next accel sample")
I_LAST_GYR = _i.add("I_LAST_GYR", 3, "rad/s", "last raw gyro sample")
I_LAST_ACC = _i.add("I_LAST_ACC", 3, "m/s/s", "last raw accel sample")
I_GYR_COUNT = _i.add("I_GYR_COUNT", 1, "", "gyro samples accumulated this tick")
I_ACC_COUNT = _i.add("I_ACC_COUNT", 1, "", "accel samples accumulated this tick")
I_EG = _i.add("I_EG", 1, "", "gyro error count")
I_EA = _i.add("I_EA", 1, "", "accel error count")
I_ACC_OK = _i.add("I_ACC_OK", 1, "",
                  "accel health (IMU.AH): 1 when it delivered a sample in the last main-loop tick")
I_T_SAMPLE_US = _i.add("I_T_SAMPLE_US", 1, "us", "physics time of the latest sampling call")
I_T_TAKE_US = _i.add("I_T_TAKE_US", 1, "us",
                     "physics time at which the EKF last took the deltas (-1: never)")
I_GYR_OK = _i.add("I_GYR_OK", 1, "",
                  "gyro health (IMU.GH): 1 when it delivered a sample in the last main-loop tick")
I_ACC_PHASE = _i.add("I_ACC_PHASE", MAX_MOTORS, "rad",
                     "motor vibration phase per motor, accelerometer (SITL's accel_motor_phase)")
I_GYR_PHASE = _i.add("I_GYR_PHASE", MAX_MOTORS, "rad",
                     "motor vibration phase per motor, gyro (SITL's gyro_motor_phase)")
I_GYR_WALK = _i.add("I_GYR_WALK", 3, "rad/s", "gyro bias random walk (TLM_GYR_WALK)")
I_ACC_WALK = _i.add("I_ACC_WALK", 3, "m/s^2", "accel bias random walk (TLM_ACC_WALK)")
IMU_STRIDE = IMU.close()

# ---- per-barometer record (at BARO_BASE + i * BARO_STRIDE) ---------------------------------
BARO = Layout("baro", "one barometer instance")
_b = BARO
BA_ALT = _b.add("BA_ALT", 1, "m", "last altitude above the ground calibration")
BA_ALT_PREV = _b.add("BA_ALT_PREV", 1, "m", "the sample before (climb rate)")
BA_PRESS = _b.add("BA_PRESS", 1, "Pa", "last pressure")
BA_TEMP = _b.add("BA_TEMP", 1, "degC", "last temperature")
BA_T_MS = _b.add("BA_T_MS", 1, "ms", "time of the last sample")
BA_DRIFT = _b.add("BA_DRIFT", 1, "m", "accumulated SIM_BARn_DRIFT offset (stays when DRIFT is 0)")
BA_HEALTHY = _b.add("BA_HEALTHY", 1, "", "1 while the instance delivers samples (BARO.H)")
BARO_STRIDE = BARO.close()

# ---- per-compass record (at MAG_BASE + i * MAG_STRIDE): what the EKF reads of compass i -----
MAG = Layout("mag", "one compass instance")
M_FIELD = MAG.add("M_FIELD", 3, "gauss",
                  "body field as the compass delivers it (held while it delivers nothing)")
M_NEW = MAG.add("M_NEW", 1, "", "1 if the compass delivered a sample on the latest compass tick")
M_HEALTHY = MAG.add("M_HEALTHY", 1, "",
                    "1 while its last sample is under 0.5 s old (AP_Compass health, MAG.Health)")
M_T_US = MAG.add("M_T_US", 1, "us", "time of its last delivered sample (MAG.S)")
MAG_STRIDE = MAG.close()

# ---- GPS record: a delay line of main-loop ticks ---------------------------------------------
GPS_HIST_N = 64  # delay line length (main-loop ticks, 400 Hz -> 160 ms)
G_ROW = 7  # one history row: t_s, pn, pe, pd, vn, ve, vd
GPS = Layout("gps", "GPS delay line")
G_HEAD = GPS.add("G_HEAD", 1, "", "index of the newest history row")
G_COUNT = GPS.add("G_COUNT", 1, "", "rows filled")
G_NEXT_US = GPS.add("G_NEXT_US", 1, "us", "time of the next GPS epoch")
G_HIST = GPS.add("G_HIST", GPS_HIST_N * G_ROW, "s, m, m/s",
                 "history rows (t_s, pn, pe, pd, vn, ve, vd) x GPS_HIST_N")
G_LON_SCALE = GPS.add("G_LON_SCALE", 1, "",
                      "cos(home latitude): metres east per metre-equivalent of longitude")
G_JAM_LAST_MS = GPS.add("G_JAM_LAST_MS", 1, "ms", "time of the last jammed epoch (SIM_GPS1_JAM)")
G_JAM_START_MS = GPS.add("G_JAM_START_MS", 1, "ms", "start of the current jamming episode")
G_JAM_PN, G_JAM_PE = GPS.vector(("G_JAM_PN", "G_JAM_PE"), "m",
                                "latched (random-walk) jammed position north, east")
G_JAM_T_SATS = GPS.add("G_JAM_T_SATS", 1, "ms", "last change of the jammed satellites/lock")
G_JAM_T_VZ = GPS.add("G_JAM_T_VZ", 1, "ms", "last change of the jammed vertical velocity")
G_JAM_T_VEL = GPS.add("G_JAM_T_VEL", 1, "ms", "last change of the jammed horizontal velocity")
G_JAM_T_POS = GPS.add("G_JAM_T_POS", 1, "ms", "last step of the jammed position walk")
G_JAM_T_ACC = GPS.add("G_JAM_T_ACC", 1, "ms", "last change of the jammed accuracies")
G_MWC_Z, G_MWC_W = GPS.vector(("G_MWC_Z", "G_MWC_W"), "",
                              "state of SITL's get_random16 (two multiply-with-carry "
                              "generators, 1234 and 76542 at start-up), drawn only by jamming")
GPS_SIZE = GPS.close()

# ---- one GPS epoch: what gps_measure produces, the EKF fuses and the GPS log writes ----------
GPS_EPOCH = Layout("gps epoch", "one GPS measurement (gps_measure's output)")
_ge = GPS_EPOCH
GE_PN, GE_PE, GE_PD = _ge.vector(("GE_PN", "GE_PE", "GE_PD"), "m",
                                 "position NED from home ground")
GE_VN, GE_VE, GE_VD = _ge.vector(("GE_VN", "GE_VE", "GE_VD"), "m/s", "velocity NED")
GE_STATUS = _ge.add("GE_STATUS", 1, "", "fix status as GPS.Status logs it")
GE_NSATS = _ge.add("GE_NSATS", 1, "", "satellites in use")
GE_FIX_3D = _ge.add("GE_FIX_3D", 1, "", "1 with a 3-D fix (the EKF may fuse the epoch)")
GE_HACC, GE_VACC = _ge.vector(("GE_HACC", "GE_VACC"), "m",
                              "reported horizontal / vertical accuracy")
GE_SACC = _ge.add("GE_SACC", 1, "m/s", "reported speed accuracy")
GE_HDOP = _ge.add("GE_HDOP", 1, "", "reported horizontal dilution of precision")
N_GPS_EPOCH = GPS_EPOCH.close()

# ---- the sensor state s ----------------------------------------------------------------------
STATE = Layout("s", "sensor state")
_s = STATE
IMU_BASE = _s.block("IMU", IMU, N_IMU)
GPS_BASE = _s.block("GPS", GPS)
MISC_BASE = _s.size
B_NEXT_US = _s.add("B_NEXT_US", 1, "us", "next baro sample (10 Hz as the autopilot reads it)")
B_ALT = _s.add("B_ALT", 1, "m", "the primary baro's altitude (what the EKF fuses, CTUN.BAlt)")
B_PRIMARY = _s.add("B_PRIMARY", 1, "",
                   "primary baro: BARO_PRIMARY (0) if healthy, else the first healthy one")
B_PRIMARY_OK = _s.add("B_PRIMARY_OK", 1, "", "1 while the primary baro is healthy (ERR 18)")
M_NEXT_US = _s.add("M_NEXT_US", 1, "us", "next compass sample")
M_BODY = _s.add("M_BODY", 3, "gauss",
                 "body field of the latest compass tick before the per-compass faults (earth "
                 "field + anomaly rotated, + motor interference + SIM_MAG_RND noise)")
MAG_BASE = _s.block("MAG", MAG, N_MAG)
RC_NEXT_US = _s.add("RC_NEXT_US", 1, "us", "next RC frame")
RC_LAST_FRAME_US = _s.add("RC_LAST_FRAME_US", 1, "us", "time of the last RC frame received")
RC_CH = _s.add("RC_CH", 8, "us", "RC input channels 1..8 as the receiver delivers them (PWM)")
RC_ROW = _s.add("RC_ROW", 1, "", "next row of the flight's RC table (a pilot-flown flight)")
RC_HAND = _s.add("RC_HAND", 1, "",
                 "the pilot's hand on the throttle: 0 the table's, else its HOLD / LAND code")
RC_HAND_ALT = _s.add("RC_HAND_ALT", 1, "m",
                     "height the pilot's hand holds (above home), moving towards RC_HAND_GOAL")
RC_HAND_GOAL = _s.add("RC_HAND_GOAL", 1, "m", "height the pilot's hand is to reach")
RC_HAND_I = _s.add("RC_HAND_I", 1, "us", "the hand's slowly learnt throttle stick")
BARO_BASE = _s.block("BARO", BARO, N_BARO)
B_GND_TEMP = _s.add("B_GND_TEMP", 1, "degC",
                    "AP_Baro's ground temperature: the primary's at calibration (BARO.GndTemp)")
B_FIELD_ELEV = _s.add("B_FIELD_ELEV", 1, "m",
                      "field elevation once set from the EKF origin, 0 before (BARO.AltAMSL)")
G_EPOCHS = _s.add("G_EPOCHS", 1, "", "GPS epochs produced so far")
PM_VOLT = _s.add("PM_VOLT", 1, "V", "battery voltage as the power module reads it this tick")
PM_CURR = _s.add("PM_CURR", 1, "A", "battery current as the power module reads it this tick")
ROTOR_PWM = _s.add("ROTOR_PWM", MAX_MOTORS, "us",
                   "with TLM_ROTOR_TC > 0: each rotor's speed as the PWM that commands it at "
                   "rest (the motor model's lagged command), what the motor vibration runs at; "
                   "unused otherwise")
N_SENSOR_STATE = STATE.close()

#: The sensors' output block: what the EKF and the autopilot may read of the sensor state, as
#: ArduPilot's sensor libraries expose it (each IMU's filtered gyro and accel and their health,
#: the barometers' health and the primary's altitude, each compass's record, the GPS epoch, the
#: RC channels, the power module). Delay lines, filter states, vibration phases, timers, the
#: configuration and the noise streams are the sensors' own (tests/test_structure_sim.py).
PUBLISHED: frozenset[str] = frozenset({
    "N_IMU", "IMU_BASE", "IMU_STRIDE", "I_GYR_F", "I_ACC_F", "I_GYR_OK", "I_ACC_OK",
    "N_BARO", "BARO_BASE", "BARO_STRIDE", "BA_HEALTHY", "B_ALT", "B_PRIMARY",
    "N_MAG", "MAG_BASE", "MAG_STRIDE", *(slot.name for slot in MAG),
    "N_GPS_EPOCH", *(slot.name for slot in GPS_EPOCH),
    "RC_CH", "RC_LAST_FRAME_US", "PM_VOLT", "PM_CURR",
})

# ---- sensor configuration scfg (built once per flight from parameters) ------------------------
CONFIG = Layout("scfg", "sensor configuration")
_c = CONFIG
C_ACC_NOISE = _c.add("C_ACC_NOISE", 1, "m/s/s", "base accel noise amplitude (uniform)")
C_GYR_NOISE = _c.add("C_GYR_NOISE", 1, "rad/s", "base gyro noise amplitude (uniform)")
C_GYR_RND = _c.add("C_GYR_RND", 2, "rad/s", "SIM_GYR1_RND, SIM_GYR2_RND")
C_ACC_BIAS = _c.add("C_ACC_BIAS", 6, "m/s/s", "SIM_ACC1_BIAS, SIM_ACC2_BIAS (2 x 3)")
C_GYR_BIAS = _c.add("C_GYR_BIAS", 6, "rad/s", "SIM_GYR1_BIAS, SIM_GYR2_BIAS (2 x 3)")
C_ACC_FAIL = _c.add("C_ACC_FAIL", 2, "m/s/s", "SIM_ACCEL1_FAIL, SIM_ACCEL2_FAIL")
C_DRIFT_SPEED = _c.add("C_DRIFT_SPEED", 1, "rad/s/min", "SIM_DRIFT_SPEED")
C_DRIFT_TIME = _c.add("C_DRIFT_TIME", 1, "min", "SIM_DRIFT_TIME")
C_INS_THR_MIN = _c.add("C_INS_THR_MIN", 1, "", "SIM_INS_THR_MIN")
C_GYR_PERIOD_US = _c.add("C_GYR_PERIOD_US", 2, "us", "gyro sample period per IMU")
C_ACC_PERIOD_US = _c.add("C_ACC_PERIOD_US", 2, "us", "accel sample period per IMU")
C_GYR_LPF = _c.add("C_GYR_LPF", 10, "",
                   "gyro biquad coefficients per IMU (b0, b1, b2, a1, a2) x 2")
C_ACC_LPF = _c.add("C_ACC_LPF", 10, "", "accel biquad coefficients per IMU x 2")
C_VIB_FLOOR_A = _c.add("C_VIB_FLOOR_A", 2, "", "VIBE floor 5 Hz alpha per IMU")
C_VIB_SQ_A = _c.add("C_VIB_SQ_A", 2, "", "VIBE 2 Hz alpha per IMU")
C_GPS_ENABLE = _c.add("C_GPS_ENABLE", 1, "", "SIM_GPS1_ENABLE")
C_GPS_PERIOD_US = _c.add("C_GPS_PERIOD_US", 1, "us", "1e6 / SIM_GPS1_HZ")
C_GPS_LAG_S = _c.add("C_GPS_LAG_S", 1, "s", "SIM_GPS1_LAG_MS / 1000")
C_GPS_NUMSATS = _c.add("C_GPS_NUMSATS", 1, "", "SIM_GPS1_NUMSATS")
C_GPS_HDOP = _c.add("C_GPS_HDOP", 1, "", "reported HDop (TLM_GPS_HDOP)")
C_GPS_VDOP = _c.add("C_GPS_VDOP", 1, "", "reported VDop (TLM_GPS_VDOP)")
C_GPS_ACC = _c.add("C_GPS_ACC", 1, "m", "reported horizontal/vertical accuracy (SIM_GPS1_ACC)")
C_GPS_VERR = _c.add("C_GPS_VERR", 3, "m/s", "SIM_GPS1_VERR")
C_GPS_NOISE = _c.add("C_GPS_NOISE", 1, "m", "SIM_GPS1_NOISE")
C_GPS_GLITCH = _c.add("C_GPS_GLITCH", 3, "deg, deg, m",
                      "SIM_GPS1_GLTCH_X/Y/Z: latitude, longitude and altitude offsets")
C_GPS_JAM = _c.add("C_GPS_JAM", 1, "", "SIM_GPS1_JAM: 1 runs SITL's jamming model")
C_BARO_RND = _c.add("C_BARO_RND", N_BARO, "m", "SIM_BARO_RND, SIM_BAR2_RND")
C_BARO_GLITCH = _c.add("C_BARO_GLITCH", N_BARO, "m", "SIM_BARO_GLITCH, SIM_BAR2_GLITCH")
C_BARO_DRIFT = _c.add("C_BARO_DRIFT", N_BARO, "m/s", "SIM_BARO_DRIFT, SIM_BAR2_DRIFT")
C_BARO_FREEZE = _c.add("C_BARO_FREEZE", N_BARO, "", "SIM_BARO_FREEZE, SIM_BAR2_FREEZE")
C_BARO_DISABLE = _c.add("C_BARO_DISABLE", N_BARO, "", "SIM_BARO_DISABLE, SIM_BAR2_DISABLE")
C_MAG_RND = _c.add("C_MAG_RND", 1, "gauss", "SIM_MAG_RND")
C_MAG_EARTH = _c.add("C_MAG_EARTH", 3, "gauss", "earth field NED")
C_MAG_FAIL = _c.add("C_MAG_FAIL", N_MAG, "",
                    "SIM_MAG1_FAIL..SIM_MAG3_FAIL: 0 ok, 1 no data, 2 frozen (last reading)")
C_MAG_ALY = _c.add("C_MAG_ALY", 3, "gauss", "SIM_MAG_ALY_X/Y/Z: ground-level anomaly, NED")
C_MAG_ALY_HGT = _c.add("C_MAG_ALY_HGT", 1, "m",
                       "SIM_MAG_ALY_HGT: height where the anomaly has fallen to 1/8")
C_MAG_MOT = _c.add("C_MAG_MOT", 3, "gauss/A",
                   "SIM_MAG_MOT_X/Y/Z: body field per ampere of battery current")
C_RC_FAIL = _c.add("C_RC_FAIL", 1, "", "SIM_RC_FAIL")
C_RC3_RANGE = _c.add("C_RC3_RANGE", 2, "us", "RC3_MIN, RC3_MAX (the throttle stick's travel)")
C_HOME_ALT = _c.add("C_HOME_ALT", 1, "m", "SIM_OPOS_ALT (AMSL)")
C_VIB_MOT_MAX = _c.add("C_VIB_MOT_MAX", 1, "Hz", "SIM_VIB_MOT_MAX")
C_ACC_RND = _c.add("C_ACC_RND", 2, "m/s/s", "SIM_ACC1_RND, SIM_ACC2_RND")
C_FRAME_HEIGHT = _c.add("C_FRAME_HEIGHT", 1, "m", "ground-to-CG height")
C_NOISE_SCALE = _c.add("C_NOISE_SCALE", 2, "", "per-IMU scale of the base noise amplitudes")
C_ACC_SCAL = _c.add("C_ACC_SCAL", 6, "",
                     "SIM_ACC1_SCAL, SIM_ACC2_SCAL (2 x 3): reading divided by it if non-zero")
C_GYR_SCALE = _c.add("C_GYR_SCALE", 6, "",
                     "gyro scale factor 1 + SIM_GYRn_SCALE / 100 per IMU and axis (2 x 3)")
C_ACC_FAIL_MSK = _c.add("C_ACC_FAIL_MSK", 1, "",
                        "SIM_ACC_FAIL_MSK: bit i set -> IMU i's accel produces no samples")
C_GYR_FAIL_MSK = _c.add("C_GYR_FAIL_MSK", 1, "",
                        "SIM_GYR_FAIL_MSK: bit i set -> IMU i's gyro produces no samples")
C_VIB_ON = _c.add("C_VIB_ON", 1, "",
                  "1 when SIM_VIB_FREQ or SIM_VIB_MOT_MAX is set (vibration instead of the "
                  "second gyro noise term)")
C_VIB_FREQ = _c.add("C_VIB_FREQ", 3, "Hz", "SIM_VIB_FREQ_X/Y/Z: fixed vibration frequencies")
C_VIB_MOT_MULT = _c.add("C_VIB_MOT_MULT", 1, "",
                        "SIM_VIB_MOT_MULT: motor vibration amplitude scale")
C_VIB_MOT_HMNC = _c.add("C_VIB_MOT_HMNC", 1, "",
                        "SIM_VIB_MOT_HMNC: harmonics bit mask (bit k-1 -> harmonic k)")
C_VIB_ACC_AX = _c.add("C_VIB_ACC_AX", 3, "", "accelerometer vibration gain per body axis "
                      "(TLM_VIB_ACC_X/Y/Z)")
C_VIB_GYR_AX = _c.add("C_VIB_GYR_AX", 3, "", "gyro vibration gain per body axis "
                      "(TLM_VIB_GYR_X/Y/Z)")
C_VIB_IMB_MOT = _c.add("C_VIB_IMB_MOT", 1, "",
                       "imbalanced motor, output index 0..7 (-1: none); acts while C_VIB_IMB > 0")
C_VIB_IMB = _c.add("C_VIB_IMB", 1, "m/s^2", "its imbalance force at full command (TLM_VIB_IMB)")
C_ROTOR_TC = _c.add("C_ROTOR_TC", 1, "s", "rotor speed time constant of the vibration "
                    "(TLM_ROTOR_TC; 0: the command itself)")
C_VIB_MOT_FMUL = _c.add("C_VIB_MOT_FMUL", MAX_MOTORS, "",
                        "each motor's vibration frequency factor (1 + TLM_VIB_SPREAD x its "
                        "place in -1..1; 1: SITL's)")
C_VIB_CMD_REF = _c.add("C_VIB_CMD_REF", 1, "", "motor command at which the motor vibration "
                       "has its SIM_ACCn_RND / SIM_GYRn_RND amplitude, each rotor's scaling with "
                       "its command squared (TLM_VIB_CMD_REF; 0: SITL's, no scaling)")
C_ROTOR_PWM = _c.add("C_ROTOR_PWM", 2, "us", "the frame's PWM at motor command 0 and its span "
                     "to command 1 (TLM_PWM_MIN/MAX, TLM_SPIN_MIN/MAX, as the motor model)")
C_GYR_WALK_STEP = _c.add("C_GYR_WALK_STEP", 2, "rad/s",
                         "gyro bias random-walk step per sample per IMU (TLM_GYR_WALK x "
                         "sqrt(sample period))")
C_ACC_WALK_STEP = _c.add("C_ACC_WALK_STEP", 2, "m/s^2",
                         "accel bias random-walk step per sample per IMU (TLM_ACC_WALK x "
                         "sqrt(sample period))")
C_ACC_SLOW = _c.add("C_ACC_SLOW", 2, "", "1: IMU i's accel samples take the vibrating path "
                    "for an imbalance or a bias walk (sensors.imu._accel_sample_vib)")
C_VIB_MOT_MASK = _c.add("C_VIB_MOT_MASK", 1, "",
                        "motors that vibrate: the frame's motors OR SIM_VIB_MOT_MASK (bit mask)")
C_IMU_NSUB = _c.add("C_IMU_NSUB", 4, "",
                    "sub-samples averaged per published sample (gyro IMU0, IMU1, accel IMU0, "
                    "IMU1): SITL's fast sampling of the first IMU")
C_GPS_LOCK_US = _c.add("C_GPS_LOCK_US", 1, "us", "SIM_GPS1_LCKTIME: no lock before this time")
C_GPS_DETECT_US = _c.add("C_GPS_DETECT_US", 1, "us",
                         "first GPS epoch (the driver finds the receiver; 0 without the boot "
                         "phase, tlm_sim.boot)")
C_BOOT = _c.add("C_BOOT", 1, "", "TLM_BOOT_PHASE")
C_TEMP_START = _c.add("C_TEMP_START", 1, "degC", "SIM_TEMP_START")
C_TEMP_BRD_OFF = _c.add("C_TEMP_BRD_OFF", 1, "degC", "SIM_TEMP_BRD_OFF")
C_TEMP_TCONST = _c.add("C_TEMP_TCONST", 1, "s", "SIM_TEMP_TCONST")
N_SENSOR_CFG = CONFIG.close()

# ---- sensor noise streams: rows of the flight's noise generator array ------------------------
# One xorshift64* stream per sensor (tlm_sim.rng.new_streams), so a fault that stops one
# sensor's draws (a failed accelerometer draws no noise) leaves every other sensor's noise as
# it was.
NOISE = Layout("noise", "sensor noise streams (rows of the rng array)")
RNG_GYRO = NOISE.add("RNG_GYRO", N_IMU, "", "gyro noise, one stream per IMU")
RNG_ACC = NOISE.add("RNG_ACC", N_IMU, "", "accelerometer noise, one stream per IMU")
RNG_GPS = NOISE.add("RNG_GPS", 1, "", "GPS velocity noise and the jamming model's draws")
RNG_BARO = NOISE.add("RNG_BARO", 1, "", "barometer noise")
RNG_MAG = NOISE.add("RNG_MAG", 1, "",
                    "compass noise (SIM_MAG_RND: one draw shared by the three compasses, as SITL)")
RNG_BARO2 = NOISE.add("RNG_BARO2", 1, "", "barometer 2 noise (RNG_BARO is barometer 1's)")
N_NOISE_STREAMS = NOISE.close()
