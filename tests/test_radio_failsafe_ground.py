"""The radio failsafe on the ground (ArduCopter's should_disarm_on_failsafe): a pilot-flown
copter armed and still landed disarms at once (ARM.Method 16, RADIOFAILSAFE) instead of
flying the failsafe's RTL; in the air it flies RTL as before."""

from __future__ import annotations

import numpy as np
import pytest

from tlm_sim import ardupilot as AP
from tlm_sim import fly
from tlm_sim.mission.sticks import StickScript

#: LOITER: the rudder arming gesture at 42.4-46 s, then the throttle stays down (landed) or
#: climbs at 46.2 s and holds at 56.9 s (as the reference pilot flights)
ARM_ROWS = ({"t": 0, "mode": "LOITER"}, {"t": 42.4, "yaw": 1.0, "ramp": 0},
            {"t": 46.0, "yaw": 0.0, "ramp": 0})
CLIMB_ROWS = ({"t": 46.2, "throttle": 0.8, "ramp": 0}, {"t": 56.9, "throttle": 0.5})


def _fly(rows, fail_at: float):
    return fly(None, sticks=StickScript(rows), faults=[(fail_at, "SIM_RC_FAIL", 1)], seed=1)


def _armed_at(log) -> float:
    ev = log.tables["EV"]
    return float(ev.TimeUS[ev.Id == AP.EV_ARMED].iloc[0]) * 1e-6


def test_landed_it_disarms_by_the_radio_failsafe():
    log = _fly(ARM_ROWS, 48.0)
    assert _armed_at(log) < 48.0
    arm = log.tables["ARM"]
    last = arm.iloc[-1]
    assert last.ArmState == 0 and last.Method == AP.ARM_METHOD_RADIOFAILSAFE
    # the radio failsafe (ERR 5/1) then the disarm, RC_FS_TIMEOUT after the last frame
    err = log.tables["ERR"]
    fs = err[(err.Subsys == AP.ERR_FAILSAFE_RADIO) & (err.ECode == AP.ERR_CODE_FAILSAFE)]
    assert len(fs) == 1
    t_fs = float(fs.TimeUS.iloc[0]) * 1e-6
    assert 48.0 < t_fs < 50.0
    assert float(last.TimeUS) * 1e-6 == pytest.approx(t_fs, abs=0.01)
    assert not (log.tables["MODE"].Mode == AP.MODE_RTL).any()


def test_in_the_air_it_flies_rtl():
    log = _fly(ARM_ROWS + CLIMB_ROWS, 70.0)
    mode = log.tables["MODE"]
    rtl = mode[mode.Mode == AP.MODE_RTL]
    assert len(rtl) and 70.0 < float(rtl.TimeUS.iloc[0]) * 1e-6 < 72.0
    assert int(rtl.Rsn.iloc[0]) == AP.RSN_RADIO_FAILSAFE
    arm = log.tables["ARM"]
    assert not np.any(arm.Method == AP.ARM_METHOD_RADIOFAILSAFE)
