"""Motor loss on frames of six and more motors (issue 20): ArduCopter's motor-loss handling in
the mixer (AP_MotorsMatrix::check_for_failed_motor, the thrust boost ratio) and the throttle vs
attitude priority it relies on (ATC_THR_MIX_*), then whole flights: a hexa losing motor 1 in
AUTO keeps flying with ArduCopter's hex settings, an octa needs no help, a quad still falls.

Flights: built-in mission 1, seed 0, SIM_ENGINE_MUL 0 on the SIM_ENGINE_FAIL motors from 120 s
to 150 s (the "engine" fault), heights from the SIM truth above home.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
import pandas as pd
import pytest

from tlm_process.fault_metrics import Flight
from tlm_sim.control import layout as C
from tlm_sim.control.attitude import throttle_mix_update
from tlm_sim.control.config import build_control_config
from tlm_sim.control.mixer import (
    MOT_SPOOL_TIME_S,
    _yaw_allowed,
    boost_ratio_update,
    mix,
    motor_loss_monitor,
)
from tlm_sim.flightlog.texts import event_texts
from tlm_sim.params import Params

T0, T1 = 120.0, 150.0  # the motor is dead from T0 to T1 [s]
#: ArduCopter's usable minimum settings for a hexa losing a motor (the comment in
#: AP_MotorsMatrix::output_armed_stabilizing): MOT_YAW_HEADROOM 0, ATC_RAT_RLL_IMAX and
#: ATC_RAT_PIT_IMAX 1.0 (ATC_RAT_YAW_IMAX 0.5 is the default)
HEX_SETTINGS = {"MOT_YAW_HEADROOM": 0.0, "ATC_RAT_RLL_IMAX": 1.0, "ATC_RAT_PIT_IMAX": 1.0}


def _config(frame_class: int, frame_type: int) -> np.ndarray:
    return build_control_config(Params({"FRAME_CLASS": frame_class, "FRAME_TYPE": frame_type}))


def _state(g: np.ndarray) -> np.ndarray:
    """A controller state for mixing without voltage or density compensation (comp = 1)."""
    c = np.zeros(C.N_CONTROL_STATE)
    c[C.THR_AVG_MAX] = 1.0
    return c


def _vmax(g: np.ndarray) -> float:
    return float(g[C.G_MOT_BAT_MAX])


# ------------------------------------------------------------------------ mixer, unit level


def test_lost_motor_leaves_the_range_and_the_others_keep_their_authority():
    """Hexa (+), motor 1 (front) lost, boost ratio 1: a pitch-up demand that puts motor 1
    beyond full output is mixed for the other five as if motor 1 were not there: no roll/pitch
    scaling, the throttle not held down by motor 1; motor 1 itself is clipped at 1 while its
    unclipped demand (> 1) feeds the monitor's filter. With ratio 0 the same demand is scaled
    down and the throttle capped by motor 1, as on any frame."""
    g = _config(2, 0)
    out = {}
    for r in (0.0, 1.0):
        c = _state(g)
        c[C.THRUST_BOOST] = 1.0
        c[C.MOTOR_LOST] = 0.0
        c[C.THRUST_UNBALANCED] = 1.0 if r else 0.0
        c[C.THRUST_BOOST_RATIO] = r
        filt0 = np.array([1.2, 0.0, 0.6, 0.6, 0.6, 0.6])
        c[C.MIX_THRUST_FILT : C.MIX_THRUST_FILT + 6] = filt0
        mix(c, g, 0.0, 1.2, 0.0, 0.6, _vmax(g))
        alpha = g[C.G_DT] / (g[C.G_DT] + 0.5)
        unclipped = (c[C.MIX_THRUST_FILT] - (1.0 - alpha) * filt0[0]) / alpha
        out[r] = (c[C.MIX_THRUST : C.MIX_THRUST + 6].copy(), unclipped, c[C.LIM_THR_HI],
                  c[C.LIM_RP], c[C.MOT_THR_OUT])
    m0, _, hi0, rp0, t0 = out[0.0]
    m1, raw1, hi1, rp1, t1 = out[1.0]
    assert m1[0] == 1.0 and raw1 == pytest.approx(1.2, abs=1e-9)  # 0.6 + 1.2 x 0.5
    assert m1[3] - m1[2] == pytest.approx(0.6, abs=1e-9)  # front-right minus rear-left: 1.2 x 0.5
    assert m0[3] - m0[2] == pytest.approx(0.5, abs=1e-9)  # scaled by 1 / 1.2
    assert (hi1, rp1, hi0, rp0) == (0.0, 0.0, 1.0, 1.0)
    assert t1 == pytest.approx(0.6, abs=1e-12) and t0 == pytest.approx(0.5, abs=1e-12)


def test_quad_boost_changes_only_the_yaw_that_would_raise_the_lost_motor():
    """A quad never finds its thrust unbalanced, so the boost ratio stays 0 (ArduCopter:
    motor-loss handling needs 6 motors) and the boost changes its mix only through the lost
    motor's yaw room: without yaw the mix is the same, and a yaw that would raise the
    saturated lost motor further is cut to its room (0 here) instead of MOT_YAW_HEADROOM."""
    g = _config(1, 1)
    rng = np.random.default_rng(3)
    for _ in range(200):
        r, p = rng.uniform(-1.5, 1.5, 2)
        t = rng.uniform(0.0, 1.0)
        a, b = _state(g), _state(g)
        b[C.THRUST_BOOST] = 1.0
        b[C.MIX_THRUST_FILT : C.MIX_THRUST_FILT + 4] = [1.5, 0.0, 0.2, 0.2]  # balance 3.9
        mix(a, g, r, p, 0.0, t, _vmax(g))
        mix(b, g, r, p, 0.0, t, _vmax(g))
        assert b[C.THRUST_UNBALANCED] == 0.0 and b[C.THRUST_BOOST_RATIO] == 0.0
        assert np.array_equal(a[C.MIX_PWM : C.MIX_PWM + 4], b[C.MIX_PWM : C.MIX_PWM + 4])
    # X quad, motor 1 (front right, CCW) lost and saturated by a roll-left pitch-up demand;
    # yaw right (+) raises the CCW motors
    out = []
    for boost in (0.0, 1.0):
        c = _state(g)
        c[C.THRUST_BOOST] = boost
        c[C.MIX_THRUST_FILT] = 1.5
        mix(c, g, -0.5, 0.5, 0.3, 0.5, _vmax(g))
        out.append(c[C.MIX_THRUST : C.MIX_THRUST + 4].copy())
    spread = [(m[0] + m[1]) - (m[2] + m[3]) for m in out]  # CCW minus CW: the yaw applied
    assert spread[0] == pytest.approx(4 * 0.5 * 0.2) and spread[1] == pytest.approx(0.0)


@pytest.mark.parametrize("frame", [(2, 0), (1, 1)])
def test_monitor_names_the_highest_motor_flags_imbalance_and_ends_the_boost(frame):
    """check_for_failed_motor: the lost motor is the highest filtered output (held while the
    boost is on); unbalanced at highest x n / sum >= 1.5 (six motors or more), balanced again
    at <= 1.25, hysteresis in between; the boost ends once balanced, below 0.9 and with
    throttle headroom."""
    g = _config(*frame)
    n = int(g[C.G_N_MOTORS])
    c = _state(g)
    six = n >= 6

    def monitor(filt, thr=0.5):
        c[C.MIX_THRUST_FILT : C.MIX_THRUST_FILT + n] = filt
        motor_loss_monitor(c, g, n, 1.0, thr)

    lopsided = [0.2] * n
    lopsided[1] = 1.2
    monitor(lopsided)  # 1.2 n / (1.2 + 0.2 (n - 1))
    assert c[C.MOTOR_LOST] == 1 and c[C.THRUST_UNBALANCED] == float(six)
    c[C.THRUST_BOOST] = 1.0
    other = [0.2] * n
    other[2] = 1.2
    monitor(other)
    assert c[C.MOTOR_LOST] == 1  # held while boosted
    mid = [0.3] * n
    mid[0] = 0.3 * 1.4 * (n - 1) / (n - 1.4)  # balance 1.4, between the thresholds
    monitor(mid)
    assert c[C.THRUST_UNBALANCED] == float(six) and c[C.THRUST_BOOST] == float(six)
    c[C.THRUST_BOOST] = 1.0
    monitor([0.95] * n)  # balanced, but the highest output is still at 95 %
    assert c[C.THRUST_UNBALANCED] == 0.0 and c[C.THRUST_BOOST] == 1.0
    monitor([0.5] * n, thr=1.0)  # throttle at its maximum (comp 1)
    assert c[C.THRUST_BOOST] == 1.0
    monitor([0.5] * n)
    assert c[C.THRUST_BOOST] == 0.0
    monitor([0.5] * (n - 1) + [0.55])
    assert c[C.MOTOR_LOST] == n - 1  # free again


def test_boost_ratio_ramps_over_the_spool_time():
    """_thrust_boost_ratio: up to 1 in MOT_SPOOL_TIME while boosted and unbalanced, back down
    at the same rate otherwise."""
    g = _config(2, 0)
    c = _state(g)
    c[C.THRUST_BOOST] = 1.0
    c[C.THRUST_UNBALANCED] = 1.0
    ticks = round(MOT_SPOOL_TIME_S / g[C.G_DT])
    for _ in range(ticks // 2):
        boost_ratio_update(c, g)
    assert c[C.THRUST_BOOST_RATIO] == pytest.approx(0.5, abs=1e-9)
    for _ in range(ticks):
        boost_ratio_update(c, g)
    assert c[C.THRUST_BOOST_RATIO] == 1.0
    c[C.THRUST_UNBALANCED] = 0.0
    for _ in range(ticks // 4):
        boost_ratio_update(c, g)
    assert c[C.THRUST_BOOST_RATIO] == pytest.approx(0.75, abs=1e-9)


def test_yaw_headroom_without_the_lost_motor():
    """Yaw room: the least room of the motors with a yaw factor, at least MOT_YAW_HEADROOM (0.2
    by default). While boosted, with ratio r: the lost motor's room does not count, the floor
    is r 0.5 + (1 - r) 0.2, then the lost motor's room in the direction the yaw demand moves
    it (up for a yaw that raises it) limits the result by 1 - r, floor or not."""
    g = _config(2, 0)
    n = 6
    assert g[C.G_MOT_YAW_HEADROOM] == pytest.approx(0.2)
    # hexa (+), pitch 0.7 at thr_best 0.6: motor 1 (front, CW) at 0.95 has 0.05 / 0.5 = 0.1
    # of room up; the tightest of the others are motors 4 and 5 at 0.775: 0.45
    assert _yaw_allowed(g, 0.0, 0.7, 1.0, 0.6, (n, -1, 0.0), -0.3) == pytest.approx(0.2)
    # boosted, ratio 0: a yaw left (negative) raises the CW motor 1 -> its 0.1, below the floor
    assert _yaw_allowed(g, 0.0, 0.7, 1.0, 0.6, (n, 0, 0.0), -0.3) == pytest.approx(0.1)
    # ... a yaw right lowers it (room 1.9): the other motors' 0.45
    assert _yaw_allowed(g, 0.0, 0.7, 1.0, 0.6, (n, 0, 0.0), 0.3) == pytest.approx(0.45)
    assert _yaw_allowed(g, 0.0, 0.7, 1.0, 0.6, (n, 0, 1.0), -0.3) == pytest.approx(0.5)
    assert _yaw_allowed(g, 0.0, 0.7, 1.0, 0.6, (n, 0, 0.5), -0.3) == pytest.approx(
        0.5 * 0.45 + 0.5 * 0.1)  # floor 0.35 < 0.45


def test_throttle_is_raised_for_attitude_only_up_to_the_average_maximum():
    """The mixer may lift the throttle above the demand to keep the lowest motor at 0 only up to
    THR_AVG_MAX; beyond it the roll/pitch/yaw demand is scaled down (rpy_scale)."""
    g = _config(2, 0)
    c = _state(g)
    mix(c, g, 0.0, 0.8, 0.0, 0.1, _vmax(g))  # motor 2 at -0.4: the throttle goes to 0.4
    assert c[C.MOT_THR_OUT] == pytest.approx(0.4) and c[C.MIX_THRUST + 1] == 0.0
    c = _state(g)
    c[C.THR_AVG_MAX] = 0.3
    mix(c, g, 0.0, 0.8, 0.0, 0.1, _vmax(g))
    assert c[C.MOT_THR_OUT] == pytest.approx(0.3) and c[C.MIX_THRUST + 1] == pytest.approx(0.0)
    assert c[C.MIX_THRUST] == pytest.approx(0.6)  # 0.3 + 0.4 x 0.75
    assert c[C.LIM_RP] == 1.0 and c[C.LIM_YAW] == 1.0


def test_throttle_mix_slews_and_resets_to_the_mix_in_use():
    """_throttle_rpy_mix: up at 2/s, down at 0.5/s but at once to the mix the mixer used,
    within 0.1..5; THR_AVG_MAX = max(thr, thr (1 - mix) + hover mix)."""
    g = _config(1, 1)
    c = _state(g)
    c[C.THR_HOVER] = 0.4
    c[C.THR_RPY_MIX] = 0.1
    for _ in range(40):  # 0.1 s
        throttle_mix_update(c, g, g[C.G_THR_MIX_MAX], 0.2, 0.2)
    assert c[C.THR_RPY_MIX] == pytest.approx(0.3)
    assert c[C.THR_AVG_MAX] == pytest.approx(0.2 * 0.7 + 0.4 * 0.3)
    for _ in range(400):
        throttle_mix_update(c, g, g[C.G_THR_MIX_MAX], 0.2, 0.2)
    assert c[C.THR_RPY_MIX] == pytest.approx(g[C.G_THR_MIX_MAX])
    c[C.MOT_THR_OUT] = 0.3  # the mixer raised the throttle half way to the hover throttle
    throttle_mix_update(c, g, g[C.G_THR_MIX_MIN], 0.2, 0.2)
    assert c[C.THR_RPY_MIX] == pytest.approx(0.5 - 0.5 * g[C.G_DT])  # used 0.5: slew only
    c[C.MOT_THR_OUT] = 0.2
    throttle_mix_update(c, g, g[C.G_THR_MIX_MIN], 0.2, 0.2)
    assert c[C.THR_RPY_MIX] == pytest.approx(max(g[C.G_THR_MIX_MIN], 0.1))  # used 0: at once


# ----------------------------------------------------------------------------- flights


@lru_cache(maxsize=16)
def _fly(frame_class: int, frame_type: int, extra: tuple = ()):
    import tlm_sim
    from tlm_sim.faults import Fault, FaultSchedule

    params = {"FRAME_CLASS": frame_class, "FRAME_TYPE": frame_type, **dict(extra)}
    log = tlm_sim.fly(1, FaultSchedule((Fault("engine", T0, T1),)), params=params, seed=0)
    t = dict(log.tables)
    return t, Flight(t), event_texts(t)


def _measure(frame_class: int, frame_type: int, extra: dict | None = None) -> dict:
    """What the motor loss does: heights, ERR 25 and crash-check times, texts, heading."""
    t, f, texts = _fly(frame_class, frame_type, tuple(sorted((extra or {}).items())))
    st, h = f.sim_t, f.h
    win = (st >= T0 * 1e6) & (st <= T1 * 1e6)
    h0 = float(np.mean(h[(st >= (T0 - 5) * 1e6) & (st < T0 * 1e6)]))
    err = t.get("ERR", pd.DataFrame({"TimeUS": [], "Subsys": []}))

    def err_s(sub):
        return [(x - T0 * 1e6) * 1e-6 for x, s in zip(err.TimeUS, err.Subsys, strict=True)
                if s == sub and T0 * 1e6 <= x <= T1 * 1e6]

    e25 = err_s(25)
    settled = win & (st >= T0 * 1e6 + ((e25[0] if e25 else 0.0) + 5.0) * 1e6)
    att = t["ATT"]
    before = att[(att.TimeUS >= (T0 - 2) * 1e6) & (att.TimeUS < T0 * 1e6)].Yaw.mean()
    late = att[(att.TimeUS >= (T1 - 5) * 1e6) & (att.TimeUS < T1 * 1e6)].Yaw
    pn, pe = t["PSCN"], t["PSCE"]
    w = (pn.TimeUS >= T0 * 1e6) & (pn.TimeUS <= T1 * 1e6)
    return {
        "h_drop": h0 - float(h[win].min()),
        "ground": bool((h[win] <= 0.5).any()),
        "settled": (float((h[settled] - h0).min()), float((h[settled] - h0).max()))
        if settled.any() else None,
        "err25": e25,
        "err12": err_s(12),
        "texts": [m for x, m in texts if T0 * 1e6 <= x <= T1 * 1e6
                  and not m.startswith(("Mission:", "Reached command"))],  # not the progress
        "heading_change": float((late.mean() - before + 180.0) % 360.0 - 180.0),
        "heading_std_late": float(late.std()),
        "track_max": float(np.hypot((pn.TPN - pn.PN)[w], (pe.TPE - pe.PE)[w]).max()),
        "auto_kept": f.mode_kept(3, T0 * 1e6, (T1 + 30) * 1e6),
        "armed_kept": 1.0 - f.disarmed_in(T0 * 1e6, T1 * 1e6),
    }


@pytest.mark.parametrize("frame, motor", [((2, 0), 1), ((2, 1), 1), ((2, 0), 2), ((2, 1), 3)])
def test_hexa_with_arducopter_hex_settings_survives_a_motor_loss(frame, motor):
    """Hexa (+ and X) with ArduCopter's hex settings losing one motor for 30 s in AUTO: ~3 s of
    descent at full throttle until the thrust-loss check (ERR 25/1, "Potential Thrust Loss
    (n)" naming the dead motor) turns the thrust boost on; then the mixer lets the dead motor
    go, the copter holds its altitude (measured: 6.6-6.8 m lost, within 0.7 m of the
    mission's height from 5 s after the detection) and its track (error at most 1.8-7.4 m),
    turns 56-91 deg away from its heading and holds the new one (one yaw direction is lost
    with the motor), keeps AUTO and flies the mission to its end."""
    extra = dict(HEX_SETTINGS, SIM_ENGINE_FAIL=float(1 << (motor - 1)))
    m = _measure(*frame, extra)
    assert not m["ground"] and m["h_drop"] < 8.0
    assert len(m["err25"]) == 1 and 2.0 < m["err25"][0] < 4.0
    assert m["texts"] == [f"Potential Thrust Loss ({motor})"]
    assert -1.0 < m["settled"][0] and m["settled"][1] < 0.5
    assert m["track_max"] < 8.0
    assert 45.0 < abs(m["heading_change"]) < 100.0 and m["heading_std_late"] < 1.0
    assert m["auto_kept"] == 1.0 and m["armed_kept"] == 1.0 and not m["err12"]


def test_hexa_with_default_rate_imax_cannot_hold_its_attitude():
    """With ArduCopter's default ATC_RAT_PIT_IMAX 0.5 the hexa (+) losing motor 1 gets the
    boost but not its attitude back: holding the rear motor at 0 against the dead front one
    needs a steady pitch output of at least ~0.75 (motors 3-6 at 1.5 x hover = 0.58, the rear
    motor's share -0.75 x pitch), more than the integrator may hold, so the copter hangs pitched
    45-55 deg from its target (at the mission's height) until the crash check disarms it in
    the air (measured: 15.6 s after the loss). This is why
    ArduCopter's comment lists IMAX 1.0 for hexa motor loss and why its own autotest
    (MotorFail) only expects an octocopter to survive."""
    m = _measure(2, 0)
    assert len(m["err25"]) == 1 and m["texts"][0] == "Potential Thrust Loss (1)"
    assert len(m["err12"]) == 1 and m["err25"][0] + 5.0 < m["err12"][0]
    _, f, _ = _fly(2, 0)
    at = np.searchsorted(f.sim_t, (T0 + m["err12"][0]) * 1e6) - 1
    assert f.h[at] > 15.0 and m["armed_kept"] < 1.0  # disarmed in the air


@pytest.mark.parametrize("motor", [1, 2])
def test_octa_loses_a_motor_without_help(motor):
    """An octa (+) losing one motor never saturates (throttle ~0.45, the dead motor's command
    ~1800 us): no thrust-loss check, no boost; it dips 0.7 m and flies on (heading within
    8 deg)."""
    m = _measure(3, 0, {"SIM_ENGINE_FAIL": float(1 << (motor - 1))})
    assert not m["ground"] and m["h_drop"] < 1.5
    assert m["err25"] == [] and m["texts"] == []
    assert abs(m["heading_change"]) < 8.0 and m["track_max"] < 2.0
    assert m["auto_kept"] == 1.0 and m["armed_kept"] == 1.0


@pytest.mark.parametrize("frame", [(1, 0), (1, 1)])
def test_quad_losing_a_motor_still_falls(frame):
    """A quad has no motor-loss handling: it hits the ground within 3 s, then the thrust-loss
    check reports the motor with the highest output: motor 1 for "+", which then lies still at
    full throttle as SITL's (engine_s14.bin). The X quad's lean target ends up on a live
    motor's side: it bounces on the 1 mm ground band at the lift threshold (0.2-0.9 m/s
    impacts), and the motor named depends on the bounce (no SITL X-frame engine reference)."""
    m = _measure(*frame)
    assert m["ground"] and m["h_drop"] > 19.0
    lost = [x for x in m["texts"] if x.startswith("Potential Thrust Loss (")]
    assert m["err25"] and lost
    if frame == (1, 0):
        assert lost[0] == "Potential Thrust Loss (1)"
        assert sum(x.startswith("SIM Hit ground") for x in m["texts"]) == 1
    t, f, _ = _fly(*frame)
    down = f.sim_t[(f.sim_t >= T0 * 1e6) & (f.h <= 0.5)][0]
    assert (down - T0 * 1e6) * 1e-6 < 3.0
    assert math.isclose(m["auto_kept"], 1.0)
