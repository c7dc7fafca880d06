"""Slots of the DCM attitude estimator array (ArduPilot's ``AP_AHRS_DCM``), declared once
(:class:`tlm_sim.slots.Layout`; ``DCM.describe(dcm)``).

``dcm[N_DCM]`` -- the AHRS's second attitude solution, run every main-loop tick beside the EKF
by :func:`tlm_sim.control.dcm.dcm_update` and logged as DCM and AHR2. Frames: earth NED
(relative to home), body FRD; the direction cosine matrix takes body vectors to NED
(row-major). Times are seconds since boot.
"""

from tlm_sim.sensors.layout import N_IMU
from tlm_sim.slots import Layout

DCM = Layout("dcm", "DCM attitude estimator (AP_AHRS_DCM)")
_d = DCM
D_R = _d.add("D_R", 9, "", "direction cosine matrix body -> NED, row-major")
D_ROLL = _d.add("D_ROLL", 1, "rad",
                 "roll of the matrix (DCM.Roll, AHR2.Roll; control.dcm.dcm_eulers refreshes)")
D_PITCH = _d.add("D_PITCH", 1, "rad", "pitch of the matrix")
D_YAW = _d.add("D_YAW", 1, "rad", "yaw of the matrix, (-pi, pi]")
D_OMEGA = _d.add("D_OMEGA", 3, "rad/s",
                 "primary filtered gyro plus the drift estimate (its length: the spin rate)")
D_OMEGA_P = _d.add("D_OMEGA_P", 3, "rad/s", "roll/pitch proportional correction, body")
D_OMEGA_YAW_P = _d.add("D_OMEGA_YAW_P", 3, "rad/s", "yaw proportional correction, body")
D_OMEGA_I = _d.add("D_OMEGA_I", 3, "rad/s", "gyro drift estimate (omega_I), body")
D_OMEGA_I_SUM = _d.add("D_OMEGA_I_SUM", 3, "rad/s",
                       "integrator input collected until it is applied to omega_I (every 5 s)")
D_OMEGA_I_SUM_T = _d.add("D_OMEGA_I_SUM_T", 1, "s", "time collected in D_OMEGA_I_SUM")
D_RA_SUM = _d.add("D_RA_SUM", 3 * N_IMU, "m/s",
                  "per accel: its specific force rotated to NED, integrated since the last "
                  "correction (scaled to g units at the correction)")
D_RA_DELAY = _d.add("D_RA_DELAY", 3 * N_IMU, "",
                    "per accel: the previous correction's scaled sum (matches the GPS lag)")
D_RA_DT = _d.add("D_RA_DT", 1, "s", "time integrated in D_RA_SUM")
D_RA_START = _d.add("D_RA_START", 1, "s",
                    "GPS fix (or time) the sums started at; -1 before the first")
D_LAST_VEL = _d.add("D_LAST_VEL", 3, "m/s", "velocity NED of the last correction")
D_GPS_LOCK = _d.add("D_GPS_LOCK", 1, "", "1 when the last correction used GPS velocity")
D_LAST_TAS = _d.add("D_LAST_TAS", 1, "m/s",
                    "forward speed through the air at the last GPS correction (dead reckoning)")
D_ACCEL_EF = _d.add("D_ACCEL_EF", 3, "m/s^2",
                    "primary filtered accel rotated to NED (at the last compass sample)")
D_ERR_RP = _d.add("D_ERR_RP", 1, "", "roll/pitch error, low-passed (DCM.ErrRP)")
D_ERR_YAW = _d.add("D_ERR_YAW", 1, "", "heading error, low-passed (DCM.ErrYaw)")
D_HAVE_YAW = _d.add("D_HAVE_YAW", 1, "", "1 once the heading was set from the compass")
D_MAG_T = _d.add("D_MAG_T", 1, "us", "time of the compass sample last used (0: none)")
D_GPS_T = _d.add("D_GPS_T", 1, "s", "time of the latest GPS epoch (-1: none)")
D_POS_N, D_POS_E = _d.vector(("D_POS_N", "D_POS_E"), "m",
                             "position of the last GPS correction, NE from home")
D_OFS_N, D_OFS_E = _d.vector(("D_OFS_N", "D_OFS_E"), "m",
                             "dead-reckoned offset since the last GPS position")
D_HAVE_POS = _d.add("D_HAVE_POS", 1, "", "1 once a GPS position was seen")
D_T_POS = _d.add("D_T_POS", 1, "s", "time of the last GPS position")
D_T_START = _d.add("D_T_START", 1, "s", "time of the last reset (fast gains for 20 s after)")
D_INIT = _d.add("D_INIT", 1, "", "1 once the matrix was initialised from the accel")
D_INIT_TRIES = _d.add("D_INIT_TRIES", 1, "", "ticks spent waiting for a usable accel at start")
N_DCM = DCM.close()
