"""Slots of the navigation EKF arrays, declared once (:class:`tlm_sim.slots.Layout`;
``LANE.describe(ekf[lane])``, ``SELECTOR``, ``CONFIG``, ``OUTPUT``).

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

from tlm_sim.slots import Layout

# ------------------------------------------------------------------ sizes ----------------------
NS = 15  # error states (covariance dimension)
NBUF = 128  # ring-buffer length in main-loop ticks (0.32 s at 400 Hz): longest usable delay
BUF_ROW = 6  # pn, pe, pd, vn, ve, vd per ring-buffer row
MAX_LANES = 3

# error-state offsets (covariance rows/columns)
ERROR_STATE = Layout("error state", "covariance ordering")
ES_ATT = ERROR_STATE.add("ES_ATT", 3, "rad", "earth-frame attitude error")
ES_VEL = ERROR_STATE.add("ES_VEL", 3, "m/s", "velocity NED")
ES_POS = ERROR_STATE.add("ES_POS", 3, "m", "position NED")
ES_BG = ERROR_STATE.add("ES_BG", 3, "rad/s", "gyro bias, body")
ES_BA = ERROR_STATE.add("ES_BA", 3, "m/s^2", "accel bias, body")
assert ERROR_STATE.close() == NS

# ------------------------------------------------------------------ lane row -------------------
LANE = Layout("ekf lane", "one EKF lane (row of the ekf array)")
_l = LANE
# nominal state
QW, QX, QY, QZ = _l.vector(("QW", "QX", "QY", "QZ"), "", "attitude quaternion body -> NED")
VN, VE, VD = _l.vector(("VN", "VE", "VD"), "m/s", "velocity NED (the output, see above)")
PN, PE, PD = _l.vector(("PN", "PE", "PD"), "m",
                       "position NED from the origin (the output, see above)")
BGX, BGY, BGZ = _l.vector(("BGX", "BGY", "BGZ"), "rad/s",
                          "gyro bias, body FRD (subtracted from the gyro)")
BAX, BAY, BAZ = _l.vector(("BAX", "BAY", "BAZ"), "m/s^2",
                          "accel bias, body FRD (subtracted from the accel)")
N_NOMINAL = _l.size
# rotation matrix body -> NED (row-major), kept in step with the quaternion
R00, R01, R02, R10, R11, R12, R20, R21, R22 = _l.vector(
    ("R00", "R01", "R02", "R10", "R11", "R12", "R20", "R21", "R22"), "",
    "rotation matrix body -> NED, row-major")
P0 = _l.add("P0", NS * NS, "", "covariance, P[i, j] = ekf[lane, P0 + i * NS + j]")
# IMU accumulators since the last covariance prediction
ACC_DVN, ACC_DVE, ACC_DVD = _l.vector(("ACC_DVN", "ACC_DVE", "ACC_DVD"), "m/s",
                                      "sum of rotated delta velocities, NED")
ACC_DT = _l.add("ACC_DT", 1, "s", "accumulated time")
# scratch (no allocation inside the kernels)
SCR_A = _l.add("SCR_A", 9 * NS, "", "F P rows for attitude/velocity/position (9 x NS)")
SCR_C = _l.add("SCR_C", NS, "", "P H^T column")
SCR_DX = _l.add("SCR_DX", NS, "",
                "error-state correction accumulated during one measurement batch")
# alignment
ALIGNED = _l.add("ALIGNED", 1, "", "1 after tilt/yaw alignment")
ALIGN_T0 = _l.add("ALIGN_T0", 1, "s", "time alignment data started")
ALIGN_FX, ALIGN_FY, ALIGN_FZ = _l.vector(("ALIGN_FX", "ALIGN_FY", "ALIGN_FZ"), "m/s",
                                         "summed delta velocity while aligning")
ALIGN_DT = _l.add("ALIGN_DT", 1, "s", "summed time while aligning")
MAG_HAVE = _l.add("MAG_HAVE", 1, "", "1 once a magnetometer sample was seen")
MAG_LX, MAG_LY, MAG_LZ = _l.vector(("MAG_LX", "MAG_LY", "MAG_LZ"), "gauss",
                                   "last body-frame field")
# compass selection (EKF3 magSelectIndex and its timers, tlm_sim.ekf.compass)
MAG_IDX = _l.add("MAG_IDX", 1, "", "compass the lane reads (0-based; XKFS.MI)")
T_MAG_READ = _l.add("T_MAG_READ", 1, "s",
                    "last time the lane's compass delivered a sample (or the lane changed compass)")
T_MAG_PASS = _l.add("T_MAG_PASS", 1, "s",
                    "last magnetometer fusion inside the gate (or alignment, compass change)")
IN_FLIGHT = _l.add("IN_FLIGHT", 1, "",
                   "1 from C_INFLIGHT_HGT above the origin while armed until disarmed "
                   "(EKF3's in-flight magnetometer fusion, XKFS.MAG_FUSION 2)")
# timing / aiding
T_LAST = _l.add("T_LAST", 1, "s", "time of the last prediction tick (-1 before the first)")
T_ALIGNED = _l.add("T_ALIGNED", 1, "s", "time alignment completed")
AID_MODE = _l.add("AID_MODE", 1, "", "AID_NONE or AID_ABSOLUTE")
T_VEL_PASS = _l.add("T_VEL_PASS", 1, "s", "last GPS velocity fusion or reset")
T_POS_PASS = _l.add("T_POS_PASS", 1, "s", "last GPS position fusion or reset")
T_HGT_PASS = _l.add("T_HGT_PASS", 1, "s", "last height fusion or reset")
T_GPS_FUSED = _l.add("T_GPS_FUSED", 1, "s",
                     "last time GPS position was fused (using_gps: within 4 s)")
T_CONSTPOS = _l.add("T_CONSTPOS", 1, "s", "last constant-position pseudo-measurement")
CONSTPOS_N, CONSTPOS_E = _l.vector(("CONSTPOS_N", "CONSTPOS_E"), "m",
                                   "last known position for constant-position mode")
VEL_TR, POS_TR, HGT_TR, MAG_TR = _l.vector(
    ("VEL_TR", "POS_TR", "HGT_TR", "MAG_TR"), "",
    "raw test ratios (ekf_check uses their square roots); MAG_TR = max over the three axes")
# innovations (measurement - prediction) of the last fusion attempt
INNOV_VN, INNOV_VE, INNOV_VD = _l.vector(("INNOV_VN", "INNOV_VE", "INNOV_VD"), "m/s",
                                         "velocity innovations NED")
INNOV_PN, INNOV_PE = _l.vector(("INNOV_PN", "INNOV_PE"), "m", "position innovations NE")
INNOV_HGT = _l.add("INNOV_HGT", 1, "m", "height innovation, down")
INNOV_MX, INNOV_MY, INNOV_MZ = _l.vector(("INNOV_MX", "INNOV_MY", "INNOV_MZ"), "gauss",
                                         "magnetometer innovations, body")
# status flags (1.0 / 0.0)
F_ATTITUDE = _l.add("F_ATTITUDE", 1, "", "attitude valid")
F_HORIZ_VEL = _l.add("F_HORIZ_VEL", 1, "", "horizontal velocity valid")
F_VERT_VEL = _l.add("F_VERT_VEL", 1, "", "vertical velocity valid")
F_HORIZ_POS = _l.add("F_HORIZ_POS", 1, "",
                     "absolute horizontal position valid (horiz_pos_abs)")
F_VERT_POS = _l.add("F_VERT_POS", 1, "", "vertical position valid")
F_CONST_POS = _l.add("F_CONST_POS", 1, "", "constant-position mode (aiding stopped)")
F_USING_GPS = _l.add("F_USING_GPS", 1, "", "GPS position fused within the last 4 s")
FAULT = _l.add("FAULT", 1, "", "1 after a numerical fault (NaN); lane then unhealthy")
HEALTHY = _l.add("HEALTHY", 1, "", "lane health as the selector sees it")
SCORE = _l.add("SCORE", 1, "", "error score max(0.5 (vel + pos), hgt)")
SCORE_PREV = _l.add("SCORE_PREV", 1, "", "error score before its latest change")
T_SCORE = _l.add("T_SCORE", 1, "s", "time of the latest error score change")
IMU_OK = _l.add("IMU_OK", 1, "", "1 while this lane's IMU delivers samples")
# resets (for controllers that must absorb jumps), counters and last deltas
POS_RESET_COUNT = _l.add("POS_RESET_COUNT", 1, "", "position resets so far")
POS_RESET_DN, POS_RESET_DE = _l.vector(("POS_RESET_DN", "POS_RESET_DE"), "m",
                                       "last position reset NE")
VEL_RESET_COUNT = _l.add("VEL_RESET_COUNT", 1, "", "velocity resets so far")
VEL_RESET_DN, VEL_RESET_DE, VEL_RESET_DD = _l.vector(
    ("VEL_RESET_DN", "VEL_RESET_DE", "VEL_RESET_DD"), "m/s", "last velocity reset NED")
HGT_RESET_COUNT = _l.add("HGT_RESET_COUNT", 1, "", "height resets so far")
# configuration of the lane
IMU_INDEX = _l.add("IMU_INDEX", 1, "", "which IMU instance this lane integrates")
N_PREDICT = _l.add("N_PREDICT", 1, "", "covariance predictions so far")
# ring buffer of past output states (stored minus the cumulative shift BUF_OFS, so shifts
# applied later move all stored entries at O(1) cost)
BUF_HEAD = _l.add("BUF_HEAD", 1, "", "index of the newest ring-buffer row")
BUF_COUNT = _l.add("BUF_COUNT", 1, "", "ring-buffer rows filled (<= NBUF)")
# bad-IMU handling (EKF3: vertical GPS velocity and height innovations both large, same sign)
BAD_IMU = _l.add("BAD_IMU", 1, "",
                 "1 while the bad-IMU response is active (held 10 s after the last detection)")
T_BAD_IMU = _l.add("T_BAD_IMU", 1, "s", "last bad-IMU detection")
BARO_LAST = _l.add("BARO_LAST", 1, "m", "latest baro altitude, up")
T_BARO_LAST = _l.add("T_BARO_LAST", 1, "s", "time of the latest baro sample")
T_GOOD_IMU = _l.add("T_GOOD_IMU", 1, "s",
                    "last GPS sample without bad-IMU detection (or last bad-IMU height reset)")
TILT_BAD_T = _l.add("TILT_BAD_T", 1, "s",
                    "time the lane has been static with a large tilt error")
TILT_RESET_COUNT = _l.add("TILT_RESET_COUNT", 1, "", "stationary tilt re-alignments so far")
# GPS quality (EKF3 readGpsData / calcGpsGoodForFlight): the reported accuracies' decaying
# envelopes (measurement noise of the fusion), the speed-accuracy test and the innovation
# consistency test whose failure is EKF3's gps_glitching flag
GPS_HACC_F = _l.add("GPS_HACC_F", 1, "m",
                    "reported horizontal accuracy, decaying peak hold (tau 5 s), 0 before any")
GPS_SACC_F = _l.add("GPS_SACC_F", 1, "m/s",
                    "reported speed accuracy, decaying peak hold (tau 5 s), 0 before any")
T_GPS_ACC = _l.add("T_GPS_ACC", 1, "s", "time of the last GPS accuracy sample (0: none)")
SACC_LPF = _l.add("SACC_LPF", 1, "m/s", "speed accuracy low-passed (0.2 per sample)")
SACC_PEAK = _l.add("SACC_PEAK", 1, "m/s", "SACC_LPF peak hold decaying with tau 10 s")
GPS_SPD_FAIL = _l.add("GPS_SPD_FAIL", 1, "", "1 while the GPS speed-accuracy test fails")
T_INNOV_PASS = _l.add("T_INNOV_PASS", 1, "s",
                      "last time GPS velocity and position test ratios were both < 1")
T_INNOV_HIGH = _l.add("T_INNOV_HIGH", 1, "s",
                      "last time a GPS velocity or position test ratio exceeded 0.7")
GPS_INNOV_FAIL = _l.add("GPS_INNOV_FAIL", 1, "",
                        "1 while the GPS innovation consistency test fails")
GPS_GLITCHING = _l.add("GPS_GLITCHING", 1, "",
                       "EKF3's gps_glitching flag: a GPS test fails while aiding with GPS")
GPS_NOISE_SCALE = _l.add("GPS_NOISE_SCALE", 1, "",
                         "EKF3 gpsNoiseScaler of the last 3-D-fix sample: 1 with 6 or more "
                         "satellites, 1.4 with 5, 2 with fewer or outside absolute aiding; "
                         "scales the GPS measurement noise (standard deviation) of the fusion")
POS_TIMEOUT = _l.add("POS_TIMEOUT", 1, "",
                     "EKF3 posTimeout: 1 once no GPS position passed its gate for the retry "
                     "time (C_POS_RETRY_VEL while GPS velocity is used, else C_POS_RETRY); "
                     "position is then fused ungated until a reset to GPS clears it")
# what only the log reads (XKF5, XKV1/XKV2: tlm_sim.ekf.log)
DT_EKF_AVG = _l.add("DT_EKF_AVG", 1, "s",
                    "average covariance prediction interval (EKF3 dtEkfAvg: 0.98/0.02 filter "
                    "of each interval, from C_TARGET_DT): the unit of EKF3's delta-angle and "
                    "delta-velocity bias states")
TERRAIN = _l.add("TERRAIN", 1, "m",
                 "EKF3's terrain state (terrainState, down): with no range finder or optical "
                 "flow only its constraint acts, at least the filter's down position + 0.05 m "
                 "(ground level at alignment and on-ground height resets); XKF5 offset/HAGL")
T_XKV_LOG = _l.add("T_XKV_LOG", 1, "s",
                   "last XKV1/XKV2 rows of this lane (EKF3 lastEkfStateVarLogTime_ms)")
# output tracking error: filter state minus output state (pn, pe, pd, vn, ve, vd), EKF3's
# output-observer error. The lane's VN..PD hold the *output* (what controllers and logs read);
# measurement corrections change the filter state only, and the output follows with the time
# constant EK3_TAU_OUTPUT (see tlm_sim.ekf.core.output_track). Ordered like a ring-buffer row.
OUT_EPN, OUT_EPE, OUT_EPD = _l.vector(("OUT_EPN", "OUT_EPE", "OUT_EPD"), "m",
                                      "output tracking error, position NED")
OUT_EVN, OUT_EVE, OUT_EVD = _l.vector(("OUT_EVN", "OUT_EVE", "OUT_EVD"), "m/s",
                                      "output tracking error, velocity NED")
# time integrals of the tracking errors (the observer's integral term), same order
OUT_IPN, OUT_IPE, OUT_IPD = _l.vector(("OUT_IPN", "OUT_IPE", "OUT_IPD"), "m s",
                                      "integral of the position tracking error")
OUT_IVN, OUT_IVE, OUT_IVD = _l.vector(("OUT_IVN", "OUT_IVE", "OUT_IVD"), "m",
                                      "integral of the velocity tracking error")
# EKF3's start-up (tlm_sim.ekf.lifecycle): tilt and yaw alignment, GPS checks, origin, gyro
# bias learning; LIFE_EVENTS holds what changed for the flight's text log (MSG)
TILT_DONE = _l.add("TILT_DONE", 1, "", "1 once the tilt variance fell below (5 deg)^2 "
                   "(EKF3 tiltAlignComplete)")
YAW_DONE = _l.add("YAW_DONE", 1, "", "1 once the yaw was aligned to the compass "
                  "(EKF3 yawAlignComplete); no compass fusion before")
ORIGIN_OK = _l.add("ORIGIN_OK", 1, "", "1 once the lane's origin is set (EKF3 validOrigin)")
GPS_GOOD = _l.add("GPS_GOOD", 1, "", "EKF3 gpsGoodToAlign: the GPS checks passed for 10 s "
                  "(cleared after 5 s without a passing sample)")
BIAS_LEARNED = _l.add("BIAS_LEARNED", 1, "", "EKF3 delAngBiasLearned: every gyro bias standard "
                      "deviation below 0.15 deg/s")
T_GPS_CHK_FAIL = _l.add("T_GPS_CHK_FAIL", 1, "s",
                        "last GPS sample failing the checks (-1: no 3-D fix sample checked yet)")
T_GPS_CHK_PASS = _l.add("T_GPS_CHK_PASS", 1, "s", "last GPS sample passing the checks")
GPS_CHK_FAILS = _l.add("GPS_CHK_FAILS", 1, "", "EK3_GPS_CHECK bits failing on the last sample")
GPS_DRIFT = _l.add("GPS_DRIFT", 1, "m", "filtered GPS position drift on the ground (10 s decay)")
GPS_PREV_N, GPS_PREV_E = _l.vector(("GPS_PREV_N", "GPS_PREV_E"), "m",
                                   "previous GPS position NE (drift check)")
GPS_VZ_F = _l.add("GPS_VZ_F", 1, "m/s", "filtered GPS vertical speed (ground check)")
GPS_VH_F = _l.add("GPS_VH_F", 1, "m/s", "filtered GPS horizontal speed (ground check)")
LIFE_EVENTS = _l.add("LIFE_EVENTS", 1, "", "lifecycle events not yet written to the text log "
                     "(bit mask, tlm_sim.ardupilot EKF_EVT_*)")
INNOV_YAW = _l.add("INNOV_YAW", 1, "rad", "heading innovation of the ground heading fusion "
                   "(measurement - prediction; XKF3.IYAW)")
INFLIGHT_SEEN = _l.add("INFLIGHT_SEEN", 1, "", "1 once IN_FLIGHT was first set (in-flight yaw "
                       "alignment message)")
BUF_OFS = _l.add("BUF_OFS", BUF_ROW, "m, m/s",
                 "cumulative output shifts pn, pe, pd, vn, ve, vd")
BUF0 = _l.add("BUF0", NBUF * BUF_ROW, "m, m/s",
              "ring buffer: NBUF rows of (pn, pe, pd, vn, ve, vd)")
N_EKF = LANE.close()

# aiding modes (EKF3 names)
AID_ABSOLUTE = 0.0
AID_NONE = 2.0
#: EKF3 rngOnGnd [m]: how far the terrain state (TERRAIN) is kept below the vehicle
RNG_ON_GND = 0.05

# ------------------------------------------------------------------ selector -------------------
SELECTOR = Layout("sel", "lane selector")
_s = SELECTOR
SEL_PRIMARY = _s.add("SEL_PRIMARY", 1, "", "index of the primary lane")
SEL_N_LANES = _s.add("SEL_N_LANES", 1, "", "lanes running")
SEL_CHANGES = _s.add("SEL_CHANGES", 1, "", "number of primary changes (ERR 24 events)")
SEL_T_SWITCH = _s.add("SEL_T_SWITCH", 1, "s", "time of the last switch (-1 if none)")
SEL_RUN = _s.add("SEL_RUN", 1, "", "1 once the primary has been healthy for 10 s (latched)")
SEL_HEALTHY_SINCE = _s.add("SEL_HEALTHY_SINCE", 1, "s",
                           "time the primary became continuously healthy (-1 if not)")
SEL_REL_ERR = _s.add("SEL_REL_ERR", MAX_LANES, "", "relative error per lane")
SEL_T_PRIMARY = _s.add("SEL_T_PRIMARY", MAX_LANES, "s",
                       "time each lane last stopped being primary")
SEL_GPS_GLITCH = _s.add("SEL_GPS_GLITCH", 1, "",
                        "gps_glitching of the primary as ArduCopter's 10 Hz check last saw it")
N_SEL = SELECTOR.close()

# ------------------------------------------------------------------ configuration --------------
CONFIG = Layout("cfg", "EKF configuration (built once per flight from EK3_* parameters)")
_c = CONFIG
C_DT = _c.add("C_DT", 1, "s", "nominal main-loop period")
C_TARGET_DT = _c.add("C_TARGET_DT", 1, "s", "covariance prediction target interval (EKF3: 12 ms)")
C_VELNE_NSE = _c.add("C_VELNE_NSE", 1, "m/s", "EK3_VELNE_M_NSE")
C_VELD_NSE = _c.add("C_VELD_NSE", 1, "m/s", "EK3_VELD_M_NSE")
C_POSNE_NSE = _c.add("C_POSNE_NSE", 1, "m", "EK3_POSNE_M_NSE")
C_ALT_NSE = _c.add("C_ALT_NSE", 1, "m", "EK3_ALT_M_NSE")
C_MAG_NSE = _c.add("C_MAG_NSE", 1, "gauss", "EK3_MAG_M_NSE")
C_GYRO_PNSE = _c.add("C_GYRO_PNSE", 1, "rad/s", "EK3_GYRO_P_NSE")
C_ACC_PNSE = _c.add("C_ACC_PNSE", 1, "m/s^2", "EK3_ACC_P_NSE")
C_GBIAS_PNSE = _c.add("C_GBIAS_PNSE", 1, "rad/s^2", "EK3_GBIAS_P_NSE")
C_ABIAS_PNSE = _c.add("C_ABIAS_PNSE", 1, "m/s^3", "EK3_ABIAS_P_NSE")
C_VEL_GATE = _c.add("C_VEL_GATE", 1, "", "EK3_VEL_I_GATE as sigmas: max(gate / 100, 1)")
C_POS_GATE = _c.add("C_POS_GATE", 1, "", "EK3_POS_I_GATE as sigmas")
C_HGT_GATE = _c.add("C_HGT_GATE", 1, "", "EK3_HGT_I_GATE as sigmas")
C_MAG_GATE = _c.add("C_MAG_GATE", 1, "", "EK3_MAG_I_GATE as sigmas")
C_GLITCH_RAD = _c.add("C_GLITCH_RAD", 1, "m", "EK3_GLITCH_RAD")
C_NOAID_NSE = _c.add("C_NOAID_NSE", 1, "m", "EK3_NOAID_M_NSE")
C_ERR_THRESH = _c.add("C_ERR_THRESH", 1, "", "EK3_ERR_THRESH")
C_GPS_DELAY = _c.add("C_GPS_DELAY", 1, "s", "assumed GPS measurement delay")
C_HGT_DELAY = _c.add("C_HGT_DELAY", 1, "s", "EK3_HGT_DELAY")
C_MAG_N, C_MAG_E, C_MAG_D = _c.vector(("C_MAG_N", "C_MAG_E", "C_MAG_D"), "gauss",
                                      "earth magnetic field NED")
C_POS_RETRY = _c.add("C_POS_RETRY", 1, "s",
                     "GPS position/velocity timeout (EKF3 posRetryTimeNoVel)")
C_POS_RETRY_VEL = _c.add("C_POS_RETRY_VEL", 1, "s",
                         "GPS position timeout while GPS velocity passes (posRetryTimeUseVel)")
C_TILT_DRIFT = _c.add("C_TILT_DRIFT", 1, "s", "time without aiding before constant-position mode")
C_HGT_RETRY = _c.add("C_HGT_RETRY", 1, "s",
                     "height timeout: a rejected height is reset to baro, a missing one invalid")
C_USING_GPS_T = _c.add("C_USING_GPS_T", 1, "s", "using_gps flag window")
C_CONSTPOS_DT = _c.add("C_CONSTPOS_DT", 1, "s", "interval of constant-position pseudo-measurements")
C_GBIAS_LIM = _c.add("C_GBIAS_LIM", 1, "rad/s", "gyro bias limit")
C_ABIAS_LIM = _c.add("C_ABIAS_LIM", 1, "m/s^2", "EK3_ACC_BIAS_LIM")
C_ALIGN_TIME = _c.add("C_ALIGN_TIME", 1, "s", "accel averaging time for tilt alignment")
C_LANE_INIT_T = _c.add("C_LANE_INIT_T", 1, "s", "lane unhealthy for this long after alignment")
C_SCORE_LAG = _c.add("C_SCORE_LAG", 1, "s",
                     "how much later the primary's fusion shows in the relative errors")
C_SELECT_T = _c.add("C_SELECT_T", 1, "s",
                    "primary healthy this long before selection runs; min time between uses")
C_ONGROUND_NSE = _c.add("C_ONGROUND_NSE", 1, "m", "constant-position noise while disarmed")
C_N_LANES = _c.add("C_N_LANES", 1, "", "number of lanes (from EK3_IMU_MASK)")
C_LANE_IMU = _c.add("C_LANE_IMU", MAX_LANES, "", "IMU instance of each lane")
C_BAD_IMU_ACC_NSE = _c.add("C_BAD_IMU_ACC_NSE", 1, "m/s^2",
                           "accel process noise while the IMU is bad")
C_BAD_IMU_HOLD = _c.add("C_BAD_IMU_HOLD", 1, "s", "bad-IMU response hold time")
C_BAD_IMU_TIMEOUT = _c.add("C_BAD_IMU_TIMEOUT", 1, "s",
                           "continuous bad-IMU time before a height reset")
C_TAU_OUTPUT = _c.add("C_TAU_OUTPUT", 1, "s", "EK3_TAU_OUTPUT: output observer time constant")
C_MAG_FAIL_T = _c.add("C_MAG_FAIL_T", 1, "s",
                      "EKF3 magFailTimeLimit: a lane changes compass after its compass has been "
                      "unhealthy and silent, or its fusion rejected in flight, this long")
C_MAG_SWITCH_T0 = _c.add("C_MAG_SWITCH_T0", 1, "s",
                         "no compass change for rejected fusion this soon after alignment")
C_INFLIGHT_HGT = _c.add("C_INFLIGHT_HGT", 1, "m",
                        "height above the origin (armed) from which a lane counts as in flight")
C_BOOT = _c.add("C_BOOT", 1, "", "1: SITL's boot phase (TLM_BOOT_PHASE): lanes start at "
                "C_EKF_START, align tilt and yaw, wait for the GPS checks, origin and gyro bias "
                "learning before using GPS; 0: ready from the first GPS sample")
C_EKF_START = _c.add("C_EKF_START", 1, "s", "time the EKF lanes initialise (EKF3 InitialiseFilter)")
C_GPS_CHECK = _c.add("C_GPS_CHECK", 1, "", "EK3_GPS_CHECK bit mask")
C_CHECK_SCALE = _c.add("C_CHECK_SCALE", 1, "", "EK3_CHECK_SCALE / 100")
C_YAW_NSE = _c.add("C_YAW_NSE", 1, "rad", "EK3_YAW_M_NSE (heading fusion)")
C_YAW_GATE = _c.add("C_YAW_GATE", 1, "", "EK3_YAW_I_GATE as sigmas")
C_GSF_RUN_MASK = _c.add("C_GSF_RUN_MASK", 1, "",
                        "EK3_GSF_RUN_MASK: lanes (bit i: lane i) that run a yaw estimator")
N_CFG = CONFIG.close()

# ------------------------------------------------------------------ output vector --------------
# filled by tlm_sim.ekf.lanes.ekf_output from the primary lane
OUTPUT = Layout("out", "EKF output: what the rest of the vehicle reads")
_o = OUTPUT
O_QW, O_QX, O_QY, O_QZ = _o.vector(("O_QW", "O_QX", "O_QY", "O_QZ"), "",
                                   "quaternion body -> NED")
O_VN, O_VE, O_VD = _o.vector(("O_VN", "O_VE", "O_VD"), "m/s", "velocity NED")
O_PN, O_PE, O_PD = _o.vector(("O_PN", "O_PE", "O_PD"), "m", "position NED")
O_BGX, O_BGY, O_BGZ = _o.vector(("O_BGX", "O_BGY", "O_BGZ"), "rad/s", "gyro bias")
O_BAX, O_BAY, O_BAZ = _o.vector(("O_BAX", "O_BAY", "O_BAZ"), "m/s^2", "accel bias")
O_ROLL, O_PITCH, O_YAW = _o.vector(("O_ROLL", "O_PITCH", "O_YAW"), "rad",
                                   "Euler angles (ZYX), yaw in (-pi, pi]")
O_F_ATTITUDE, O_F_HORIZ_VEL, O_F_HORIZ_POS, O_F_VERT_POS = _o.vector(
    ("O_F_ATTITUDE", "O_F_HORIZ_VEL", "O_F_HORIZ_POS", "O_F_VERT_POS"), "", "status flags")
O_F_CONST_POS, O_F_USING_GPS = _o.vector(("O_F_CONST_POS", "O_F_USING_GPS"), "",
                                         "status flags")
O_SQRT_VEL, O_SQRT_POS, O_SQRT_HGT, O_SQRT_MAG = _o.vector(
    ("O_SQRT_VEL", "O_SQRT_POS", "O_SQRT_HGT", "O_SQRT_MAG"), "", "sqrt of the test ratios")
O_PRIMARY = _o.add("O_PRIMARY", 1, "", "primary lane")
O_PRIMARY_CHANGES = _o.add("O_PRIMARY_CHANGES", 1, "", "primary lane changes so far")
O_POS_RESET_COUNT = _o.add("O_POS_RESET_COUNT", 1, "", "position resets of the primary")
O_VEL_RESET_COUNT = _o.add("O_VEL_RESET_COUNT", 1, "", "velocity resets of the primary")
O_IMU = _o.add("O_IMU", 1, "", "IMU instance the primary lane integrates")
O_R00, O_R01, O_R02, O_R10, O_R11, O_R12, O_R20, O_R21, O_R22 = _o.vector(
    ("O_R00", "O_R01", "O_R02", "O_R10", "O_R11", "O_R12", "O_R20", "O_R21", "O_R22"), "",
    "rotation matrix body -> NED, row-major")
O_INNOV_VD = _o.add("O_INNOV_VD", 1, "m/s",
                    "GPS down-velocity innovation, measurement - prediction")
O_INNOV_HGT = _o.add("O_INNOV_HGT", 1, "m", "height innovation (down), measurement - prediction")
O_VEL_TR, O_POS_TR, O_MAG_TR = _o.vector(("O_VEL_TR", "O_POS_TR", "O_MAG_TR"), "",
                                         "test ratios (velocity, horizontal position, compass)")
O_BAD_IMU = _o.add("O_BAD_IMU", 1, "", "1 while the bad-IMU (vibration) response is active")
# what the pre-arm checks ask of EKF3 (its pre_arm_check, attitude and variance status)
O_HEALTHY = _o.add("O_HEALTHY", 1, "", "1 while the primary lane is healthy")
O_ALIGNED = _o.add("O_ALIGNED", 1, "", "1 once the primary lane has aligned (EKF started)")
O_TILT_DONE, O_YAW_DONE = _o.vector(("O_TILT_DONE", "O_YAW_DONE"), "",
                                    "1 once the primary lane's tilt / yaw alignment is complete")
O_GPS_GLITCHING = _o.add("O_GPS_GLITCHING", 1, "",
                         "1 while the primary lane rejects GPS position as a glitch")
O_HGT_TR = _o.add("O_HGT_TR", 1, "", "height test ratio of the primary lane")
O_ORIGIN_OK = _o.add("O_ORIGIN_OK", 1, "", "1 once the primary lane's origin is set")
O_N_LANES = _o.add("O_N_LANES", 1, "", "lanes whose status records O_LANES holds")

# one status record per lane: what EKF3 reports of each core (health, origin, texts)
LANE_STATUS = Layout("lane status", "one EKF lane's published status")
LS_HEALTHY = LANE_STATUS.add("LS_HEALTHY", 1, "", "1 while the lane is healthy")
LS_ORIGIN_OK = LANE_STATUS.add("LS_ORIGIN_OK", 1, "", "1 once the lane's origin is set")
LS_IMU = LANE_STATUS.add("LS_IMU", 1, "", "IMU instance the lane integrates (its name in texts)")
LS_MAG = LANE_STATUS.add("LS_MAG", 1, "", "compass the lane reads (0-based)")
LS_EVENTS = LANE_STATUS.add("LS_EVENTS", 1, "",
                            "lifecycle events (ardupilot.EKF_EVT_* bits) raised since the "
                            "last publication: each event is published once")
LANE_STRIDE = LANE_STATUS.close()
O_LANES = _o.block("O_LANES", LANE_STATUS, MAX_LANES)
N_OUT = OUTPUT.close()

#: The EKF's output block: all the rest of the vehicle may read of the EKF (the O_* slots and
#: the lanes' status records); the lanes, the selector and the configuration are its own
#: (tests/test_structure_sim.py).
PUBLISHED: frozenset[str] = frozenset({
    "N_OUT", "MAX_LANES", "LANE_STRIDE", *(slot.name for slot in OUTPUT),
    *(slot.name for slot in LANE_STATUS),
})
