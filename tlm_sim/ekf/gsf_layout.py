"""Slots of the EKF-GSF yaw estimator array (EKF3's ``EKFGSF_yaw``), declared once
(:class:`tlm_sim.slots.Layout`; ``GSF.describe(gsf[lane])``).

``gsf[lane, N_GSF]`` -- one row per EKF lane, as EKF3 gives each core its own yaw estimator
(EK3_GSF_RUN_MASK): a bank of ``N_MODELS`` yaw hypotheses, each an AHRS complementary filter
(rotation matrix and gyro bias) with a three-state EKF (velocity north, east, yaw) on top,
combined by a Gaussian sum filter whose weights follow the GPS velocity innovations. The
kernels are :mod:`tlm_sim.ekf.gsf`; XKY0 / XKY1 log the row (:func:`tlm_sim.ekf.log.log_gsf`).

The models' AHRS differ only by a rotation about the vertical (module docstring of
:mod:`tlm_sim.ekf.gsf`): the row holds one AHRS (``G_R``, ``G_GBIAS``) and each model's
heading offset from it as a unit vector (``M_COS``, ``M_SIN``); model m's AHRS matrix is
``Rz(offset_m) @ G_R``.

Frames: earth NED, body FRD; the rotation matrices take body vectors to NED (row-major). The
estimator runs on the lane's IMU data summed to EKF3's prediction steps and delayed by the
assumed GPS delay (EKF3 runs it on its delayed-horizon IMU data), through the step buffer
``G_BUF``.
"""

from tlm_sim.slots import Layout

N_MODELS = 5  # EKF3's N_MODELS_EKFGSF
NBUF_STEPS = 32  # delay line length in prediction steps (0.4 s of 12.5 ms steps)
STEP_ROW = 7  # one delay-line row: delta angle (3), delta velocity (3), interval

# ------------------------------------------------------------------ one model ----------------
MODEL = Layout("gsf model", "one yaw hypothesis: its AHRS heading offset and its three-state EKF")
_m = MODEL
M_COS = _m.add("M_COS", 1, "", "cosine of the model's AHRS heading offset from G_R")
M_SIN = _m.add("M_SIN", 1, "", "sine of the model's AHRS heading offset from G_R")
M_VN = _m.add("M_VN", 1, "m/s", "EKF state: velocity north")
M_VE = _m.add("M_VE", 1, "m/s", "EKF state: velocity east")
M_YAW = _m.add("M_YAW", 1, "rad",
               "EKF state: yaw; while fusing it is the yaw of the model's AHRS (the firmware "
               "recomputes it at every prediction), refreshed by gsf.gsf_refresh when read")
M_P = _m.add("M_P", 9, "m^2/s^2, m rad/s, rad^2",
             "EKF covariance of (vn, ve, yaw), row-major, kept symmetric")
M_S = _m.add("M_S", 4, "m^2/s^2", "NE velocity innovation variance of the last fusion, row-major")
M_INNOV = _m.add("M_INNOV", 2, "m/s",
                 "NE velocity innovations of the last fusion, prediction - measurement (XKY1)")
MODEL_STRIDE = MODEL.close()

# ------------------------------------------------------------------ lane row -----------------
GSF = Layout("gsf", "EKF-GSF yaw estimator of one EKF lane (row of the gsf array)")
_g = GSF
G_ENABLED = _g.add("G_ENABLED", 1, "", "1 when EK3_GSF_RUN_MASK gives the lane an estimator")
G_RUN = _g.add("G_RUN", 1, "",
               "EKF3's EKFGSF_run_filterbank: 1 while armed with the GPS speed accuracy passing")
G_FUSING = _g.add("G_FUSING", 1, "",
                  "vel_fuse_running: 1 once the bank fuses GPS velocity (XKY0/XKY1 logged)")
G_TILT_ALIGNED = _g.add("G_TILT_ALIGNED", 1, "", "1 once the AHRS tilt was set from the accel")
G_R = _g.add("G_R", 9, "", "the AHRS rotation matrix body -> NED (heading offset 0), row-major")
G_GBIAS = _g.add("G_GBIAS", 3, "rad/s", "AHRS gyro bias, body (subtracted from the gyro)")
G_ACC = _g.add("G_ACC", 3, "m/s^2", "low-pass filtered specific force, body (AHRS tilt reference)")
G_ACC_GAIN = _g.add("G_ACC_GAIN", 1, "1/s", "AHRS tilt correction gain")
G_YAW = _g.add("G_YAW", 1, "rad",
               "composite yaw, weighted over the models (XKY0.YC; refreshed when read)")
G_YAW_VAR = _g.add("G_YAW_VAR", 1, "rad^2", "composite yaw variance (refreshed when read)")
G_W = _g.add("G_W", N_MODELS, "", "model weights, summing to 1 (XKY0.W0..W4)")
G_N_CLIPS = _g.add("G_N_CLIPS", 1, "", "models whose weight hit the floor at the last fusion")
G_SUM_DANG = _g.add("G_SUM_DANG", 3, "rad", "delta angle summed since the last step")
G_SUM_DVEL = _g.add("G_SUM_DVEL", 3, "m/s", "delta velocity summed since the last step")
G_SUM_DT = _g.add("G_SUM_DT", 1, "s", "time summed since the last step")
G_BUF_HEAD = _g.add("G_BUF_HEAD", 1, "", "index of the newest delay-line row")
G_BUF_COUNT = _g.add("G_BUF_COUNT", 1, "", "delay-line rows filled (<= NBUF_STEPS)")
G_BUF = _g.add("G_BUF", NBUF_STEPS * STEP_ROW, "rad, m/s, s",
               "delay line of prediction steps: NBUF_STEPS rows of (delta angle, delta "
               "velocity, interval)")
MODEL_BASE = _g.block("MODEL", MODEL, N_MODELS)
N_GSF = GSF.close()
assert G_SUM_DVEL == G_SUM_DANG + 3 and G_SUM_DT == G_SUM_DANG + 6  # one STEP_ROW, as G_BUF's
