"""Slots of the sensor state ``s`` and sensor configuration ``scfg`` arrays, declared once
(:class:`tlm_sim.slots.Layout`; ``STATE.describe(s)``, ``CONFIG.describe(scfg)``).

The sensor state holds, per IMU instance, the accumulators handed to the EKF each main-loop tick,
the autopilot's 20 Hz low-pass filter states, the VIBE metric filters and the clip counters; plus
the GPS delay line, baro, compass and RC receiver state. Units: SI (m, m/s, m/s^2, rad, rad/s),
body frame FRD, earth frame NED.
"""

from tlm_sim.slots import Layout

N_IMU = 2

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
I_ACC_OK = _i.add("I_ACC_OK", 1, "", "1 while the accel delivers samples this tick")
I_T_SAMPLE_US = _i.add("I_T_SAMPLE_US", 1, "us", "physics time of the latest sampling call")
I_T_TAKE_US = _i.add("I_T_TAKE_US", 1, "us",
                     "physics time at which the EKF last took the deltas (-1: never)")
IMU_STRIDE = IMU.close()

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
N_GPS_EPOCH = GPS_EPOCH.close()

# ---- the sensor state s ----------------------------------------------------------------------
STATE = Layout("s", "sensor state")
_s = STATE
IMU_BASE = _s.block("IMU", IMU, N_IMU)
GPS_BASE = _s.block("GPS", GPS)
MISC_BASE = _s.size
B_NEXT_US = _s.add("B_NEXT_US", 1, "us", "next baro sample (10 Hz as the autopilot reads it)")
B_ALT = _s.add("B_ALT", 1, "m", "last baro altitude above the ground calibration")
B_ALT_PREV = _s.add("B_ALT_PREV", 1, "m", "previous baro altitude (climb rate)")
B_PRESS = _s.add("B_PRESS", 1, "Pa", "last pressure")
B_TEMP = _s.add("B_TEMP", 1, "degC", "last temperature")
M_NEXT_US = _s.add("M_NEXT_US", 1, "us", "next compass sample")
M_FIELD = _s.add("M_FIELD", 3, "gauss", "last body field")
RC_NEXT_US = _s.add("RC_NEXT_US", 1, "us", "next RC frame")
RC_LAST_FRAME_US = _s.add("RC_LAST_FRAME_US", 1, "us", "time of the last RC frame received")
RC_CH = _s.add("RC_CH", 8, "us", "RC input channels 1..8 as the receiver delivers them (PWM)")
N_SENSOR_STATE = STATE.close()

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
C_BARO_RND = _c.add("C_BARO_RND", 1, "m", "SIM_BARO_RND")
C_BARO_GLITCH = _c.add("C_BARO_GLITCH", 1, "m", "SIM_BARO_GLITCH")
C_MAG_RND = _c.add("C_MAG_RND", 1, "gauss", "SIM_MAG_RND")
C_MAG_EARTH = _c.add("C_MAG_EARTH", 3, "gauss", "earth field NED")
C_RC_FAIL = _c.add("C_RC_FAIL", 1, "", "SIM_RC_FAIL")
C_HOME_ALT = _c.add("C_HOME_ALT", 1, "m", "SIM_OPOS_ALT (AMSL)")
C_VIB_MOT_MAX = _c.add("C_VIB_MOT_MAX", 1, "Hz", "SIM_VIB_MOT_MAX")
C_ACC_RND = _c.add("C_ACC_RND", 2, "m/s/s", "SIM_ACC1_RND, SIM_ACC2_RND")
C_FRAME_HEIGHT = _c.add("C_FRAME_HEIGHT", 1, "m", "ground-to-CG height")
C_ENGINE_MUL = _c.add("C_ENGINE_MUL", 1, "",
                      "SIM_ENGINE_MUL: PWM multiplier above 1000 us on the failed outputs")
C_ENGINE_MASK = _c.add("C_ENGINE_MASK", 1, "",
                       "SIM_ENGINE_FAIL as a bit mask of outputs (bit 0 = SERVO1 = motor 1)")
C_NOISE_SCALE = _c.add("C_NOISE_SCALE", 2, "", "per-IMU scale of the base noise amplitudes")
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
RNG_MAG = NOISE.add("RNG_MAG", 1, "", "compass noise")
N_NOISE_STREAMS = NOISE.close()
