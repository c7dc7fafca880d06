"""Index constants of the navigation EKF arrays.

Three float64 arrays hold everything the filter needs; all are allocated once per flight by
:func:`tlm_sim.ekf.config.new_ekf` and mutated in place by the ``@njit`` kernels:

* ``ekf[lane, N_EKF]`` -- one row per lane (one lane per IMU): nominal state, cached rotation
  matrix, the 15x15 error-state covariance (row-major, kept exactly symmetric), IMU
  accumulators, scratch space for the covariance products, a ring buffer of past
  position/velocity for fusing delayed measurements, timers, innovations, test ratios and flags.
* ``sel[N_SEL]`` -- the lane selector: primary lane index, relative errors, switch counter.
* ``cfg[N_CFG]`` -- configuration built once per flight from EK3_* parameters
  (:func:`tlm_sim.ekf.config.build_ekf_config`).

Frames: earth NED (x north, y east, z down) relative to the EKF origin (home at ground level);
body FRD. The quaternion is Hamilton, scalar first, rotating body vectors into NED
(``v_ned = q * v_body * q^-1``), the same convention as ``tlm_sim.dynamics.layout``.

Error state (covariance ordering, 15 states): attitude error as a small rotation vector in the
earth frame (``R_true = (I + [phi x]) R_est``), velocity NED, position NED, gyro bias (body, rad/s),
accel bias (body, m/s^2). The nominal state has 16 numbers (quaternion 4 + 12).

Output and filter state (EKF3's output observer): the lane's velocity and position slots
(``VN..PD``) and the ring buffer hold the *output* -- what controllers and the XKF1 log read.
The filter's own velocity/position is the output plus the tracking error ``OUT_EPN..OUT_EVD``:
measurement corrections and the bad-IMU vertical-velocity assignment change the filter state
only, and the output converges to it with the time constant EK3_TAU_OUTPUT; resets (GPS
position/velocity, height) shift both, as EKF3's resets shift the output history.

Times stored in the arrays are seconds (``t_us * 1e-6``). Test ratios are EKF3's normalised
innovation test ratios (innovation^2 / (gate^2 * innovation variance), fusion skipped when >= 1);
ekf_check reads their square roots (see :func:`tlm_sim.ekf.lanes.ekf_output`).
"""

# ------------------------------------------------------------------ sizes ----------------------
NS = 15  # error states (covariance dimension)
NBUF = 128  # ring-buffer length in main-loop ticks (0.32 s at 400 Hz): longest usable delay
BUF_ROW = 6  # pn, pe, pd, vn, ve, vd per ring-buffer row
MAX_LANES = 3

# error-state offsets (covariance rows/columns)
ES_ATT = 0  # earth-frame attitude error (3) [rad]
ES_VEL = 3  # velocity NED (3) [m/s]
ES_POS = 6  # position NED (3) [m]
ES_BG = 9  # gyro bias, body (3) [rad/s]
ES_BA = 12  # accel bias, body (3) [m/s^2]

# ------------------------------------------------------------------ lane row -------------------
# nominal state
QW, QX, QY, QZ = 0, 1, 2, 3  # attitude quaternion body -> NED
VN, VE, VD = 4, 5, 6  # velocity NED [m/s]
PN, PE, PD = 7, 8, 9  # position NED from the origin [m]
BGX, BGY, BGZ = 10, 11, 12  # gyro bias, body FRD [rad/s] (subtracted from the gyro)
BAX, BAY, BAZ = 13, 14, 15  # accel bias, body FRD [m/s^2] (subtracted from the accel)
N_NOMINAL = 16
# rotation matrix body -> NED (row-major), kept in step with the quaternion
R00, R01, R02, R10, R11, R12, R20, R21, R22 = 16, 17, 18, 19, 20, 21, 22, 23, 24
# covariance P[i, j] = ekf[lane, P0 + i * NS + j]
P0 = 25
# IMU accumulators since the last covariance prediction
ACC_DVN, ACC_DVE, ACC_DVD = 250, 251, 252  # sum of rotated delta velocities, NED [m/s]
ACC_DT = 253  # accumulated time [s]
# scratch (no allocation inside the kernels)
SCR_A = 254  # F P rows for attitude/velocity/position (9 x NS)
SCR_C = 389  # P H^T column (NS)
SCR_DX = 404  # error-state correction accumulated during one measurement batch (NS)
# alignment
ALIGNED = 419  # 1 after tilt/yaw alignment
ALIGN_T0 = 420  # time alignment data started [s]
ALIGN_FX, ALIGN_FY, ALIGN_FZ = 421, 422, 423  # summed delta velocity while aligning [m/s]
ALIGN_DT = 424  # summed time while aligning [s]
MAG_HAVE = 425  # 1 once a magnetometer sample was seen
MAG_LX, MAG_LY, MAG_LZ = 426, 427, 428  # last body-frame field [gauss]
# timing / aiding
T_LAST = 429  # time of the last prediction tick [s] (-1 before the first)
T_ALIGNED = 430  # time alignment completed [s]
AID_MODE = 431  # AID_NONE or AID_ABSOLUTE
T_VEL_PASS = 432  # last GPS velocity fusion or reset [s]
T_POS_PASS = 433  # last GPS position fusion or reset [s]
T_HGT_PASS = 434  # last height fusion or reset [s]
T_GPS_FUSED = 435  # last time GPS position was fused [s] (using_gps: within 4 s)
T_CONSTPOS = 436  # last constant-position pseudo-measurement [s]
CONSTPOS_N, CONSTPOS_E = 437, 438  # last known position for constant-position mode [m]
# test ratios (raw; ekf_check uses their square roots)
VEL_TR, POS_TR, HGT_TR, MAG_TR = 439, 440, 441, 442  # MAG_TR = max over the three axes
# innovations (measurement - prediction) of the last fusion attempt
INNOV_VN, INNOV_VE, INNOV_VD = 443, 444, 445  # [m/s]
INNOV_PN, INNOV_PE = 446, 447  # [m]
INNOV_HGT = 448  # [m, down]
INNOV_MX, INNOV_MY, INNOV_MZ = 449, 450, 451  # [gauss, body]
# status flags (1.0 / 0.0)
F_ATTITUDE = 452  # attitude valid
F_HORIZ_VEL = 453  # horizontal velocity valid
F_VERT_VEL = 454
F_HORIZ_POS = 455  # absolute horizontal position valid (horiz_pos_abs)
F_VERT_POS = 456
F_CONST_POS = 457  # constant-position mode (aiding stopped)
F_USING_GPS = 458  # GPS position fused within the last 4 s
FAULT = 459  # 1 after a numerical fault (NaN); lane then unhealthy
HEALTHY = 460  # lane health as the selector sees it
SCORE = 461  # error score max(0.5 (vel + pos), hgt)
IMU_OK = 462  # 1 while this lane's IMU delivers samples
# resets (for controllers that must absorb jumps), counters and last deltas
POS_RESET_COUNT = 463
POS_RESET_DN, POS_RESET_DE = 464, 465  # [m]
VEL_RESET_COUNT = 466
VEL_RESET_DN, VEL_RESET_DE, VEL_RESET_DD = 467, 468, 469  # [m/s]
HGT_RESET_COUNT = 470
# configuration of the lane
IMU_INDEX = 471  # which IMU instance this lane integrates
N_PREDICT = 472  # covariance predictions so far
# ring buffer of past output states (stored minus the cumulative shift BUF_OFS, so shifts
# applied later move all stored entries at O(1) cost)
BUF_HEAD = 473  # index of the newest row
BUF_COUNT = 474  # rows filled (<= NBUF)
# bad-IMU handling (EKF3: vertical GPS velocity and height innovations both large, same sign)
BAD_IMU = 475  # 1 while the bad-IMU response is active (held 10 s after the last detection)
T_BAD_IMU = 476  # last detection [s]
BARO_LAST = 477  # latest baro altitude [m, up]
T_BARO_LAST = 478  # time of the latest baro sample [s]
T_GOOD_IMU = 479  # last GPS sample without bad-IMU detection (or last bad-IMU height reset) [s]
TILT_BAD_T = 480  # time the lane has been static with a large tilt error [s]
TILT_RESET_COUNT = 481  # stationary tilt re-alignments so far
# output tracking error: filter state minus output state (pn, pe, pd, vn, ve, vd), EKF3's
# output-observer error. The lane's VN..PD hold the *output* (what controllers and logs read);
# measurement corrections change the filter state only, and the output follows with the time
# constant EK3_TAU_OUTPUT (see tlm_sim.ekf.core.output_track). Ordered like a ring-buffer row.
OUT_EPN, OUT_EPE, OUT_EPD = 482, 483, 484  # [m]
OUT_EVN, OUT_EVE, OUT_EVD = 485, 486, 487  # [m/s]
# time integrals of the tracking errors (the observer's integral term), same order
OUT_IPN, OUT_IPE, OUT_IPD = 488, 489, 490  # [m s]
OUT_IVN, OUT_IVE, OUT_IVD = 491, 492, 493  # [m]
BUF_OFS = 494  # cumulative output shifts pn, pe, pd, vn, ve, vd (6)
BUF0 = 500  # NBUF rows of BUF_ROW
N_EKF = BUF0 + NBUF * BUF_ROW

# aiding modes (EKF3 names)
AID_ABSOLUTE = 0.0
AID_NONE = 2.0

# ------------------------------------------------------------------ selector -------------------
SEL_PRIMARY = 0  # index of the primary lane
SEL_N_LANES = 1
SEL_CHANGES = 2  # number of primary changes (ERR 24 events)
SEL_T_SWITCH = 3  # time of the last switch [s] (-1 if none)
SEL_RUN = 4  # 1 once the primary has been healthy for 10 s (latched)
SEL_HEALTHY_SINCE = 5  # time the primary became continuously healthy [s] (-1 if not)
SEL_REL_ERR = 6  # relative error per lane (MAX_LANES)
SEL_T_PRIMARY = SEL_REL_ERR + MAX_LANES  # time each lane last stopped being primary (MAX_LANES)
N_SEL = SEL_T_PRIMARY + MAX_LANES

# ------------------------------------------------------------------ configuration --------------
C_DT = 0  # nominal main-loop period [s]
C_TARGET_DT = 1  # covariance prediction target interval [s] (EKF3: 12 ms)
C_VELNE_NSE = 2  # EK3_VELNE_M_NSE [m/s]
C_VELD_NSE = 3  # EK3_VELD_M_NSE [m/s]
C_POSNE_NSE = 4  # EK3_POSNE_M_NSE [m]
C_ALT_NSE = 5  # EK3_ALT_M_NSE [m]
C_MAG_NSE = 6  # EK3_MAG_M_NSE [gauss]
C_GYRO_PNSE = 7  # EK3_GYRO_P_NSE [rad/s]
C_ACC_PNSE = 8  # EK3_ACC_P_NSE [m/s^2]
C_GBIAS_PNSE = 9  # EK3_GBIAS_P_NSE [rad/s^2]
C_ABIAS_PNSE = 10  # EK3_ABIAS_P_NSE [m/s^3]
C_VEL_GATE = 11  # EK3_VEL_I_GATE as sigmas: max(gate / 100, 1)
C_POS_GATE = 12  # EK3_POS_I_GATE as sigmas
C_HGT_GATE = 13  # EK3_HGT_I_GATE as sigmas
C_MAG_GATE = 14  # EK3_MAG_I_GATE as sigmas
C_GLITCH_RAD = 15  # EK3_GLITCH_RAD [m]
C_NOAID_NSE = 16  # EK3_NOAID_M_NSE [m]
C_ERR_THRESH = 17  # EK3_ERR_THRESH
C_GPS_DELAY = 18  # assumed GPS measurement delay [s]
C_HGT_DELAY = 19  # EK3_HGT_DELAY [s]
C_MAG_N, C_MAG_E, C_MAG_D = 20, 21, 22  # earth magnetic field NED [gauss]
C_POS_RETRY = 23  # GPS position/velocity timeout (EKF3 posRetryTimeNoVel) [s]
C_TILT_DRIFT = 24  # time without aiding before constant-position mode [s]
C_HGT_RETRY = 25  # height innovation timeout before a reset to baro [s]
C_USING_GPS_T = 26  # using_gps flag window [s]
C_CONSTPOS_DT = 27  # interval of constant-position pseudo-measurements [s]
C_GBIAS_LIM = 28  # gyro bias limit [rad/s]
C_ABIAS_LIM = 29  # EK3_ACC_BIAS_LIM [m/s^2]
C_ALIGN_TIME = 30  # accel averaging time for tilt alignment [s]
C_LANE_INIT_T = 31  # lane unhealthy for this long after alignment [s]
C_SELECT_T = 32  # primary healthy this long before selection runs; min time between uses [s]
C_ONGROUND_NSE = 33  # constant-position noise while disarmed [m]
C_N_LANES = 34  # number of lanes (from EK3_IMU_MASK)
C_LANE_IMU = 35  # IMU instance of each lane (MAX_LANES)
C_BAD_IMU_ACC_NSE = C_LANE_IMU + MAX_LANES  # accel process noise while the IMU is bad [m/s^2]
C_BAD_IMU_HOLD = C_BAD_IMU_ACC_NSE + 1  # bad-IMU response hold time [s]
C_BAD_IMU_TIMEOUT = C_BAD_IMU_HOLD + 1  # continuous bad-IMU time before a height reset [s]
C_TAU_OUTPUT = C_BAD_IMU_TIMEOUT + 1  # EK3_TAU_OUTPUT: output observer time constant [s]
N_CFG = C_TAU_OUTPUT + 1

# ------------------------------------------------------------------ output vector --------------
# filled by tlm_sim.ekf.lanes.ekf_output from the primary lane
O_QW, O_QX, O_QY, O_QZ = 0, 1, 2, 3  # quaternion body -> NED
O_VN, O_VE, O_VD = 4, 5, 6  # [m/s]
O_PN, O_PE, O_PD = 7, 8, 9  # [m]
O_BGX, O_BGY, O_BGZ = 10, 11, 12  # gyro bias [rad/s]
O_BAX, O_BAY, O_BAZ = 13, 14, 15  # accel bias [m/s^2]
O_ROLL, O_PITCH, O_YAW = 16, 17, 18  # Euler angles [rad] (ZYX), yaw in (-pi, pi]
O_F_ATTITUDE, O_F_HORIZ_VEL, O_F_HORIZ_POS, O_F_VERT_POS = 19, 20, 21, 22
O_F_CONST_POS, O_F_USING_GPS = 23, 24
O_SQRT_VEL, O_SQRT_POS, O_SQRT_HGT, O_SQRT_MAG = 25, 26, 27, 28  # sqrt of the test ratios
O_PRIMARY = 29
O_PRIMARY_CHANGES = 30
O_POS_RESET_COUNT = 31
O_VEL_RESET_COUNT = 32
N_OUT = 33
