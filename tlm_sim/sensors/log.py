"""The sensors' log messages: GPS, GPA (per GPS epoch), IMU (25 Hz), VIBE, BARO, MAG, RCIN
(10 Hz). Columns by name (:mod:`tlm_sim.logger`), values in the tables' units."""

import math

from tlm_sim import logger as L
from tlm_sim._jit import inline_jit, tick_jit
from tlm_sim.geo import ne_to_latlon_scalar
from tlm_sim.sensors import layout as S
from tlm_sim.sensors.imu import vibe

GPS, GPA, IMU = L.GPS_COLS, L.GPA_COLS, L.IMU_COLS
VIBE, BARO, MAG, RCIN = L.VIBE_COLS, L.BARO_COLS, L.MAG_COLS, L.RCIN_COLS


@tick_jit
def log_gps(log, t_us, gps, scfg, home, gps_time, last_ms):
    """GPS and GPA rows for one GPS epoch gps (layout GE_*); home in degrees and m AMSL;
    gps_time: (week, ms of week at boot). Returns the epoch's ms of week."""
    bufs = log[0]  # the log buffers
    home_lat, home_lon, home_alt = home[0], home[1], home[2]  # deg, deg, m AMSL
    r = L.new_row(log, L.K_GPS, t_us)
    ms = gps_time[1] + round(t_us / 200000.0) * 200.0
    week = gps_time[0] + math.floor(ms / 604800000.0)
    ms = ms % 604800000.0
    if r >= 0:
        b = bufs[L.K_GPS]
        lat, lon = ne_to_latlon_scalar(gps[S.GE_PN], gps[S.GE_PE], home_lat, home_lon)
        b[r, GPS.I] = 0.0
        b[r, GPS.Status] = gps[S.GE_STATUS]
        b[r, GPS.GMS] = ms
        b[r, GPS.GWk] = week
        b[r, GPS.NSats] = gps[S.GE_NSATS]
        b[r, GPS.HDop] = scfg[S.C_GPS_HDOP]
        b[r, GPS.Lat] = lat
        b[r, GPS.Lng] = lon
        b[r, GPS.Alt] = home_alt - gps[S.GE_PD]
        b[r, GPS.Spd] = math.sqrt(gps[S.GE_VN] * gps[S.GE_VN] + gps[S.GE_VE] * gps[S.GE_VE])
        crs = math.degrees(math.atan2(gps[S.GE_VE], gps[S.GE_VN]))
        b[r, GPS.GCrs] = crs + 360.0 if crs < 0.0 else crs
        b[r, GPS.VZ] = gps[S.GE_VD]
        b[r, GPS.Yaw] = 0.0
        b[r, GPS.U] = 1.0
    _log_gpa(log, t_us, gps, scfg, ms, last_ms)
    return ms


@inline_jit
def _log_gpa(log, t_us, gps, scfg, ms, last_ms):
    """The GPA row of a GPS epoch gps at ms of week (last_ms: the previous epoch's, 0 for
    none): the accuracies the receiver reports."""
    bufs = log[0]  # the log buffers
    r = L.new_row(log, L.K_GPA, t_us)
    if r >= 0:
        b = bufs[L.K_GPA]
        b[r, GPA.I] = 0.0
        b[r, GPA.VDop] = scfg[S.C_GPS_VDOP]
        b[r, GPA.HAcc] = gps[S.GE_HACC]
        b[r, GPA.VAcc] = gps[S.GE_VACC]
        b[r, GPA.SAcc] = gps[S.GE_SACC]
        b[r, GPA.YAcc] = 0.0
        b[r, GPA.VV] = 1.0
        b[r, GPA.SMS] = t_us // 1000
        b[r, GPA.Delta] = (ms - last_ms) if last_ms > 0.0 else 0.0


@tick_jit
def log_imu(log, t_us, s, scfg):
    """IMU rows (one per instance): filtered gyro/accel (held while the sensor is stopped),
    error counts, temperature, health (GH/AH: a sample in the last main-loop tick), rates."""
    bufs = log[0]  # the log buffers
    temp = 45.0 - 20.0 * math.exp(-t_us * 1e-6 / 300.0)
    for i in range(S.N_IMU):
        r = L.new_row(log, L.K_IMU, t_us)
        if r < 0:
            return
        b = bufs[L.K_IMU]
        ib = S.IMU_BASE + i * S.IMU_STRIDE
        b[r, IMU.I] = i
        for k in range(3):
            b[r, IMU.GyrX + k] = s[ib + S.I_GYR_F + k]
            b[r, IMU.AccX + k] = s[ib + S.I_ACC_F + k]
        b[r, IMU.EG] = s[ib + S.I_EG]
        b[r, IMU.EA] = s[ib + S.I_EA]
        b[r, IMU.T] = temp
        b[r, IMU.GH] = s[ib + S.I_GYR_OK]
        b[r, IMU.AH] = s[ib + S.I_ACC_OK]
        b[r, IMU.GHz] = round(1e6 / scfg[S.C_GYR_PERIOD_US + i])
        b[r, IMU.AHz] = round(1e6 / scfg[S.C_ACC_PERIOD_US + i])


@tick_jit
def log_sensors_10hz(log, t_us, s, home_alt):
    """The sensors' 10 Hz rows: VIBE (per IMU), BARO (two instances), MAG (three), RCIN."""
    bufs = log[0]  # the log buffers
    for i in range(S.N_IMU):
        r = L.new_row(log, L.K_VIBE, t_us)
        if r >= 0:
            b = bufs[L.K_VIBE]
            b[r, VIBE.IMU] = i
            for k in range(3):
                b[r, VIBE.VibeX + k] = vibe(s, i, k)
            b[r, VIBE.Clip] = s[S.IMU_BASE + i * S.IMU_STRIDE + S.I_CLIP]
    for i in range(S.N_BARO):
        _log_baro(log, t_us, s, home_alt, i)
    for i in range(S.N_MAG):
        _log_mag(log, t_us, s, i)
    r = L.new_row(log, L.K_RCIN, t_us)
    if r >= 0:
        b = bufs[L.K_RCIN]
        for k in range(8):
            b[r, RCIN.C1 + k] = s[S.RC_CH + k]


@inline_jit
def _log_baro(log, t_us, s, home_alt, i):
    """One BARO row of instance i: its last sample (held while it delivers none), health."""
    bufs = log[0]  # the log buffers
    r = L.new_row(log, L.K_BARO, t_us)
    if r >= 0:
        b = bufs[L.K_BARO]
        sb = S.BARO_BASE + i * S.BARO_STRIDE
        alt = s[sb + S.BA_ALT]
        b[r, BARO.I] = i
        b[r, BARO.Alt] = alt
        b[r, BARO.AltAMSL] = s[S.B_FIELD_ELEV] + alt  # 0 + alt until the field elevation is set
        b[r, BARO.Press] = s[sb + S.BA_PRESS]
        b[r, BARO.Temp] = s[sb + S.BA_TEMP]
        b[r, BARO.CRt] = (alt - s[sb + S.BA_ALT_PREV]) * 10.0
        # the last sample's time: frozen while the instance delivers none
        b[r, BARO.SMS] = t_us // 1000 if s[sb + S.BA_HEALTHY] != 0.0 else s[sb + S.BA_T_MS]
        b[r, BARO.Offset] = 0.0
        b[r, BARO.GndTemp] = s[S.B_GND_TEMP]
        b[r, BARO.H] = s[sb + S.BA_HEALTHY]
        b[r, BARO.CPress] = s[sb + S.BA_PRESS]


@inline_jit
def _log_mag(log, t_us, s, i):
    """One MAG row (compass i): its reading [mGauss] (held while it delivers nothing), health,
    the time of its last sample [us]."""
    bufs = log[0]  # the log buffers
    r = L.new_row(log, L.K_MAG, t_us)
    if r >= 0:
        b = bufs[L.K_MAG]
        m = S.MAG_BASE + i * S.MAG_STRIDE
        b[r, MAG.I] = i
        for k in range(3):
            b[r, MAG.MagX + k] = round(s[m + S.M_FIELD + k] * 1000.0)
        b[r, MAG.Health] = s[m + S.M_HEALTHY]
        b[r, MAG.S] = s[m + S.M_T_US]
