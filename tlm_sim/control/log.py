"""The autopilot's 10 Hz log messages: RATE, ATT, RCOU, CTUN, PSCN/PSCE/PSCD and BAT (the battery
monitor, :mod:`tlm_sim.control.battery`), DCM and AHR2 (the DCM estimator,
:mod:`tlm_sim.control.dcm`). Columns by name (:mod:`tlm_sim.logger`); attitude and
heights from the EKF output block (``ekf.layout`` O_*)."""

import math

from tlm_sim import logger as L
from tlm_sim._jit import inline_jit, tick_jit
from tlm_sim.control import dcm_layout as DL
from tlm_sim.control import layout as C
from tlm_sim.control.battery import resting_voltage
from tlm_sim.control.dcm import dcm_eulers, dcm_location, dcm_quaternion
from tlm_sim.ekf import layout as EK
from tlm_sim.frames import MAX_MOTORS
from tlm_sim.geo import ne_to_latlon_scalar
from tlm_sim.sensors import layout as S

RATE, ATT, RCOU, CTUN, PSC = L.RATE_COLS, L.ATT_COLS, L.RCOU_COLS, L.CTUN_COLS, L.PSCN_COLS
BAT = L.BAT_COLS


@tick_jit
def log_control_10hz(bufs, counts, t_us, c, eo, s, pos, acc):
    """The autopilot's 10 Hz rows from its state c, the EKF output eo, the baro altitude in the
    sensor state s, its position estimate pos [m, NED] and the acceleration NED acc [m/s^2]."""
    _log_rate(bufs, counts, t_us, c)
    _log_att(bufs, counts, t_us, c, eo)
    r = L.new_row(bufs, counts, L.K_RCOU, t_us)
    if r >= 0:
        for k in range(MAX_MOTORS):  # outputs beyond the frame's motors read 0, as in SITL
            bufs[L.K_RCOU][r, RCOU.C1 + k] = round(c[C.MIX_PWM + k])
    _log_ctun(bufs, counts, t_us, c, eo, s, pos)
    for ax in range(3):
        _log_psc(bufs, counts, t_us, c, eo, pos, acc, ax)
    _log_bat(bufs, counts, t_us, c)


@inline_jit
def _log_bat(bufs, counts, t_us, c):
    """BAT: the battery monitor's voltage, resting voltage, current, consumed mAh and Wh,
    resistance estimate and remaining percentage."""
    r = L.new_row(bufs, counts, L.K_BAT, t_us)
    if r >= 0:
        b = bufs[L.K_BAT]
        b[r, BAT.Inst] = 0.0
        b[r, BAT.Volt] = c[C.BM_VOLT]
        b[r, BAT.VoltR] = resting_voltage(c)
        b[r, BAT.Curr] = c[C.BM_CURR]
        b[r, BAT.CurrTot] = c[C.BM_MAH]
        b[r, BAT.EnrgTot] = c[C.BM_WH]
        b[r, BAT.Temp] = 0.0
        b[r, BAT.Res] = c[C.BM_RES]
        b[r, BAT.RemPct] = c[C.BM_REMPCT]
        b[r, BAT.H] = 1.0
        b[r, BAT.SH] = 0.0


@inline_jit
def _log_rate(bufs, counts, t_us, c):
    """RATE: rate targets, measurements and outputs per axis [deg/s], vertical acceleration."""
    d = L.RAD2DEG
    r = L.new_row(bufs, counts, L.K_RATE, t_us)
    if r >= 0:
        b = bufs[L.K_RATE]
        for k in range(3):  # (RDes, R, ROut), (PDes, P, POut), (YDes, Y, YOut)
            rb = C.RATE_BASE + k * C.RATE_STRIDE
            b[r, RATE.RDes + 3 * k] = c[rb + C.R_TARGET] * d
            b[r, RATE.R + 3 * k] = c[rb + C.R_MEAS] * d
            b[r, RATE.ROut + 3 * k] = c[rb + C.R_OUT]
        b[r, RATE.ADes] = c[C.PZ_ACC_T] * 100.0
        b[r, RATE.A] = c[C.PZ_ACC_MEAS] * 100.0
        b[r, RATE.AOut] = c[C.THR_OUT_BOOSTED] if c[C.ARMED] != 0.0 else 0.0
        b[r, RATE.AOutSlew] = 0.0


@inline_jit
def _log_att(bufs, counts, t_us, c, eo):
    """ATT: attitude targets and the EKF's attitude [deg, yaw 0..360]."""
    d = L.RAD2DEG
    r = L.new_row(bufs, counts, L.K_ATT, t_us)
    if r >= 0:
        b = bufs[L.K_ATT]
        yaw = eo[EK.O_YAW] * d
        b[r, ATT.DesRoll] = c[C.ATT_ROLL_T] * d
        b[r, ATT.Roll] = eo[EK.O_ROLL] * d
        b[r, ATT.DesPitch] = c[C.ATT_PITCH_T] * d
        b[r, ATT.Pitch] = eo[EK.O_PITCH] * d
        yd = c[C.ATT_YAW_T] * d
        b[r, ATT.DesYaw] = yd + 360.0 if yd < 0.0 else yd
        b[r, ATT.Yaw] = yaw + 360.0 if yaw < 0.0 else yaw
        b[r, ATT.AEKF] = 3.0


@inline_jit
def _log_ctun(bufs, counts, t_us, c, eo, s, pos):
    """CTUN: throttle, altitude target and estimates (the position controller's: 0 while the
    EKF has no valid height), climb rates."""
    r = L.new_row(bufs, counts, L.K_CTUN, t_us)
    if r >= 0:
        b = bufs[L.K_CTUN]
        b[r, CTUN.ThI] = c[C.THR_OUT]
        b[r, CTUN.ABst] = c[C.THR_OUT_BOOSTED] - c[C.THR_OUT]
        b[r, CTUN.ThO] = c[C.THR_OUT_BOOSTED] if c[C.ARMED] != 0.0 else 0.0
        b[r, CTUN.ThH] = c[C.THR_HOVER]
        b[r, CTUN.DAlt] = -c[C.PZ_POS_T]
        b[r, CTUN.Alt] = -pos[2]
        b[r, CTUN.BAlt] = s[S.B_ALT]
        b[r, CTUN.DSAlt] = math.nan
        b[r, CTUN.SAlt] = 0.0
        b[r, CTUN.TAlt] = math.nan
        b[r, CTUN.DCRt] = round(-c[C.PZ_VEL_T] * 100.0)
        b[r, CTUN.CRt] = round(-eo[EK.O_VD] * 100.0)


@inline_jit
def _log_psc(bufs, counts, t_us, c, eo, pos, acc, ax):
    """PSCN (ax 0), PSCE (1) or PSCD (2): position, velocity and acceleration desired, target
    and actual. The three messages share one column order (PSC names PSCN's columns)."""
    kbuf = L.K_PSCN + ax
    r = L.new_row(bufs, counts, kbuf, t_us)
    if r < 0:
        return
    b = bufs[kbuf]
    if ax < 2:
        b[r, PSC.DPN] = c[C.PXY_POS_T + ax]
        b[r, PSC.TPN] = c[C.PXY_POS_T + ax]
        b[r, PSC.DVN] = c[C.PXY_VEL_FF + ax]
        b[r, PSC.TVN] = c[C.PXY_VEL_T + ax]
        b[r, PSC.DAN] = c[C.PXY_ACC_FF + ax]
        b[r, PSC.TAN] = c[C.PXY_ACC_T + ax]
    else:
        b[r, PSC.DPN] = c[C.PZ_POS_T]
        b[r, PSC.TPN] = c[C.PZ_POS_T]
        b[r, PSC.DVN] = c[C.PZ_VEL_T]
        b[r, PSC.TVN] = c[C.PZ_VEL_T]
        b[r, PSC.DAN] = -c[C.PZ_ACC_T]
        b[r, PSC.TAN] = -c[C.PZ_ACC_T]
    b[r, PSC.PN] = pos[ax]
    b[r, PSC.VN] = eo[EK.O_VN + ax]
    b[r, PSC.AN] = acc[ax]


DCMC, AHR2 = L.DCM_COLS, L.AHR2_COLS


@tick_jit
def log_dcm_10hz(bufs, counts, t_us, d, g, s, gps, eo, home_lat, home_lon, home_alt):
    """DCM (the estimator's state) and AHR2 (the AHRS's secondary solution: the DCM's, while the
    EKF is the active one) at 10 Hz from the DCM array d (:mod:`tlm_sim.control.dcm`); g: the
    controller configuration, s: sensor state (baro), gps: the latest GPS epoch, eo: the EKF
    output block, home: degrees, m AMSL. AHR2's angles are truncated to centidegrees as the
    firmware's integer casts do."""
    if d[DL.D_INIT] == 0.0:
        return
    dcm_eulers(d)
    rd = L.RAD2DEG
    yaw = (d[DL.D_YAW] * rd) % 360.0
    r = L.new_row(bufs, counts, L.K_DCM, t_us)
    if r >= 0:
        b = bufs[L.K_DCM]
        b[r, DCMC.Roll] = d[DL.D_ROLL] * rd
        b[r, DCMC.Pitch] = d[DL.D_PITCH] * rd
        b[r, DCMC.Yaw] = yaw
        b[r, DCMC.ErrRP] = d[DL.D_ERR_RP]
        b[r, DCMC.ErrYaw] = d[DL.D_ERR_YAW]
        b[r, DCMC.VWN] = 0.0
        b[r, DCMC.VWE] = 0.0
        b[r, DCMC.VWD] = 0.0
    if eo[EK.O_F_ATTITUDE] == 0.0:  # the DCM is the active solution: no secondary to log
        return
    r = L.new_row(bufs, counts, L.K_AHR2, t_us)
    if r >= 0:
        b = bufs[L.K_AHR2]
        have, north, east, alt = dcm_location(d, g, s, gps, t_us * 1e-6, home_alt)
        lat, lon = ne_to_latlon_scalar(north, east, home_lat, home_lon) if have else (0.0, 0.0)
        b[r, AHR2.Roll] = int(d[DL.D_ROLL] * rd * 100.0) * 0.01
        b[r, AHR2.Pitch] = int(d[DL.D_PITCH] * rd * 100.0) * 0.01
        b[r, AHR2.Yaw] = int(yaw * 100.0) * 0.01
        b[r, AHR2.Alt] = math.nan if not have and alt == 0.0 else alt
        b[r, AHR2.Lat] = lat
        b[r, AHR2.Lng] = lon
        qw, qx, qy, qz = dcm_quaternion(d)
        b[r, AHR2.Q1] = qw
        b[r, AHR2.Q2] = qx
        b[r, AHR2.Q3] = qy
        b[r, AHR2.Q4] = qz
