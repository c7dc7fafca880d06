"""The flight: one numba call runs physics, sensors, EKF, autopilot and logging for a whole flight.

``fly(mission, faults=None, params=None, seed=0) -> FlightLog`` is the public entry point. It
builds the per-subsystem arrays from the parameters once, allocates the log buffers, runs
:func:`run_flight` (a single ``@njit(cache=True, nogil=True)`` call: 1200 Hz physics on an
integer-microsecond clock, 400 Hz main loop) and wraps the buffers into a FlightLog.
A flight is a pure function of (mission, faults, parameters, seed).
"""

from __future__ import annotations

import datetime as _dt
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from tlm_sim import ardupilot as AP
from tlm_sim import logger as L
from tlm_sim._jit import inline_jit, loop_jit, tick_jit
from tlm_sim.boot import BOOT_ARM_S
from tlm_sim.bundles import (
    EkfInputs,
    FlightLogs,
    FlightPlan,
    LoopTick,
    LoopWork,
    VehicleConfig,
    VehicleInputs,
    VehicleState,
)
from tlm_sim.control import layout as C
from tlm_sim.control.ahrs import ahrs_update
from tlm_sim.control.arming import (
    arming_init,
    arming_step,
    boot_texts_due,
    lifecycle_texts,
)
from tlm_sim.control.battery import battery_monitor
from tlm_sim.control.config import build_control_config
from tlm_sim.control.dcm import dcm_init, dcm_update
from tlm_sim.control.dcm_layout import N_DCM
from tlm_sim.control.events import log_err, log_mode
from tlm_sim.control.log import (
    CMD_TAKEOFF,
    log_control_10hz,
    log_dcm_10hz,
    log_vehicle_events,
    vehicle_events_due,
)
from tlm_sim.control.mixer import throttle_slew_update
from tlm_sim.control.modes import arm_vehicle, vehicle_step
from tlm_sim.control.pilot import arm_pilot, pilot_gcs, pilot_init, pilot_rc
from tlm_sim.control.wpnav import (
    P_CMD,
    P_CNUM,
    P_HOLD,
    P_SPEED,
    P_STOP,
    PATH_COLS,
    prepare_path,
)
from tlm_sim.dynamics import layout as X
from tlm_sim.dynamics.body import init_state, physics_step
from tlm_sim.dynamics.frame import F_ENGINE_MASK, F_ENGINE_MUL, build_frame
from tlm_sim.dynamics.log import log_dynamics_10hz, log_sim2
from tlm_sim.earthfield import with_home_field
from tlm_sim.ekf import layout as EK
from tlm_sim.ekf.config import build_ekf_config, new_ekf
from tlm_sim.ekf.gsf import gsf_init, gsf_update
from tlm_sim.ekf.gsf_layout import N_GSF
from tlm_sim.ekf.lanes import (
    ekf_gps_accuracy,
    ekf_gps_checks,
    ekf_init,
    ekf_output,
    ekf_output_nav,
    ekf_update,
)
from tlm_sim.ekf.log import (
    gps_glitch_check,
    log_ekf_10hz,
    log_ekf_evidence,
    log_gsf,
    log_lane_switch,
)
from tlm_sim.faults import FaultSchedule, jitter_nsats
from tlm_sim.faults.records import fault_records
from tlm_sim.flightlog import LOGGED_MESSAGES, FlightLog, allocate_buffers
from tlm_sim.frames import FRAMES, MAX_MOTORS, frame_for
from tlm_sim.geo import HOME_CMAC
from tlm_sim.mission import Mission, builtin_mission
from tlm_sim.mission.mission import ITEM_FIELDS
from tlm_sim.mission.sticks import StickScript
from tlm_sim.params import Params
from tlm_sim.profiles import profile_params
from tlm_sim.rng import new_rng, new_streams
from tlm_sim.sensors import layout as S
from tlm_sim.sensors.baro import baro_init, baro_read, calibration_temperature
from tlm_sim.sensors.config import build_sensor_config
from tlm_sim.sensors.gps import gps_due, gps_init, gps_measure, gps_push_truth
from tlm_sim.sensors.imu import imu_init, imu_sample, imu_take_deltas
from tlm_sim.sensors.log import log_gps, log_imu, log_sensors_10hz
from tlm_sim.sensors.mag import (
    mag_init,
    mag_sample,
)
from tlm_sim.sensors.power import power_module_read
from tlm_sim.sensors.rc import RC_COLS, rc_init, rc_update
from tlm_sim.slots import Layout

# the physics tick and the main loop at the rates tlm simulates (SIM_RATE_HZ and
# SCHED_LOOP_RATE are pinned to them: tlm_sim.params refuses any other value)
PHYSICS_DT_US = int(1e6 // AP.SIM_RATE_HZ)  # 833 us at 1200 Hz, as SITL
LOOP_DT_US = round(1e6 / AP.LOOP_RATE_HZ)  # 2500 us at 400 Hz


def task_ticks(task: str) -> int:
    """Main-loop ticks between two runs of ``task`` (a task of
    :data:`tlm_sim.ardupilot.TASK_RATES_HZ`); ValueError unless the loop rate is a whole
    multiple of its rate."""
    n, rest = divmod(AP.LOOP_RATE_HZ, AP.TASK_RATES_HZ[task])
    if rest or n < 1:
        raise ValueError(f"task {task} at {AP.TASK_RATES_HZ[task]} Hz does not divide the "
                         f"{AP.LOOP_RATE_HZ} Hz main loop")
    return n


# the main loop's schedule (module constants: numba compiles them in)
GLITCH_CHECK_TICKS = task_ticks("gpsglitch_check")  # 40: 10 Hz
SIM2_TICKS = task_ticks("sim_state_logging")  # 8: 50 Hz
IMU_LOG_TICKS = task_ticks("twentyfive_hz_logging")  # 16: 25 Hz
TEN_HZ_LOG_TICKS = task_ticks("ten_hz_logging_loop")  # 40: 10 Hz
BARO_PERIOD_US = 1e6 / AP.TASK_RATES_HZ["update_altitude"]  # 100000.0 us: 10 Hz
MAG_PERIOD_US = 1e6 / AP.TASK_RATES_HZ["update_batt_compass"]  # 100000.0 us: 10 Hz
GPS_EPOCH = _dt.datetime(1980, 1, 6, tzinfo=_dt.UTC)
BOOT_UTC = _dt.datetime(2025, 10, 24, 12, 0, 0, tzinfo=_dt.UTC)  # simulated boot time (UTC)
LEAP_SECONDS = 18

#: the flight ends this long after the autopilot disarms or the arming driver gives up [us]
END_AFTER_US = 2_000_000

# schedule targets: which configuration array a parameter change writes into (its field of
# VehicleConfig, the order build_schedule enumerates the configuration in)
TGT_FRAME, TGT_SENSOR, TGT_EKF, TGT_CONTROL = (
    VehicleConfig._fields.index(name) for name in ("frame", "scfg", "ecfg", "g"))
TGT_NONE = -1  # marks a change that alters no configuration entry (its time is still recorded)

#: The columns of a row of the change schedule (:func:`build_schedule`)
SCHEDULE_ROW = Layout("schedule row", "one scheduled write into a configuration array")
SCH_AT = SCHEDULE_ROW.add("SCH_AT", 1, "us or waypoints",
                          "when it is due: a time since boot, or a count of waypoints reached")
SCH_KIND = SCHEDULE_ROW.add("SCH_KIND", 1, "", "trigger kind (TRIG_TIME, TRIG_WP)")
SCH_TGT = SCHEDULE_ROW.add("SCH_TGT", 1, "", "target configuration array (TGT_*)")
SCH_IDX = SCHEDULE_ROW.add("SCH_IDX", 1, "", "the slot written in that array")
SCH_VAL = SCHEDULE_ROW.add("SCH_VAL", 1, "", "the value written (the array's units)")
SCH_CHANGE = SCHEDULE_ROW.add("SCH_CHANGE", 1, "",
                              "the parameter change it realises (its position in the changes)")
N_SCH = SCHEDULE_ROW.close()
# trigger kinds
TRIG_TIME = 0  # SCH_AT is a time [us since boot]
TRIG_WP = 1  # SCH_AT is a waypoint number: due once that many mission waypoints are reached

#: Why a flight ended (``FlightLog.meta["end_reason"]``): the land detector disarmed the copter
#: on the ground (the normal end), the crash check disarmed it (ERR CRASH_CHECK), or it was
#: still armed when the loop reached the time cap (:func:`max_duration_s`), e.g. sitting armed
#: on the ground after an engine fault or unable to advance against a strong wind: its tables
#: are valid but the flight was cut off.
END_LANDED, END_CRASH, END_TIME_CAP = "landed", "crash", "time_cap"
#: ... or it never armed: the driver's arm attempts failed the pre-arm checks until it gave up
#: (tlm_sim.control.arming ARM_TIMEOUT_S after its first attempt; the reasons are the flight's
#: "Arm:" / "PreArm:" texts)
END_NOT_ARMED = "not_armed"
END_REASONS: tuple[str, ...] = (END_LANDED, END_CRASH, END_TIME_CAP, END_NOT_ARMED)

#: The rows of run_flight's scratch block (:func:`new_work`): one row per per-tick vector the
#: main loop hands between its stages, :data:`WORK_COLS` wide (the widest of them).
WORK = Layout("work", "run_flight's scratch rows (rows of new_work's block)")
W_IMU_OK = WORK.add("W_IMU_OK", doc="per IMU i: [i] its accel delivered samples this tick, "
                    "[N_IMU + i] its gyro did (0/1)")
W_GPS = WORK.add("W_GPS", doc="the GPS epoch of this tick (sensors.layout GE_*)")
W_PWM = WORK.add("W_PWM", doc="the motors' PWM as the engine fault alters it [us]")
W_POS = WORK.add("W_POS", doc="the controllers' position NED from home (control.ahrs) [m]")
W_VEL = WORK.add("W_VEL", doc="the controllers' velocity NED (control.ahrs) [m/s]")
W_Q = WORK.add("W_Q", doc="the controllers' attitude quaternion body->NED (control.ahrs)")
W_GYRO = WORK.add("W_GYRO", doc="the controllers' body rates (control.ahrs) [rad/s]")
W_ACC_NED = WORK.add("W_ACC_NED", doc="the controllers' acceleration NED (control.ahrs) [m/s^2]")
N_WORK_ROWS = WORK.close()
#: the scratch rows' width: the widest row's (imu_ok, the GPS epoch, the PWM of MAX_MOTORS
#: outputs, the quaternion)
WORK_COLS = max(2 * S.N_IMU, S.N_GPS_EPOCH, MAX_MOTORS, 4)



def gps_week_ms(utc: _dt.datetime) -> tuple[int, int]:
    """GPS week and milliseconds of week for a UTC time."""
    dt = utc - GPS_EPOCH + _dt.timedelta(seconds=LEAP_SECONDS)
    ms = int(dt.total_seconds() * 1000)
    return ms // (7 * 86400000), ms % (7 * 86400000)


@tick_jit
def _apply_schedule(plan, cfg, k, t_us, wp_reached):
    """Apply the scheduled rows of plan.sched that are due, strictly in order, to the
    configuration arrays cfg; returns the next row index.

    A row is due when its trigger has passed: time rows at t_us >= SCH_AT, waypoint rows once
    wp_reached >= SCH_AT. plan.applied[change] gets the time [us] its first row was applied.
    """
    sched, applied = plan.sched, plan.applied
    while k < sched.shape[0]:
        if sched[k, SCH_KIND] == TRIG_TIME:
            if sched[k, SCH_AT] > t_us:
                break
        elif wp_reached < sched[k, SCH_AT]:
            break
        ch = int(sched[k, SCH_CHANGE])
        if applied[ch] < 0.0:
            applied[ch] = t_us
        tgt = int(sched[k, SCH_TGT])
        idx = int(sched[k, SCH_IDX])
        v = sched[k, SCH_VAL]
        if tgt == TGT_NONE:
            pass
        elif tgt == TGT_SENSOR:
            cfg.scfg[idx] = v
        elif tgt == TGT_FRAME:
            cfg.frame[idx] = v
        elif tgt == TGT_CONTROL:
            cfg.g[idx] = v
        else:
            cfg.ecfg[idx] = v
        k += 1
    return k


@tick_jit
def _motor_pwm(c, frame, pwm):
    """Commanded PWM -> what the motors see: SIM_ENGINE_MUL on the SIM_ENGINE_FAIL outputs,
    ``1000 + (pwm - 1000) * mul`` truncated to whole microseconds as SITL's uint16 servo value
    (sitl-faults.md §6.1; RCOU keeps the commanded value). Returns the motors' mean output
    0..1 over those with a PWM (SITL's throttle for the IMU noise). run_flight calls it only
    when its inputs change (the autopilot's step, a scheduled parameter change), not every
    physics tick."""
    mask = int(frame[F_ENGINE_MASK])
    mul = frame[F_ENGINE_MUL]
    for i in range(MAX_MOTORS):
        p = c[C.MIX_PWM + i]
        if (mask >> i) & 1 and p > 0.0:  # (an output without a motor stays at 0)
            p = 1000.0 + float(int((p - 1000.0) * mul))
        pwm[i] = p
    thr_sum = 0.0
    n_on = 0
    for i in range(MAX_MOTORS):
        if pwm[i] > 0.0:
            thr_sum += (pwm[i] - 1000.0) / 1000.0
            n_on += 1
    return thr_sum / n_on if n_on > 0 else 0.0


@loop_jit
def run_flight(state, cfg, plan, logs, work, t_end_us):
    """Fly one whole flight in place; returns the final simulated time [us].

    state: the :class:`~tlm_sim.bundles.VehicleState` (truth, sensors, EKF lanes and selector,
    autopilot, DCM, yaw estimators, noise streams and the wind generator); cfg: the
    :class:`~tlm_sim.bundles.VehicleConfig` arrays (scheduled changes rewrite their slots);
    plan: the :class:`~tlm_sim.bundles.FlightPlan` (mission path, segment scratch, the change
    schedule of :func:`build_schedule` and, filled in, when each change took effect, home, GPS
    time at boot); logs: the :class:`~tlm_sim.bundles.FlightLogs` (buffers, row counts, text
    log); work: the :class:`~tlm_sim.bundles.LoopWork` scratch (:func:`new_work`).
    Allocation-free.

    The physics runs at 1200 Hz, the main loop (sensors, EKF, autopilot, logging) at 400 Hz;
    the flight ends 2 s after the autopilot disarms or the driver gives up arming, or at
    t_end_us.
    """
    x, s, ekf, sel, c, dcm, gsf, rng, wind_rng = state
    frame, scfg, ecfg, g = cfg
    path, seg, sched, applied, home, gps_time, rc, gcs = plan
    bufs, counts, txt = logs
    dang, dvel, rows, eo = work
    gps, pwm = rows[W_GPS], rows[W_PWM]
    pos, vel, q, gyro = rows[W_POS], rows[W_VEL], rows[W_Q], rows[W_GYRO]
    acc_ned = rows[W_ACC_NED]
    ev = L.event_buffers(bufs, counts)  # the event buffers (E_* order) and their row counts
    _boot(state, cfg, ev, home[0])
    k_sched = 0
    t_us = 0
    next_loop = 0
    tick = 0
    last_gps_ms = 0.0
    stop_at = -1
    throttle = _motor_pwm(c, frame, pwm)
    while t_us < t_end_us:
        k_next = _apply_schedule(plan, cfg, k_sched, t_us, c[C.WP_REACHED])
        if k_next != k_sched:  # a parameter changed: the engine fault may act on the PWM
            k_sched = k_next
            throttle = _motor_pwm(c, frame, pwm)
        t_us = _physics_tick(state, cfg, pwm, throttle, t_us)
        if t_us < next_loop:
            continue
        next_loop += LOOP_DT_US
        tick += 1
        gps_new, baro_new, mag_new = _read_sensors(state, scfg, work, t_us, ev)
        rc_update(s, scfg, float(t_us), rc, x)  # the RC receiver: the pilot's table or idle
        now = LoopTick(t_us, tick, gps_new, baro_new, mag_new)
        inputs = _ekf_inputs(state, work, now)
        dcm_update(dcm, g, s, inputs, gps, int(eo[EK.O_IMU]), t_us)
        _estimate(state, ecfg, work, now, inputs, ev)
        if boot_texts_due(c, eo):
            lifecycle_texts(c, now, eo, s, home[2], txt, ev)
        if tick % GLITCH_CHECK_TICKS == 0:  # ArduCopter's 10 Hz GPS glitch check
            gps_glitch_check(ev, t_us, ekf, sel)
        ahrs_update(eo, s, pos, vel, q, gyro, acc_ned)
        battery_monitor(c, g, t_us, s[S.PM_VOLT], s[S.PM_CURR], ev)
        vin = VehicleInputs(pos, vel, q, gyro, acc_ned, eo, s[S.PM_VOLT], s[S.RC_LAST_FRAME_US],
                            s[S.RC_CH + 2])
        pilot = g[C.G_PILOT] != 0.0
        if pilot:  # the pilot's radio: sticks, mode switch, rudder gestures
            pilot_rc(c, g, t_us, s[S.RC_CH:S.RC_CH + 8], vin, (seg, ev))
            pilot_gcs(c, g, t_us, gcs, vin, (seg, ev))
        vehicle_step(c, g, t_us, vin, path, seg, ev)
        if (c[C.ARMED] == 0.0 or t_us >= c[C.PREARM_NEXT_T] * 1e6) and arming_step(
                c, g, float(t_us), (s, gps), vin, txt, ev):
            if pilot:
                arm_pilot(c, g, t_us, vin, ev)
            else:
                arm_vehicle(c, t_us, q, ev)
        throttle_slew_update(c, g, t_us, q)  # the motors' throttle filter (RATE.AOutSlew)
        throttle = _motor_pwm(c, frame, pwm)  # the new commands, until the next main tick
        last_gps_ms = _log_tick(logs, state, cfg, plan, work, now, last_gps_ms)
        if stop_at < 0 and (c[C.DISARM_TIME] >= 0.0 or c[C.ARM_GAVE_UP] != 0.0):
            stop_at = t_us + END_AFTER_US
        if stop_at >= 0 and t_us >= stop_at:
            break
    return t_us


@inline_jit
def _boot(state, cfg, ev, home_lat):
    """Power on: sensors, EKF lanes, their yaw estimators and the DCM estimator initialised
    (the GPS found at once, or when the boot phase's driver finds it), the arming driver
    ready, the boot mode (STABILIZE) logged into the event buffers ev (events, counts)."""
    s, scfg = state.s, cfg.scfg
    imu_init(s, scfg, 0.0)
    gps_init(s, scfg[S.C_GPS_DETECT_US], home_lat)
    rc_init(s, 0.0)
    baro_init(s)
    s[S.B_GND_TEMP] = calibration_temperature(scfg)
    mag_init(s)
    ekf_init(state.ekf, state.sel, cfg.ecfg)
    arming_init(state.c, cfg.g)
    pilot_init(state.c)
    gsf_init(state.gsf, cfg.ecfg)
    dcm_init(state.dcm)
    log_mode(ev, 0, AP.MODE_STABILIZE, AP.RSN_INITIALISED)


@inline_jit
def _physics_tick(state, cfg, pwm, throttle, t_us):
    """One 1200 Hz physics step at t_us: the motors driven by pwm (the autopilot's PWM as the
    engine fault alters it, :func:`_motor_pwm`; throttle: their mean output), the rigid body,
    the IMU sampling it; returns the new time [us]."""
    physics_step(state.x, pwm, cfg.frame, PHYSICS_DT_US * 1e-6, t_us * 1e-6, state.wind_rng)
    t_us += PHYSICS_DT_US
    imu_sample(state.s, state.x, cfg.scfg, float(t_us), throttle, pwm, state.rng)
    return t_us


@inline_jit
def _read_sensors(state, scfg, work, t_us, ev):
    """The main loop's sensor reads at t_us: IMU deltas into work (its W_IMU_OK row: [i] IMU
    i's accel delivered samples, [N_IMU + i] its gyro did), the GPS epoch into the W_GPS row
    when one is due, baro and compass at 10 Hz (ERR 18 when the primary baro's health changes,
    ERR 3 when the first compass's does; ev: the event buffers and counts), the power module
    (the RC receiver follows: run_flight's rc_update). Returns (GPS, primary baro, compass
    tick) new this tick."""
    s, x, rng = state.s, state.x, state.rng
    imu_ok, gps = work.rows[W_IMU_OK], work.rows[W_GPS]
    power_module_read(s, x)
    for i in range(S.N_IMU):
        imu_ok[i] = imu_take_deltas(s, i, LOOP_DT_US * 1e-6, work.dang, work.dvel)
        imu_ok[S.N_IMU + i] = s[S.IMU_BASE + i * S.IMU_STRIDE + S.I_GYR_OK]
    gps_push_truth(s, x, t_us * 1e-6)
    gps_new = False
    if gps_due(s, float(t_us)):
        gps_measure(s, scfg, float(t_us), gps, rng[S.RNG_GPS])
        gps_new = True
    baro_new = False
    if t_us >= s[S.B_NEXT_US]:
        s[S.B_NEXT_US] += BARO_PERIOD_US
        baro_new, err = baro_read(s, x, scfg, rng, float(t_us))
        if err >= 0:
            log_err(ev, t_us, AP.ERR_BARO, err)
    mag_new = False
    if t_us >= s[S.M_NEXT_US]:
        s[S.M_NEXT_US] += MAG_PERIOD_US
        dh = mag_sample(s, x, scfg, rng[S.RNG_MAG], float(t_us))
        if dh != 0:
            log_err(ev, t_us, AP.ERR_COMPASS,
                    AP.ERR_CODE_RESOLVED if dh > 0 else AP.ERR_CODE_UNHEALTHY)
        mag_new = True
    return gps_new, baro_new, mag_new


@inline_jit
def _ekf_inputs(state, work, now):
    """This tick's :class:`~tlm_sim.bundles.EkfInputs` (now: the
    :class:`~tlm_sim.bundles.LoopTick`): the IMU deltas and health and the GPS epoch of work,
    the primary baro's altitude and the compass block of the sensor state, whether armed. The
    DCM estimator, the EKF and its yaw estimators all take them."""
    s, gps = state.s, work.rows[W_GPS]
    return EkfInputs(
        work.dang, work.dvel, work.rows[W_IMU_OK],
        now.gps_new, gps[S.GE_PN:S.GE_PN + 3], gps[S.GE_VN:S.GE_VN + 3], gps[S.GE_FIX_3D] > 0.5,
        now.baro_new, s[S.B_ALT], now.mag_new,
        s[S.MAG_BASE:S.MAG_BASE + S.N_MAG * S.MAG_STRIDE], state.c[C.ARMED] != 0.0,
    )


@inline_jit
def _estimate(state, ecfg, work, now, inputs, ev):
    """The EKF's main-loop update with this tick's sensor data (now: the
    :class:`~tlm_sim.bundles.LoopTick`; inputs: its :func:`_ekf_inputs`), its lanes' yaw
    estimators (:mod:`tlm_sim.ekf.gsf`), the per-tick part of its output block work.eo filled
    (ekf.layout O_*, :func:`ekf_output_nav`) and a primary-lane change logged into the event
    buffers ev (events, counts)."""
    ekf, sel, gsf, gps = state.ekf, state.sel, state.gsf, work.rows[W_GPS]
    t_us = now.t_us
    if now.gps_new and gps[S.GE_FIX_3D] > 0.5:
        ekf_gps_accuracy(ekf, ecfg, float(t_us), gps)
        ekf_gps_checks(ekf, ecfg, float(t_us), gps)
    switched = ekf_update(ekf, sel, ecfg, float(t_us), inputs)
    gsf_update(gsf, ekf, ecfg, inputs)
    ekf_output_nav(ekf, sel, work.eo)
    if switched:
        log_lane_switch(ev, t_us, work.eo)


@inline_jit
def _log_tick(logs, state, cfg, plan, work, now, last_gps_ms):
    """The main loop's logging at now (:class:`~tlm_sim.bundles.LoopTick`): the on-event
    messages (ORGN once home is set from the EKF's origin, ARM, LDET, MISE), GPS/GPA per epoch,
    SIM2 at 50 Hz, IMU at 25 Hz, each subsystem's 10 Hz messages. Returns the last GPS epoch's
    ms of week."""
    counts = logs.counts
    x, s, ekf, sel, c = state.x, state.s, state.ekf, state.sel, state.c
    scfg, ecfg, g, home = cfg.scfg, cfg.ecfg, cfg.g, plan.home
    eo, pos, gps = work.eo, work.rows[W_POS], work.rows[W_GPS]
    t_us, tick = now.t_us, now.tick
    origin_ready = counts[L.K_ORGN] == 0 and c[C.HOME_SET] != 0.0
    if vehicle_events_due(c, origin_ready):
        log_vehicle_events(logs, t_us, c, pos, origin_ready, home)
    if tick % SIM2_TICKS == 0:  # SIM2 at 50 Hz (LOG_FILE_RATEMAX)
        log_sim2(logs, t_us, x)
    if now.gps_new:
        last_gps_ms = log_gps(logs, t_us, gps, scfg, home, plan.gps_time, last_gps_ms)
    if tick % IMU_LOG_TICKS == 0:  # IMU at 25 Hz, both instances
        log_imu(logs, t_us, s, scfg)
    if tick % TEN_HZ_LOG_TICKS == 0:  # 10 Hz messages
        ekf_output(ekf, sel, eo)  # all of the output block (the per-tick part is fresh)
        log_sensors_10hz(logs, t_us, s, home[2])
        log_ekf_10hz(logs, t_us, ekf, sel, eo, home)
        log_ekf_evidence(logs, t_us, ekf, sel, ecfg)
        log_control_10hz(logs, t_us, c, eo, s, pos)
        log_dynamics_10hz(logs, t_us, x, home)
        log_dcm_10hz(logs, t_us, state.dcm, g, (s, gps), eo, home)
        log_gsf(logs, t_us, state.gsf)
    return last_gps_ms


# ------------------------------------------------------------------------- Python entry point


def new_work() -> LoopWork:
    """Scratch arrays of run_flight: IMU delta angles and velocities (N_IMU, 3); a
    (N_WORK_ROWS, WORK_COLS) block whose rows are :data:`WORK`'s (imu_ok, the GPS epoch,
    motor PWM, and the controllers' inputs of control.ahrs); the EKF output block
    (ekf.layout O_*)."""
    return LoopWork(np.zeros((S.N_IMU, 3)), np.zeros((S.N_IMU, 3)),
                    np.zeros((N_WORK_ROWS, WORK_COLS)), np.zeros(EK.N_OUT))


def _configs(p: Params, pilot: bool = False) -> VehicleConfig:
    """The configuration arrays (frame, sensors, EKF, autopilot) of a parameter set; pilot:
    the flight is flown from RC input (the autopilot's G_PILOT)."""
    g = build_control_config(p)
    g[C.G_PILOT] = 1.0 if pilot else 0.0
    return VehicleConfig(build_frame(p), build_sensor_config(p), build_ekf_config(p), g)


def _as_change(ch: Any) -> tuple[int, float, str, float]:
    """(trigger kind, at, name, value) of a ParamChange or a (time_s, name, value) tuple."""
    if hasattr(ch, "kind"):
        kind = TRIG_WP if ch.kind == "wp" else TRIG_TIME
        return kind, float(ch.at), str(ch.name), float(ch.value)
    t_s, name, value = ch
    return TRIG_TIME, float(t_s), str(name), float(value)


#: parameters read once at boot (ArduPilot needs a reboot): a scheduled change is refused
BOOT_ONLY_PARAMS: frozenset[str] = frozenset({"FRAME_CLASS", "FRAME_TYPE"})


def build_schedule(
    params: Params,
    changes: Sequence[Any],
    base: VehicleConfig | None = None,
    pilot: bool = False,
) -> np.ndarray:
    """Rows (at, kind, target, index, value, change) realising scheduled parameter changes.

    ``changes``: ``(time_s, NAME, value)`` tuples or ``tlm_sim.faults.ParamChange`` items
    (``kind`` "time" or "wp"). Changes are applied to the parameter set one after another:
    by time when all are timed, else in the order given (a fault schedule's sequence order);
    every configuration entry that differs from the previous configuration becomes a row (a
    change that alters none gets one TGT_NONE row, so its time is still recorded), so any
    parameter the subsystems read can change in flight, exactly as in SITL. Column ``change``
    is the change's position in ``changes``. ``base``: the configuration arrays of ``params``
    when the caller already built them; ``pilot``: the flight is flown from RC input.
    """
    items = [_as_change(ch) for ch in changes]
    order = list(range(len(items)))
    if all(it[0] == TRIG_TIME for it in items):
        order.sort(key=lambda i: items[i][1])
    rows: list[tuple[float, int, int, int, float, int]] = []
    current = params
    before = base if base is not None else _configs(current, pilot)
    for pos, i in enumerate(order):
        kind, at, name, value = items[i]
        if not math.isfinite(at) or at < 0:
            raise ValueError(f"parameter change time must be a finite time >= 0 s, got {at}")
        if name in BOOT_ONLY_PARAMS and value != current[name]:
            raise ValueError(f"{name} cannot change in flight: ArduPilot reads it at boot "
                             f"(the frame is built once); set it in the flight's parameters")
        # changes at one trigger are one step: the set must agree with itself after the last
        in_step = pos + 1 < len(order) and items[order[pos + 1]][:2] == (kind, at)
        current = (current.updated_in_step({name: value}) if in_step
                   else current.updated({name: value}))
        after = _configs(current, pilot)
        trigger = round(at * 1e6) if kind == TRIG_TIME else at
        n_before = len(rows)
        for tgt, (a, b) in enumerate(zip(before, after, strict=True)):
            for idx in np.flatnonzero(a != b):
                rows.append((trigger, kind, tgt, int(idx), float(b[idx]), i))
        if len(rows) == n_before:
            rows.append((trigger, kind, TGT_NONE, 0, 0.0, i))
        before = after
    if not rows:
        return np.zeros((0, N_SCH))
    return np.array(rows, dtype=np.float64)


def mission_path(mission: Mission, g: np.ndarray) -> np.ndarray:
    """The mission as NED points (the takeoff point above home, then the waypoints) with its
    items (control.wpnav P_SPEED, P_STOP, P_HOLD, P_CMD, P_CNUM: set speeds, stops, hold times,
    commands and item numbers) and the per-leg data of control.wpnav.prepare_path for the
    controller configuration g. A final NAV_LAND's point is at the altitude the copter comes
    from (ModeAuto::do_land flies to the landing point at its current altitude)."""
    ned = mission.ned()
    path = np.zeros((ned.shape[0] + 1, PATH_COLS))
    path[0, :3] = (0.0, 0.0, -mission.takeoff_alt)
    path[1:, :3] = ned
    path[0, P_CMD], path[0, P_CNUM] = AP.MAV_CMD_NAV_TAKEOFF, CMD_TAKEOFF
    path[1:, P_CMD] = mission.nav_commands
    path[1:, P_CNUM] = mission.item_numbers()
    path[1:, P_HOLD] = mission.holds
    path[1:, P_STOP] = mission.stops()
    speeds = mission.leg_speeds()
    path[1:, P_SPEED] = np.where(np.isnan(speeds), 0.0, speeds)
    if mission.lands:
        path[-1, 2] = path[-2, 2]
    prepare_path(path, path.shape[0], g)
    return path


def new_control_state(g: np.ndarray, mission: Mission, path: np.ndarray) -> np.ndarray:
    """The autopilot's state ``c`` at power-on for the controller configuration g: hover
    throttle MOT_THST_HOVER, the mission's takeoff altitude, not disarmed yet, AUTO's first
    waypoint (item number) of the mission path (:func:`mission_path`) once the takeoff is
    done."""
    c = np.zeros(C.N_CONTROL_STATE)
    c[C.THR_HOVER] = g[C.G_MOT_HOVER]
    c[C.TAKEOFF_ALT] = mission.takeoff_alt
    c[C.DISARM_TIME] = -1.0
    c[C.NAV_CNUM] = path[1, P_CNUM]
    return c


def max_duration_s(mission: Mission, params: Params) -> float:
    """Upper bound on a flight's simulated time (sizes the log buffers; the flight ends at
    disarm + 2 s long before): the arming (TLM_ARM_TIME, or the reference logs' ~42 s with the
    boot phase), slow cruise along the path (slower where a speed change sets less than
    3 m/s), the hold times, return, landing, margins."""
    arm_s = BOOT_ARM_S if params["TLM_BOOT_PHASE"] else params["TLM_ARM_TIME"]
    total = float(arm_s + 120.0 + 2.5 * mission.path_length_3d_m / 3.0 + 600.0)
    if mission.has_items:
        legs = np.linalg.norm(np.diff(mission.ned(), axis=0), axis=1)
        v = mission.leg_speeds()[1:]
        slow = ~np.isnan(v) & (v < 3.0)
        total += float(np.sum(mission.holds)) + float(
            2.5 * np.sum(legs[slow] * (1.0 / v[slow] - 1.0 / 3.0)))
    return total


def end_reason(disarm_time_s: float, err_rows: np.ndarray, armed: bool = True) -> str:
    """Why a flight ended (one of :data:`END_REASONS`).

    ``disarm_time_s``: the control state's disarm time [s] (< 0: never disarmed, so the loop ran
    to the time cap); ``err_rows``: the flight's ERR rows (TimeUS, Subsys, ECode); ``armed``:
    whether it ever armed."""
    if not armed:
        return END_NOT_ARMED
    if disarm_time_s < 0.0:
        return END_TIME_CAP
    return END_CRASH if bool(np.any(err_rows[:, 1] == AP.ERR_CRASH_CHECK)) else END_LANDED


def _checked_mission(mission: Mission | int, seed: int) -> Mission:
    """The Mission to fly (a built-in one for 1-4); TypeError / ValueError for a bad mission
    or seed."""
    if isinstance(mission, bool) or not isinstance(mission, Mission | int | np.integer):
        raise TypeError(f"mission must be a Mission or a built-in number 1-4, got {mission!r}")
    if not isinstance(mission, Mission):
        mission = builtin_mission(int(mission))
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    return mission


def _with_frame(params: Params | Mapping[str, float] | None,
                frame: str | None) -> Params | Mapping[str, float] | None:
    """``params`` with FRAME_CLASS / FRAME_TYPE of the frame named ``frame`` (see :func:`fly`)."""
    if frame is None:
        return params
    if frame not in FRAMES:
        raise ValueError(f"unknown frame {frame!r}; tlm has: {', '.join(FRAMES)}")
    f = FRAMES[frame]
    want = {"FRAME_CLASS": float(f.frame_class), "FRAME_TYPE": float(f.frame_type)}
    given = params if params is not None else {}
    explicit = given.changed() if isinstance(given, Params) else given
    clash = [k for k, v in want.items() if k in explicit and float(explicit[k]) != v]
    if clash:
        raise ValueError(f"frame {frame!r} is FRAME_CLASS {f.frame_class} / FRAME_TYPE "
                         f"{f.frame_type}, but params set {clash[0]} = {explicit[clash[0]]:g}")
    if isinstance(given, Params):
        return given.updated(want)
    return {**given, **want}


def fly(
    mission: Mission | int | None,
    faults: FaultSchedule | Sequence[Any] | None = None,
    params: Params | Mapping[str, float] | None = None,
    seed: int = 0,
    profile: str = "current",
    frame: str | None = None,
    sticks: StickScript | np.ndarray | None = None,
    gcs_modes: Sequence[tuple[float, str | int]] | None = None,
) -> FlightLog:
    """Fly one mission, or a pilot's sticks, and return its FlightLog.

    Args:
        mission: a Mission, or 1-4 for a built-in one. With ``sticks`` it gives only the home
            (its waypoints are neither flown nor logged); None there: SITL's home.
        faults: a :class:`tlm_sim.faults.FaultSchedule` (recorded as Eq. 4 fault records in
            ``FlightLog.faults``), or raw SITL parameter changes ``(time_s, name, value)``, e.g.
            ``[(120, "SIM_GPS1_ENABLE", 0), (150, "SIM_GPS1_ENABLE", 1)]``; None for none.
        params: parameter overrides (ArduPilot names) on top of tlm's defaults (the reference
            SITL logs' parameter set) and of the profile.
        seed: random seed of all noise draws; a flight is a pure function of its arguments.
        profile: "current" (ArduPilot as in the reference logs) or "paper" (the paper's
            ArduPilot 4.1/4.2 semantics), see :mod:`tlm_sim.profiles`.
        frame: a frame of :data:`tlm_sim.frames.FRAMES` (``"+"``, ``"x"``, ``"hexa"``,
            ``"hexax"``, ``"octa"``): sets FRAME_CLASS / FRAME_TYPE (a ValueError when
            ``params`` sets them to another frame); None: the frame of ``params``.
        sticks: fly a pilot's transmitter instead (docs/pilot.md): a
            :class:`tlm_sim.mission.sticks.StickScript` or rows (time since boot [s],
            channels 1..8 [us]), e.g. a log's RCIN. It ends 2 s after the disarm, or
            :data:`PILOT_TAIL_S` after the last row.
        gcs_modes: with ``sticks``, the ground station's mode changes (MAVLink): ``(time
            since boot [s], mode name or number)``, besides a script's ``gcs_mode`` rows.
    """
    params = _with_frame(params, frame)
    mission = _flown_mission(mission, seed, sticks is not None)
    from tlm_sim.precompile import ensure_compiled  # not at import: `python -m` runs it
    p, earth = with_home_field(profile_params(profile, params), mission.home, BOOT_UTC)
    duration, rc_table = _flight_span(mission, p, sticks)
    schedule = faults if isinstance(faults, FaultSchedule) else None
    if schedule is not None:
        schedule.validate(n_waypoints=mission.n_waypoints, max_time_s=duration)
        if sticks is not None:
            schedule.require_times()
        changes: list[Any] = list(schedule.param_changes(p))
    else:
        changes = list(faults or ())
        _check_changes(p, changes)  # a bad change fails before any compiling
    ensure_compiled()  # a cold numba cache is compiled by several processes at once
    cfg = _configs(p, pilot=sticks is not None)
    frame, g = cfg.frame, cfg.g
    sched = build_schedule(p, changes, cfg, pilot=sticks is not None)
    applied = np.full(len(changes), -1.0)
    home = np.array(mission.home, dtype=np.float64)
    x = np.zeros(X.N_STATE)
    init_state(x, frame, math.radians(p["SIM_OPOS_HDG"]))
    ekf, sel = new_ekf(p)
    path = mission_path(mission, g)
    c = new_control_state(g, mission, path)
    seg = np.zeros((2, PATH_COLS))
    bufs = allocate_buffers(duration, LOGGED_MESSAGES, rows=evidence_rows(mission, duration))
    txt = np.zeros((AP.TXT_ROWS, AP.N_TXT_COLS))
    buf_tuple = tuple(bufs[n] for n in L.LOG_ORDER)
    counts = np.zeros(len(L.LOG_ORDER), dtype=np.int64)
    week, ms = gps_week_ms(BOOT_UTC)
    state = VehicleState(x, np.zeros(S.N_SENSOR_STATE), ekf, sel, c, np.zeros(N_DCM),
                         np.zeros((ekf.shape[0], N_GSF)),
                         new_streams(int(seed), S.N_NOISE_STREAMS), new_rng(int(seed), 2))
    plan = FlightPlan(path, seg, sched, applied, home, np.array([week, ms], dtype=np.float64),
                      rc_table, gcs_table(sticks, gcs_modes))
    t_final = run_flight(state, cfg, plan,
                         FlightLogs(buf_tuple, counts, txt), new_work(), int(duration * 1e6))
    armed = c[C.ARM_TIME_S] >= 0.0
    meta: dict[str, Any] = {
        "seed": int(seed),
        "profile": profile,
        "duration_s": t_final * 1e-6,
        **_flown_meta(c, mission, sticks is not None),
        "end_reason": end_reason(float(c[C.DISARM_TIME]),
                                 bufs["ERR"][:int(counts[L.K_ERR])], armed),
        "boot_phase": bool(p["TLM_BOOT_PHASE"]),
        "texts": txt[:int(c[C.TXT_N])].tolist(),
        "max_duration_s": duration,
        "param_changes": [_change_record(ch, t) for ch, t in zip(changes, applied, strict=True)],
        "unmodelled_params": p.unmodelled(),
        "frame": frame_for(p["FRAME_CLASS"], p["FRAME_TYPE"]).name,
        "earth_field": earth.as_meta(),
    }
    fill_evidence(bufs, counts, mission, p)
    log = FlightLog.from_buffers(
        {n: bufs[n] for n in L.LOG_ORDER},
        {n: int(counts[i]) for i, n in enumerate(L.LOG_ORDER)},
        params=p, mission=mission if sticks is None else None, faults=[], meta=meta,
    )
    _jitter_sats(log, int(seed), p["TLM_SAT_JITTER"])
    if schedule is not None:
        t_last = max((float(log.columns(n)["TimeUS"][-1]) for n in log.tables
                      if log.n_rows(n)), default=0.0)
        log.faults = fault_records(schedule, changes, applied, log.tables, float(home[2]),
                                   t_last)
    return log


#: a pilot-flown flight runs at most this long after its RC table's last row [s]
PILOT_TAIL_S = 30.0


def _flown_mission(mission: Mission | int | None, seed: int, pilot: bool) -> Mission:
    """The Mission to fly (:func:`_checked_mission`); a pilot-flown flight's placeholder at
    its home (SITL's when ``mission`` is None)."""
    if pilot:
        home = HOME_CMAC if mission is None else _checked_mission(mission, seed).home
        return _checked_mission(pilot_home_mission(home), seed)
    return _checked_mission(mission, seed)


def _flight_span(mission: Mission, p: Params,
                 sticks: StickScript | np.ndarray | None) -> tuple[float, np.ndarray]:
    """The longest the flight can last [s] and its RC table (no rows without sticks)."""
    if sticks is None:
        return max_duration_s(mission, p), np.zeros((0, RC_COLS))
    rc = rc_table_us(sticks, p)
    return float(rc[-1, 0]) * 1e-6 + PILOT_TAIL_S, rc


def _flown_meta(c: np.ndarray, mission: Mission, pilot: bool) -> dict[str, Any]:
    """What the flight did, for FlightLog.meta: the mission (``pilot``: flown from sticks),
    home, arming and disarming times, final mode, waypoints, whether it landed."""
    armed = c[C.ARM_TIME_S] >= 0.0
    return {
        "mission": "pilot" if pilot else mission.name,
        "home": list(mission.home),
        "armed_s": float(c[C.ARM_TIME_S]) if armed else None,
        "disarmed_s": float(c[C.DISARM_TIME]) if c[C.DISARM_TIME] >= 0 else None,
        "final_mode": int(c[C.MODE]),
        "waypoints_reached": int(c[C.WP_REACHED]),
        "n_waypoints": 0 if pilot else int(mission.n_waypoints),
        "landed": bool(c[C.SUBMODE] == C.SUB_LANDED),
    }


def pilot_home_mission(home: Sequence[float]) -> Mission:
    """The placeholder mission of a pilot-flown flight: only its home counts (one waypoint 10 m
    above it, never flown)."""
    lat, lon, _ = home
    return Mission(np.array([[lat, lon, 10.0]]), home=tuple(home), name="pilot")


def rc_table_us(sticks: StickScript | np.ndarray, params: Params) -> np.ndarray:
    """The loop's RC table (FlightPlan.rc: time [us], channels 1..8 [us]) of a stick script
    (rendered at 50 Hz to its last row's time plus its ramp and 60 s) or of rows (time [s],
    channels 1..8); ValueError for rows that are not that."""
    if isinstance(sticks, StickScript):
        t_end = max(float(r["t"]) + float(r.get("ramp", 0.0)) for r in sticks.rows) + 60.0
        rows = sticks.table(params, t_end)
    else:
        rows = np.asarray(sticks, dtype=np.float64)
        if rows.ndim != 2 or rows.shape[1] != RC_COLS or rows.shape[0] == 0:
            raise ValueError(f"an RC table is rows of (t_s, C1..C8), {RC_COLS} columns; got "
                             f"shape {rows.shape}")
        if not np.all(np.isfinite(rows)) or np.any(np.diff(rows[:, 0]) < 0.0):
            raise ValueError("an RC table's values must be finite and its times in order")
    out = rows.copy()
    out[:, 0] = np.round(rows[:, 0] * 1e6)
    return np.ascontiguousarray(out)


def gcs_table(sticks: StickScript | np.ndarray | None,
              gcs_modes: Sequence[tuple[float, str | int]] | None) -> np.ndarray:
    """The loop's table of ground-station mode requests (FlightPlan.gcs: time [us], mode
    number, in time order): a script's ``gcs_mode`` rows and ``gcs_modes``; ValueError for a
    request without sticks, an unknown mode or a bad time."""
    rows: list[tuple[float, float]] = []
    if isinstance(sticks, StickScript):
        rows += [(float(t), float(m)) for t, m in sticks.gcs_modes()]
    if gcs_modes:
        if sticks is None:
            raise ValueError("gcs_modes are mode changes of a pilot-flown flight: give sticks")
        names = {v: k for k, v in AP.MODE_NAMES.items()}
        for t, m in gcs_modes:
            num = names.get(str(m).strip().upper()) if isinstance(m, str) else int(m)
            if num is None or num not in AP.MODE_NAMES:
                raise ValueError(f"gcs_modes: unknown flight mode {m!r}")
            if not (math.isfinite(float(t)) and float(t) >= 0.0):
                raise ValueError(f"gcs_modes: time must be >= 0 s, got {t!r}")
            rows.append((float(t), float(num)))
    out = np.array(sorted(rows, key=lambda r: r[0]), dtype=np.float64).reshape(-1, 2)
    out[:, 0] = np.round(out[:, 0] * 1e6)
    return np.ascontiguousarray(out)


def _jitter_sats(log: FlightLog, seed: int, mu: float) -> None:
    """GPS.NSats jittered by the seed's satellite-count stream (TLM_SAT_JITTER ``mu`` > 0)."""
    if mu > 0.0 and log.n_rows("GPS"):
        gps = log.tables["GPS"]
        gps["NSats"] = jitter_nsats(gps["Status"].to_numpy(), seed, mu).astype(
            gps["NSats"].dtype)


#: LDET rows per second at most (Copter::Log_LDET logs a change at most every 20 ms)
LDET_MAX_HZ = 50.0


def evidence_rows(mission: Mission, duration_s: float) -> dict[str, int]:
    """Buffer rows of the on-event messages with a bound of their own: LDET at its 50 Hz cap,
    MISE one per mission item (tlm_sim.flightlog.allocate_buffers ``rows``)."""
    return {"LDET": int(LDET_MAX_HZ * duration_s) + 16,
            "MISE": len(mission_items(mission)) + 16}


def fill_evidence(bufs: Mapping[str, np.ndarray], counts: np.ndarray, mission: Mission,
                  params: Params) -> None:
    """Complete the on-event rows the loop logged with what the flight's inputs hold: each
    MISE row's mission item (:func:`mission_items`, the CMD rows' fields), ARM.ArmChecks of an
    arming (ARMING_CHECK) and SIM2.ASpdU (SIM_SPEEDUP: SITL's achieved wall-clock speed-up;
    tlm's time is simulated only)."""
    n = int(counts[L.K_MISE])
    if n:
        items = mission_items(mission)
        mise = bufs["MISE"]
        idx = np.clip(mise[:n, L.MISE_COLS.CNum].astype(np.int64), 0, len(items) - 1)
        mise[:n, 1:] = items[idx]
    n = int(counts[L.K_ARM])
    arm = bufs["ARM"][:n]
    arm[arm[:, L.ARM_COLS.ArmState] != 0.0, L.ARM_COLS.ArmChecks] = float(
        params.get("ARMING_CHECK", 1.0))
    bufs["SIM2"][:int(counts[L.K_SIM2]), L.SIM2_COLS.ASpdU] = float(
        params.get("SIM_SPEEDUP", 1.0))


def mission_items(mission: Mission) -> np.ndarray:
    """The mission as ArduCopter stores it (:meth:`tlm_sim.mission.Mission.items`: home,
    NAV_TAKEOFF, the waypoints' items, NAV_RETURN_TO_LAUNCH unless it lands), one row per
    item in CMD / MISE column order without TimeUS (CTot, CNum, CId, Prm1-4, Lat, Lng, Alt,
    Frame)."""
    items = mission.items()
    n = len(items)
    out = np.zeros((n, len(L.MISE_COLS) - 1))
    k = {name: i - 1 for i, name in enumerate(L.MISE_COLS._fields)}
    out[:, k["CTot"]] = n
    out[:, k["CNum"]] = np.arange(n)
    for j, name in enumerate(ITEM_FIELDS):
        out[:, k[name]] = items[:, j]
    return out


def _check_changes(params: Params, changes: Sequence[Any]) -> None:
    """Validate raw ``(time_s, NAME, value)`` changes as :func:`build_schedule` applies them
    (names, values, parameters tlm models), without building configurations."""
    current = params
    for ch in changes:
        _, _, name, value = _as_change(ch)
        current = current.updated({name: value})


def _change_record(ch: Any, applied_us: float) -> dict[str, Any]:
    """One scheduled parameter change and the log time it took effect (None if never)."""
    kind, at, name, value = _as_change(ch)
    rec: dict[str, Any] = {"name": name, "value": value,
                           "at": f"wp{int(at)}" if kind == TRIG_WP else at,
                           "time_us": int(applied_us) if applied_us >= 0 else None}
    if hasattr(ch, "fault"):
        rec["fault"], rec["edge"] = int(ch.fault), ch.edge
    return rec
