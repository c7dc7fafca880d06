"""The EKF's log messages: XKF1, XKF4 and XKFS per lane, POS from the output block (10 Hz),
XKY0 / XKY1 of the lanes' yaw estimators, and the ERR rows of a primary-lane change and of
ArduCopter's GPS glitch check. Columns by name
(:mod:`tlm_sim.logger`)."""

import math

from tlm_sim import logger as L
from tlm_sim._jit import inline_jit, tick_jit
from tlm_sim.ekf import gsf_layout as GL
from tlm_sim.ekf import layout as EK
from tlm_sim.ekf.gsf import gsf_refresh
from tlm_sim.geo import ne_to_latlon_scalar

XKF1, XKF4, XKFS, POS = L.XKF1_COLS, L.XKF4_COLS, L.XKFS_COLS, L.POS_COLS
ERR_EKF_PRIMARY = 24  # ERR subsystem of a primary-lane change (ECode: the new lane)
ERR_GPS = 11  # ERR subsystem GPS: ECode 2 GPS_GLITCH, 0 resolved
ERR_GPS_GLITCH = 2


@tick_jit
def log_lane_switch(events, ev_counts, t_us, eo):
    """ERR EKF_PRIMARY with the new primary lane (from the output block eo) into the event
    buffers (tlm_sim.logger E_*)."""
    r = L.new_row(events, ev_counts, L.E_ERR, t_us)
    if r >= 0:
        events[L.E_ERR][r, L.ERR_COLS.Subsys] = ERR_EKF_PRIMARY
        events[L.E_ERR][r, L.ERR_COLS.ECode] = eo[EK.O_PRIMARY]


@tick_jit
def gps_glitch_check(events, ev_counts, t_us, ekf, sel):
    """ArduCopter's gpsglitch_check (10 Hz): an edge of the primary lane's gps_glitching flag
    logs ERR GPS 2 ("GPS Glitch or Compass error") or 0 ("Glitch cleared"). No mode change:
    Copter has no GPS failsafe of its own."""
    g = ekf[int(sel[EK.SEL_PRIMARY]), EK.GPS_GLITCHING]
    if g == sel[EK.SEL_GPS_GLITCH]:
        return
    sel[EK.SEL_GPS_GLITCH] = g
    r = L.new_row(events, ev_counts, L.E_ERR, t_us)
    if r >= 0:
        events[L.E_ERR][r, L.ERR_COLS.Subsys] = ERR_GPS
        events[L.E_ERR][r, L.ERR_COLS.ECode] = ERR_GPS_GLITCH if g != 0.0 else 0


@tick_jit
def log_ekf_10hz(bufs, counts, t_us, ekf, sel, eo, home_lat, home_lon, home_alt):
    """The EKF's 10 Hz rows: XKF1, XKF4 and XKFS for every lane, POS of the output (home:
    degrees, m AMSL)."""
    for ln in range(int(sel[EK.SEL_N_LANES])):
        _log_lane(bufs, counts, t_us, ekf[ln], ln, sel[EK.SEL_PRIMARY], home_alt)
        _log_sources(bufs, counts, t_us, ekf[ln], ln)
    r = L.new_row(bufs, counts, L.K_POS, t_us)
    if r >= 0:
        b = bufs[L.K_POS]
        lat, lon = ne_to_latlon_scalar(eo[EK.O_PN], eo[EK.O_PE], home_lat, home_lon)
        b[r, POS.Lat] = lat
        b[r, POS.Lng] = lon
        b[r, POS.Alt] = home_alt - eo[EK.O_PD]
        b[r, POS.RelHomeAlt] = -eo[EK.O_PD]
        b[r, POS.RelOriginAlt] = -eo[EK.O_PD]


@inline_jit
def _log_lane(bufs, counts, t_us, el, ln, primary, home_alt):
    """XKF1 and XKF4 rows of lane ln (its row el of the ekf array)."""
    d = L.RAD2DEG
    r = L.new_row(bufs, counts, L.K_XKF1, t_us)
    if r >= 0:
        b = bufs[L.K_XKF1]
        lr, lp, ly = L.euler_deg(el[EK.QW], el[EK.QX], el[EK.QY], el[EK.QZ])
        b[r, XKF1.C] = ln
        b[r, XKF1.Roll] = lr
        b[r, XKF1.Pitch] = lp
        b[r, XKF1.Yaw] = ly
        b[r, XKF1.VN] = el[EK.VN]
        b[r, XKF1.VE] = el[EK.VE]
        b[r, XKF1.VD] = el[EK.VD]
        b[r, XKF1.dPD] = el[EK.VD]
        b[r, XKF1.PN] = el[EK.PN]
        b[r, XKF1.PE] = el[EK.PE]
        b[r, XKF1.PD] = el[EK.PD]
        b[r, XKF1.GX] = el[EK.BGX] * d
        b[r, XKF1.GY] = el[EK.BGY] * d
        b[r, XKF1.GZ] = el[EK.BGZ] * d
        b[r, XKF1.OH] = home_alt
    r = L.new_row(bufs, counts, L.K_XKF4, t_us)
    if r >= 0:
        b = bufs[L.K_XKF4]
        b[r, XKF4.C] = ln
        b[r, XKF4.SV] = math.sqrt(max(el[EK.VEL_TR], 0.0))
        b[r, XKF4.SP] = math.sqrt(max(el[EK.POS_TR], 0.0))
        b[r, XKF4.SH] = math.sqrt(max(el[EK.HGT_TR], 0.0))
        b[r, XKF4.SM] = math.sqrt(max(el[EK.MAG_TR], 0.0))
        b[r, XKF4.FS] = el[EK.FAULT]
        # timeout bits: 1 position, 4 height (EKF3 hgtTimeout: no height fused for 10 s)
        ts = 0.0 if el[EK.F_HORIZ_POS] != 0.0 else 1.0
        if el[EK.F_ATTITUDE] != 0.0 and el[EK.F_VERT_POS] == 0.0:
            ts += 4.0
        b[r, XKF4.TS] = ts
        b[r, XKF4.PI] = primary


@inline_jit
def _log_sources(bufs, counts, t_us, el, ln):
    """XKFS row of lane ln: the compass it reads (MI), one baro, GPS and airspeed (index 0),
    GPS good to align (once it has fused GPS), magnetometer fusion state."""
    r = L.new_row(bufs, counts, L.K_XKFS, t_us)
    if r >= 0:
        b = bufs[L.K_XKFS]
        b[r, XKFS.C] = ln
        b[r, XKFS.MI] = el[EK.MAG_IDX]
        b[r, XKFS.BI] = 0.0
        b[r, XKFS.GI] = 0.0
        b[r, XKFS.AI] = 0.0
        b[r, XKFS.SS] = 0.0
        aligned = el[EK.ALIGNED] != 0.0
        b[r, XKFS.GPS_GTA] = 1.0 if aligned and el[EK.T_GPS_FUSED] > -1.0e8 else 0.0
        b[r, XKFS.GPS_CHK_WAIT] = 0.0
        b[r, XKFS.MAG_FUSION] = (2.0 if el[EK.IN_FLIGHT] != 0.0 else 1.0) if aligned else 0.0


XKY0, XKY1 = L.XKY0_COLS, L.XKY1_COLS


@tick_jit
def _deg360(a):
    """Angle [rad] in degrees wrapped to [0, 360)."""
    d = (a * L.RAD2DEG) % 360.0
    return d if d < 360.0 else 0.0


@tick_jit
def log_gsf(bufs, counts, t_us, gsf):
    """XKY0 and XKY1 rows (10 Hz) of every lane whose EKF-GSF yaw estimator (:mod:`tlm_sim.ekf.gsf`)
    fuses GPS velocity, as EKF3 logs them: composite yaw and sqrt(degrees(variance)) (the
    firmware's conversion of a rad^2 variance), each model's yaw and weight; each model's NE
    velocity innovations."""
    for ln in range(gsf.shape[0]):
        g = gsf[ln]
        if g[GL.G_FUSING] == 0.0:
            continue
        gsf_refresh(g)
        r = L.new_row(bufs, counts, L.K_XKY0, t_us)
        if r >= 0:
            b = bufs[L.K_XKY0]
            b[r, XKY0.C] = ln
            b[r, XKY0.YC] = _deg360(g[GL.G_YAW])
            b[r, XKY0.YCS] = math.sqrt(max(g[GL.G_YAW_VAR] * L.RAD2DEG, 0.0))
            for m in range(GL.N_MODELS):
                mb = GL.MODEL_BASE + m * GL.MODEL_STRIDE
                b[r, XKY0.Y0 + m] = _deg360(g[mb + GL.M_YAW])
                b[r, XKY0.W0 + m] = g[GL.G_W + m]
        r = L.new_row(bufs, counts, L.K_XKY1, t_us)
        if r >= 0:
            b = bufs[L.K_XKY1]
            b[r, XKY1.C] = ln
            for m in range(GL.N_MODELS):
                mb = GL.MODEL_BASE + m * GL.MODEL_STRIDE
                b[r, XKY1.IVN0 + m] = g[mb + GL.M_INNOV]
                b[r, XKY1.IVE0 + m] = g[mb + GL.M_INNOV + 1]
