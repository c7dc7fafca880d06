"""Which compass each lane fuses (EKF3 ``readMagData`` / ``tryChangeCompass``), once per compass
tick.

The compasses arrive as the sensors' compass block (``tlm_sim.sensors.layout`` MAG records:
field, new sample, healthy, time). A lane reads its compass ``MAG_IDX`` only (compass 0 after
start): a new sample is fused (:func:`tlm_sim.ekf.fusion.lane_fuse_mag`); without one the lane
runs on its gyros for yaw. The lane changes to the next healthy compass (cyclic order, as
EKF3) when

* its compass is unhealthy and has delivered nothing for ``C_MAG_FAIL_T`` (10 s), on the ground
  too (SITL ``SIM_MAG1_FAIL`` 1: "EKF3 IMU0 switching to compass 1" 10 s after the last sample);
* in flight, more than ``C_MAG_SWITCH_T0`` (30 s) after alignment, its fusion has been rejected
  by the innovation gate for ``C_MAG_FAIL_T`` (a frozen or disturbed compass: EKF3's
  ``magTimeout``).

While disarmed, a lane on another compass goes back to compass 0 once that is healthy (the
reference logs: "switching to compass 0" at disarm). The earth field is fixed in tlm's EKF, so a
change needs no field-state reset. ``XKFS.MI`` logs the index; the MSG text is rendered from
its changes (:mod:`tlm_sim.flightlog.texts`).
"""

from tlm_sim import ardupilot as AP
from tlm_sim._jit import tick_jit
from tlm_sim.ekf.fusion import lane_fuse_mag
from tlm_sim.ekf.layout import (
    ALIGNED,
    C_INFLIGHT_HGT,
    C_MAG_FAIL_T,
    C_MAG_SWITCH_T0,
    IN_FLIGHT,
    INFLIGHT_SEEN,
    MAG_IDX,
    PD,
    T_ALIGNED,
    T_MAG_PASS,
    T_MAG_READ,
)
from tlm_sim.ekf.lifecycle import life_event
from tlm_sim.sensors.layout import M_FIELD, M_HEALTHY, M_NEW, MAG_STRIDE, N_MAG


@tick_jit
def change_compass(e, t, mag):
    """Move the lane to the next healthy compass after its current one (cyclic); returns True
    if it changed."""
    k = int(e[MAG_IDX])
    for j in range(1, N_MAG):
        c = (k + j) % N_MAG
        if mag[c * MAG_STRIDE + M_HEALTHY] != 0.0:
            e[MAG_IDX] = c
            e[T_MAG_READ] = t
            e[T_MAG_PASS] = t
            return True
    return False


@tick_jit
def lane_read_mag(e, cfg, t, mag, armed):
    """One compass tick of one lane at t [s]: in-flight state, compass choice, fusion of a new
    sample of its compass (mag: the compass block)."""
    if not armed:
        e[IN_FLIGHT] = 0.0
        if e[MAG_IDX] != 0.0 and mag[M_HEALTHY] != 0.0:
            e[MAG_IDX] = 0.0
            e[T_MAG_READ] = t
            e[T_MAG_PASS] = t
    elif e[ALIGNED] != 0.0 and -e[PD] > cfg[C_INFLIGHT_HGT]:
        e[IN_FLIGHT] = 1.0
        if e[INFLIGHT_SEEN] == 0.0:  # EKF3's in-flight yaw alignment (its message only)
            e[INFLIGHT_SEEN] = 1.0
            life_event(e, AP.EKF_EVT_INFLIGHT_YAW)
    b = int(e[MAG_IDX]) * MAG_STRIDE
    if mag[b + M_NEW] != 0.0:
        e[T_MAG_READ] = t
        if lane_fuse_mag(e, cfg, mag[b + M_FIELD:b + M_FIELD + 3]):
            e[T_MAG_PASS] = t
        elif (e[IN_FLIGHT] != 0.0 and t - e[T_MAG_PASS] > cfg[C_MAG_FAIL_T]
              and t - e[T_ALIGNED] > cfg[C_MAG_SWITCH_T0]):
            change_compass(e, t, mag)
    elif mag[b + M_HEALTHY] == 0.0 and t - e[T_MAG_READ] > cfg[C_MAG_FAIL_T]:
        change_compass(e, t, mag)
