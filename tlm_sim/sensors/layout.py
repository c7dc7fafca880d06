"""Index constants of the sensor state ``s`` and sensor configuration ``scfg`` arrays.

The sensor state holds, per IMU instance, the accumulators handed to the EKF each main-loop tick,
the autopilot's 20 Hz low-pass filter states, the VIBE metric filters and the clip counters; plus
the GPS delay line, baro, compass and RC receiver state. Units: SI (m, m/s, m/s^2, rad, rad/s),
body frame FRD, earth frame NED.
"""

N_IMU = 2

# ---- per-IMU block (offset IMU_BASE + i * IMU_STRIDE) ----------------------------------------
IMU_BASE = 0
I_DANG = 0  # accumulated delta angle since the last main-loop tick [rad] (3)
I_DVEL = 3  # accumulated delta velocity since the last main-loop tick [m/s] (3)
I_GYR_F = 6  # low-pass filtered gyro [rad/s] (3): what controllers and the IMU log see
I_ACC_F = 9  # low-pass filtered accel [m/s^2] (3)
I_GYR_LPF = 12  # biquad delay elements, gyro (3 axes x 2)
I_ACC_LPF = 18  # biquad delay elements, accel (3 axes x 2)
I_VIB_FLOOR = 24  # VIBE 5 Hz floor filter (3)
I_VIB_SQ = 27  # VIBE 2 Hz filter of the squared deviation (3)
I_CLIP = 30  # accel clip count
I_NEXT_GYR_US = 31  # time of the next gyro sample [us]
I_NEXT_ACC_US = 32  # time of the next accel sample [us]
I_LAST_GYR = 33  # last raw gyro sample [rad/s] (3)
I_LAST_ACC = 36  # last raw accel sample [m/s^2] (3)
I_GYR_COUNT = 39  # gyro samples accumulated this tick
I_ACC_COUNT = 40  # accel samples accumulated this tick
I_EG = 41  # gyro error count
I_EA = 42  # accel error count
I_ACC_OK = 43  # 1 while the accel delivers samples this tick
I_T_SAMPLE_US = 44  # physics time of the latest sampling call [us]
I_T_TAKE_US = 45  # physics time at which the EKF last took the deltas [us] (-1: never)
IMU_STRIDE = 46

# ---- GPS ---------------------------------------------------------------------------------------
GPS_BASE = IMU_BASE + N_IMU * IMU_STRIDE
GPS_HIST_N = 64  # delay line length (main-loop ticks, 400 Hz -> 160 ms)
G_HEAD = 0  # index of the newest history row
G_COUNT = 1  # rows filled
G_NEXT_US = 2  # time of the next GPS epoch [us]
G_HIST = 3  # history rows: (t_s, pn, pe, pd, vn, ve, vd) x GPS_HIST_N
G_ROW = 7
GPS_SIZE = G_HIST + GPS_HIST_N * G_ROW

# ---- baro / compass / RC ---------------------------------------------------------------------
MISC_BASE = GPS_BASE + GPS_SIZE
B_NEXT_US = MISC_BASE + 0  # next baro sample (10 Hz as the autopilot reads it) [us]
B_ALT = MISC_BASE + 1  # last baro altitude above the ground calibration [m]
B_ALT_PREV = MISC_BASE + 2  # previous baro altitude [m] (climb rate)
B_PRESS = MISC_BASE + 3  # last pressure [Pa]
B_TEMP = MISC_BASE + 4  # last temperature [degC]
M_NEXT_US = MISC_BASE + 5  # next compass sample [us]
M_FIELD = MISC_BASE + 6  # last body field [gauss] (3)
RC_NEXT_US = MISC_BASE + 9  # next RC frame [us]
RC_LAST_FRAME_US = MISC_BASE + 10  # time of the last RC frame received [us]
RC_CH = MISC_BASE + 11  # RC input channels 1..8 as the receiver delivers them [us PWM] (8)
N_SENSOR_STATE = MISC_BASE + 19

# ---- sensor configuration (built once per flight from parameters) -----------------------------
C_ACC_NOISE = 0  # base accel noise amplitude [m/s^2] (uniform)
C_GYR_NOISE = 1  # base gyro noise amplitude [rad/s] (uniform)
C_GYR_RND = 2  # SIM_GYR1_RND, SIM_GYR2_RND [rad/s] (2)
C_ACC_BIAS = 4  # SIM_ACC1_BIAS, SIM_ACC2_BIAS [m/s^2] (2 x 3)
C_GYR_BIAS = 10  # SIM_GYR1_BIAS, SIM_GYR2_BIAS [rad/s] (2 x 3)
C_ACC_FAIL = 16  # SIM_ACCEL1_FAIL, SIM_ACCEL2_FAIL [m/s^2] (2)
C_DRIFT_SPEED = 18  # SIM_DRIFT_SPEED [rad/s per minute]
C_DRIFT_TIME = 19  # SIM_DRIFT_TIME [min]
C_INS_THR_MIN = 20  # SIM_INS_THR_MIN
C_GYR_PERIOD_US = 21  # gyro sample period per IMU [us] (2)
C_ACC_PERIOD_US = 23  # accel sample period per IMU [us] (2)
C_GYR_LPF = 25  # gyro biquad coefficients per IMU (b0, b1, b2, a1, a2) x 2
C_ACC_LPF = 35  # accel biquad coefficients per IMU x 2
C_VIB_FLOOR_A = 45  # VIBE floor 5 Hz alpha per IMU (2)
C_VIB_SQ_A = 47  # VIBE 2 Hz alpha per IMU (2)
C_GPS_ENABLE = 49  # SIM_GPS1_ENABLE
C_GPS_PERIOD_US = 50  # 1e6 / SIM_GPS1_HZ
C_GPS_LAG_S = 51  # SIM_GPS1_LAG_MS / 1000
C_GPS_NUMSATS = 52  # SIM_GPS1_NUMSATS
C_GPS_HDOP = 53  # reported HDop
C_GPS_VERR = 54  # SIM_GPS1_VERR (3) [m/s]
C_GPS_NOISE = 57  # SIM_GPS1_NOISE [m]
C_BARO_RND = 58  # SIM_BARO_RND [m]
C_BARO_GLITCH = 59  # SIM_BARO_GLITCH [m]
C_MAG_RND = 60  # SIM_MAG_RND [gauss]
C_MAG_EARTH = 61  # earth field NED [gauss] (3)
C_RC_FAIL = 64  # SIM_RC_FAIL
C_HOME_ALT = 65  # SIM_OPOS_ALT [m AMSL]
C_VIB_MOT_MAX = 66  # SIM_VIB_MOT_MAX [Hz]
C_ACC_RND = 67  # SIM_ACC1_RND, SIM_ACC2_RND [m/s^2] (2)
C_FRAME_HEIGHT = 69  # ground-to-CG height [m]
C_ENGINE_MUL = 70  # SIM_ENGINE_MUL: PWM multiplier above 1000 us on the failed outputs
C_ENGINE_MASK = 71  # SIM_ENGINE_FAIL as a bit mask of outputs (bit 0 = SERVO1 = motor 1)
C_NOISE_SCALE = 72  # per-IMU scale of the base noise amplitudes (2)
N_SENSOR_CFG = 74
