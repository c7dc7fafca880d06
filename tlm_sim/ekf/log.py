"""The EKF's log messages: XKF1, XKF4 and XKFS per lane, POS from the output block (10 Hz),
XKY0 / XKY1 of the lanes' yaw estimators, and the ERR rows of a primary-lane change and of
ArduCopter's GPS glitch check; the evidence messages (:func:`log_ekf_evidence`): XKF2, XKF3
and XKQ per lane at 10 Hz, XKF5 (10 Hz) and XKV1/XKV2 (every 0.5 s) of the primary lane
only, as EKF3 logs them. Columns by name (:mod:`tlm_sim.logger`).

What each field holds, and how tlm's 15-error-state filter maps onto EKF3's 24 states, is in
``docs/architecture.md`` ("EKF evidence messages"). Signs follow EKF3: innovations are
predicted minus measured (tlm's filter stores measured minus predicted, ``INNOV_*``).
"""

import math

from tlm_sim import ardupilot as AP
from tlm_sim import logger as L
from tlm_sim._jit import inline_jit, tick_jit
from tlm_sim.ekf import gsf_layout as GL
from tlm_sim.ekf import layout as EK
from tlm_sim.ekf.gsf import gsf_refresh
from tlm_sim.geo import ne_to_latlon_scalar

XKF1, XKF4, XKFS, POS = L.XKF1_COLS, L.XKF4_COLS, L.XKFS_COLS, L.POS_COLS
XKF2, XKF3, XKF5, XKQ = L.XKF2_COLS, L.XKF3_COLS, L.XKF5_COLS, L.XKQ_COLS
XKV1, XKV2 = L.XKV1_COLS, L.XKV2_COLS
#: EKF3 logs its state variances when more than 490 ms have passed since the last (2 Hz)
XKV_INTERVAL_S = 0.49
#: EKF3's terrain-height variance Popt after its covariance initialisation [m^2]; without a
#: range finder or optical flow nothing updates it (XKF5.Herr = its square root, 0.5 m)
TERRAIN_VAR_INIT = 0.25


@tick_jit
def log_lane_switch(ev, t_us, eo):
    """ERR EKF_PRIMARY with the new primary lane (from the output block eo) into the event
    buffers (tlm_sim.logger E_*)."""
    r = L.new_row(ev, L.E_ERR, t_us)
    if r >= 0:
        ev[0][L.E_ERR][r, L.ERR_COLS.Subsys] = AP.ERR_EKF_PRIMARY
        ev[0][L.E_ERR][r, L.ERR_COLS.ECode] = eo[EK.O_PRIMARY]


@tick_jit
def gps_glitch_check(ev, t_us, ekf, sel):
    """ArduCopter's gpsglitch_check (10 Hz): an edge of the primary lane's gps_glitching flag
    logs ERR GPS 2 ("GPS Glitch or Compass error") or 0 ("Glitch cleared"). No mode change:
    Copter has no GPS failsafe of its own."""
    g = ekf[int(sel[EK.SEL_PRIMARY]), EK.GPS_GLITCHING]
    if g == sel[EK.SEL_GPS_GLITCH]:
        return
    sel[EK.SEL_GPS_GLITCH] = g
    r = L.new_row(ev, L.E_ERR, t_us)
    if r >= 0:
        ev[0][L.E_ERR][r, L.ERR_COLS.Subsys] = AP.ERR_GPS
        ev[0][L.E_ERR][r, L.ERR_COLS.ECode] = (AP.ERR_CODE_GPS_GLITCH if g != 0.0
                                                 else AP.ERR_CODE_RESOLVED)


@tick_jit
def log_ekf_10hz(log, t_us, ekf, sel, eo, home):
    """The EKF's 10 Hz rows: XKF1, XKF4 and XKFS for every lane, POS of the output (home:
    degrees, m AMSL)."""
    bufs = log[0]  # the log buffers
    home_lat, home_lon, home_alt = home[0], home[1], home[2]  # deg, deg, m AMSL
    for ln in range(int(sel[EK.SEL_N_LANES])):
        _log_lane(log, t_us, ekf[ln], ln, sel[EK.SEL_PRIMARY], home_alt)
        _log_sources(log, t_us, ekf[ln], ln)
    r = L.new_row(log, L.K_POS, t_us)
    if r >= 0:
        b = bufs[L.K_POS]
        lat, lon = ne_to_latlon_scalar(eo[EK.O_PN], eo[EK.O_PE], home_lat, home_lon)
        b[r, POS.Lat] = lat
        b[r, POS.Lng] = lon
        b[r, POS.Alt] = home_alt - eo[EK.O_PD]
        b[r, POS.RelHomeAlt] = -eo[EK.O_PD]
        b[r, POS.RelOriginAlt] = -eo[EK.O_PD]


@inline_jit
def _log_lane(log, t_us, el, ln, primary, home_alt):
    """XKF1 and XKF4 rows of lane ln (its row el of the ekf array)."""
    bufs = log[0]  # the log buffers
    d = L.RAD2DEG
    r = L.new_row(log, L.K_XKF1, t_us)
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
    r = L.new_row(log, L.K_XKF4, t_us)
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
def _log_sources(log, t_us, el, ln):
    """XKFS row of lane ln: the compass it reads (MI), one baro, GPS and airspeed (index 0),
    GPS good to align (once it has fused GPS), magnetometer fusion state."""
    bufs = log[0]  # the log buffers
    r = L.new_row(log, L.K_XKFS, t_us)
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


@tick_jit
def log_ekf_evidence(log, t_us, ekf, sel, cfg):
    """The EKF's evidence rows (10 Hz): XKF2, XKF3 and XKQ of every lane, XKF5 of the primary
    lane, and XKV1/XKV2 of the primary when its last ones are more than 0.49 s old (EKF3's
    per-core timer: 2 Hz, and at once after a primary change). cfg: the EKF configuration
    (the earth field tlm's filter uses)."""
    p = int(sel[EK.SEL_PRIMARY])
    for ln in range(int(sel[EK.SEL_N_LANES])):
        el = ekf[ln]
        _log_states(log, t_us, el, ln, cfg)
        _log_innovations(log, t_us, el, ln, sel[EK.SEL_REL_ERR + ln])
    _log_xkf5(log, t_us, ekf[p], p)
    t = t_us * 1e-6
    if t - ekf[p, EK.T_XKV_LOG] > XKV_INTERVAL_S:
        ekf[p, EK.T_XKV_LOG] = t
        _log_variances(log, t_us, ekf[p], p)


@inline_jit
def _log_states(log, t_us, el, ln, cfg):
    """XKF2 and XKQ rows of lane ln. XKF2: the accel bias states; the earth field tlm's filter
    predicts the compass with (fixed, from TLM_MAG_*; 0 before alignment as EKF3's field
    states); body field, wind and the drag/sideslip innovations 0 (tlm has no such states or
    measurements; EKF3 on a copter without EK3_DRAG_BCOEF logs wind and drag 0 too)."""
    bufs = log[0]  # the log buffers
    r = L.new_row(log, L.K_XKF2, t_us)
    if r >= 0:
        b = bufs[L.K_XKF2]
        b[r, XKF2.C] = ln
        b[r, XKF2.AX] = el[EK.BAX]
        b[r, XKF2.AY] = el[EK.BAY]
        b[r, XKF2.AZ] = el[EK.BAZ]
        b[r, XKF2.VWN] = 0.0
        b[r, XKF2.VWE] = 0.0
        f = 1000.0 if el[EK.ALIGNED] != 0.0 else 0.0  # gauss -> mGauss
        b[r, XKF2.MN] = cfg[EK.C_MAG_N] * f
        b[r, XKF2.ME] = cfg[EK.C_MAG_E] * f
        b[r, XKF2.MD] = cfg[EK.C_MAG_D] * f
        b[r, XKF2.MX] = 0.0
        b[r, XKF2.MY] = 0.0
        b[r, XKF2.MZ] = 0.0
        b[r, XKF2.IDX] = 0.0
        b[r, XKF2.IDY] = 0.0
        b[r, XKF2.IS] = 0.0
    r = L.new_row(log, L.K_XKQ, t_us)
    if r >= 0:
        b = bufs[L.K_XKQ]
        b[r, XKQ.C] = ln
        b[r, XKQ.Q1] = el[EK.QW]
        b[r, XKQ.Q2] = el[EK.QX]
        b[r, XKQ.Q3] = el[EK.QY]
        b[r, XKQ.Q4] = el[EK.QZ]


@inline_jit
def _log_innovations(log, t_us, el, ln, rel_err):
    """XKF3 row of lane ln: the innovations the lane computed at its last GPS (velocity NED,
    position NE; or constant-position pseudo-measurement), baro (D) and compass fusion, sign
    flipped to EKF3's predicted minus measured, compass in mGauss; yaw and airspeed 0 (tlm
    fuses no yaw angle and has no airspeed sensor); the lane's relative error (rel_err) and
    error score."""
    bufs = log[0]  # the log buffers
    r = L.new_row(log, L.K_XKF3, t_us)
    if r >= 0:
        b = bufs[L.K_XKF3]
        b[r, XKF3.C] = ln
        b[r, XKF3.IVN] = -el[EK.INNOV_VN]
        b[r, XKF3.IVE] = -el[EK.INNOV_VE]
        b[r, XKF3.IVD] = -el[EK.INNOV_VD]
        b[r, XKF3.IPN] = -el[EK.INNOV_PN]
        b[r, XKF3.IPE] = -el[EK.INNOV_PE]
        b[r, XKF3.IPD] = -el[EK.INNOV_HGT]
        b[r, XKF3.IMX] = -1000.0 * el[EK.INNOV_MX]
        b[r, XKF3.IMY] = -1000.0 * el[EK.INNOV_MY]
        b[r, XKF3.IMZ] = -1000.0 * el[EK.INNOV_MZ]
        b[r, XKF3.IYAW] = 0.0
        b[r, XKF3.IVT] = 0.0
        b[r, XKF3.RErr] = rel_err
        b[r, XKF3.ErSc] = el[EK.SCORE]


@inline_jit
def _log_xkf5(log, t_us, el, ln):
    """XKF5 row of lane ln (the primary): no optical flow or range finder (their fields 0, as
    SITL logs them), height above the terrain state and the terrain state, the terrain
    height's standard deviation (EKF3's initial one once aligned), the output observer's
    tracking errors (velocity, position: magnitudes of filter minus output; angle 0: tlm
    applies attitude corrections to the output at once)."""
    bufs = log[0]  # the log buffers
    r = L.new_row(log, L.K_XKF5, t_us)
    if r >= 0:
        b = bufs[L.K_XKF5]
        b[r, XKF5.C] = ln
        b[r, XKF5.NI] = 0.0
        b[r, XKF5.FIX] = 0.0
        b[r, XKF5.FIY] = 0.0
        b[r, XKF5.AFI] = 0.0
        aligned = el[EK.ALIGNED] != 0.0
        b[r, XKF5.HAGL] = el[EK.TERRAIN] - (el[EK.PD] + el[EK.OUT_EPD]) if aligned else 0.0
        b[r, XKF5.offset] = el[EK.TERRAIN]
        b[r, XKF5.RI] = 0.0
        b[r, XKF5.rng] = 0.0
        b[r, XKF5.Herr] = math.sqrt(TERRAIN_VAR_INIT) if aligned else 0.0
        b[r, XKF5.eAng] = 0.0
        b[r, XKF5.eVel] = math.sqrt(el[EK.OUT_EVN] ** 2 + el[EK.OUT_EVE] ** 2
                                    + el[EK.OUT_EVD] ** 2)
        b[r, XKF5.ePos] = math.sqrt(el[EK.OUT_EPN] ** 2 + el[EK.OUT_EPE] ** 2
                                    + el[EK.OUT_EPD] ** 2)


@inline_jit
def _quat_var(el, g0, g1, g2):
    """Variance of one quaternion component whose first-order error is 0.5 g . phi (phi: the
    earth-frame attitude error, covariance P[0:3, 0:3] of lane row el)."""
    s = 0.0
    for i in range(3):
        gi = g0 if i == 0 else (g1 if i == 1 else g2)
        row = EK.P0 + i * EK.NS
        s += gi * (el[row] * g0 + el[row + 1] * g1 + el[row + 2] * g2)
    return 0.25 * s


@inline_jit
def _log_variances(log, t_us, el, ln):
    """XKV1 and XKV2 rows of lane ln: the covariance diagonal in EKF3's 24-state order.

    0-3 quaternion: tlm's attitude error is a rotation vector phi in the earth frame
    (q_true = dq(phi) * q), so dq = 0.5 G(q) phi and var(q_i) = 0.25 g_i P_att g_i^T; 4-6
    velocity, 7-9 position: as they are; 10-12 delta-angle bias and 13-15 delta-velocity bias:
    EKF3 keeps the biases per prediction interval, so the gyro/accel bias variances times
    DT_EKF_AVG^2; 16-21 earth and body magnetic field, 22-23 wind: 0, states tlm's filter does
    not have (EKF3 logs 0 for its magnetic field states while they are inhibited, on the
    ground, and for wind on a copter)."""
    bufs = log[0]  # the log buffers
    d = EK.NS + 1
    r = L.new_row(log, L.K_XKV1, t_us)
    if r >= 0:
        b = bufs[L.K_XKV1]
        w, x, y, z = el[EK.QW], el[EK.QX], el[EK.QY], el[EK.QZ]
        b[r, XKV1.C] = ln
        b[r, XKV1.V00] = _quat_var(el, -x, -y, -z)
        b[r, XKV1.V01] = _quat_var(el, w, z, -y)
        b[r, XKV1.V02] = _quat_var(el, -z, w, x)
        b[r, XKV1.V03] = _quat_var(el, y, -x, w)
        for i in range(6):
            b[r, XKV1.V04 + i] = el[EK.P0 + (EK.ES_VEL + i) * d]
        dt2 = el[EK.DT_EKF_AVG] ** 2
        b[r, XKV1.V10] = el[EK.P0 + EK.ES_BG * d] * dt2
        b[r, XKV1.V11] = el[EK.P0 + (EK.ES_BG + 1) * d] * dt2
    r = L.new_row(log, L.K_XKV2, t_us)
    if r >= 0:
        b = bufs[L.K_XKV2]
        dt2 = el[EK.DT_EKF_AVG] ** 2
        b[r, XKV2.C] = ln
        b[r, XKV2.V12] = el[EK.P0 + (EK.ES_BG + 2) * d] * dt2
        for i in range(3):
            b[r, XKV2.V13 + i] = el[EK.P0 + (EK.ES_BA + i) * d] * dt2
        for i in range(8):
            b[r, XKV2.V16 + i] = 0.0
XKY0, XKY1 = L.XKY0_COLS, L.XKY1_COLS


@tick_jit
def _deg360(a):
    """Angle [rad] in degrees wrapped to [0, 360)."""
    d = (a * L.RAD2DEG) % 360.0
    return d if d < 360.0 else 0.0


@tick_jit
def log_gsf(log, t_us, gsf):
    """XKY0 and XKY1 rows (10 Hz) of every lane whose EKF-GSF yaw estimator (:mod:`tlm_sim.ekf.gsf`)
    fuses GPS velocity, as EKF3 logs them: composite yaw and sqrt(degrees(variance)) (the
    firmware's conversion of a rad^2 variance), each model's yaw and weight; each model's NE
    velocity innovations."""
    bufs = log[0]  # the log buffers
    for ln in range(gsf.shape[0]):
        g = gsf[ln]
        if g[GL.G_FUSING] == 0.0:
            continue
        gsf_refresh(g)
        r = L.new_row(log, L.K_XKY0, t_us)
        if r >= 0:
            b = bufs[L.K_XKY0]
            b[r, XKY0.C] = ln
            b[r, XKY0.YC] = _deg360(g[GL.G_YAW])
            b[r, XKY0.YCS] = math.sqrt(max(g[GL.G_YAW_VAR] * L.RAD2DEG, 0.0))
            for m in range(GL.N_MODELS):
                mb = GL.MODEL_BASE + m * GL.MODEL_STRIDE
                b[r, XKY0.Y0 + m] = _deg360(g[mb + GL.M_YAW])
                b[r, XKY0.W0 + m] = g[GL.G_W + m]
        r = L.new_row(log, L.K_XKY1, t_us)
        if r >= 0:
            b = bufs[L.K_XKY1]
            b[r, XKY1.C] = ln
            for m in range(GL.N_MODELS):
                mb = GL.MODEL_BASE + m * GL.MODEL_STRIDE
                b[r, XKY1.IVN0 + m] = g[mb + GL.M_INNOV]
                b[r, XKY1.IVE0 + m] = g[mb + GL.M_INNOV + 1]
