"""Timing of SITL's boot phase (``TLM_BOOT_PHASE`` 1), as the reference SITL logs show it.

ArduCopter SITL does not fly at once: the GPS driver first has to find the simulated u-blox,
the EKF starts once the IMU buffers are filled, aligns its tilt and then its yaw to the
compass, sets its origin after 10 s of good GPS, and uses GPS once its gyro biases are
learnt; the driver (the script that ran the reference flights) meanwhile switches to GUIDED
and tries to arm every 2 s until the pre-arm checks pass. Most of that chain is modelled
(:mod:`tlm_sim.ekf.lifecycle`, :mod:`tlm_sim.control.arming`); what is firmware start-up or
the driver's cadence, with nothing to simulate, is a time here. Every value is the same to the
millisecond in all 15 reference logs (``shared/reference/sitl``: their MSG and GPS tables),
times since boot (SITL's ``TimeUS``; its log starts at 2.497 s).
"""

from __future__ import annotations

#: "EKF3 IMU0 initialised" (AP_AHRS starts EKF3 once the INS is up); "AHRS: EKF3 active"
#: follows one main-loop tick later [s]
BOOT_EKF_START_S = 4.4541
#: the first GPS message: AP_GPS's auto-baud probing finds SITL's u-blox at 230400 baud
#: ("GPS 1: probing for u-blox at 230400 baud" 20 ms before, "GPS 1: detected u-blox") [s]
BOOT_GPS_DETECT_S = 9.8294
#: the probing message comes this long before the detection [s]
BOOT_GPS_PROBE_LEAD_S = 0.02
#: the reference driver switches to GUIDED (MODE 4, reason GCS) after its mission upload [s]
BOOT_DRIVER_S = 3.7044
#: its first arm attempts ("Arm: ..." lines) [s]; then one every ARM_RETRY_S after the second
BOOT_ARM_ATTEMPTS_S = (3.7543, 3.9543)
#: the baro's boot calibration: BARO.GndTemp is the sensor temperature at this time until the
#: field elevation is set (25.365 degC in every reference log: SIM_TEMP_START 25 warming
#: towards 31.2 degC with SIM_TEMP_TCONST 30 s) [s]
BARO_CAL_S = 1.82
#: the pre-arm checks run at 1 Hz from this time (AP_Arming::update; "PreArm:" lines at
#: 30.449 s in every reference log) [s]
PREARM_FIRST_S = 3.4494
#: when the reference flights armed (normal_s11: 42.22 s; 41.94-43.13 s in the 15 logs): the
#: flight's log buffers and time cap allow for it [s]
BOOT_ARM_S = 42.2
