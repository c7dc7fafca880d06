"""Measuring a vehicle in one log, the first half of ``tlm fit`` (issue 40): the statistics a
steady segment shows (:mod:`~tlm_process.fit.stats`: hover throttle, attitude noise, IMU accel
and gyro noise per axis, rate-tracking error, VIBE) and where a log's steady segments are
(:mod:`~tlm_process.fit.segment`). They read real Copter 3.x logs, SITL's and tlm's alike."""
