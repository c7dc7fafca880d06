"""The damaged propeller (``prop_damage``, label 14; issue 40): motor 1's rotor out of balance
and its thrust down, tlm's own fault type (SITL has none). Its signature on a quiet airframe,
its clearing, its values relative to an airframe that vibrates or is unbalanced of its own,
generate's draw, and the schedule step that sets an imbalance, its motor and its rotor
frequency at one instant."""

from __future__ import annotations

import numpy as np
import pytest

from tlm_process.fault_signatures import fault_signature
from tlm_process.generate.scenario import fault_params
from tlm_sim import fly
from tlm_sim.faults import FAULT_TYPES, Fault, FaultSchedule
from tlm_sim.flight import build_schedule
from tlm_sim.params import ParamError, Params

T0, T1 = 60.0, 110.0


@pytest.fixture(scope="module")
def quiet():
    """Mission 1 on SITL's quiet airframe, the type's own fault 60-110 s."""
    return fly(1, faults=FaultSchedule([Fault("prop_damage", T0, T1)]), seed=3)


def test_type_record():
    ft = FAULT_TYPES["prop_damage"]
    assert ft.label == 14 and list(FAULT_TYPES)[13] == "prop_damage"
    assert ft.params_start["TLM_VIB_IMB_MOT"] == 1.0  # SIM_ENGINE_FAIL's default motor
    assert ft.params_end["TLM_VIB_IMB"] == 0.0 and ft.params_end["SIM_ENGINE_MUL"] == 1.0


def test_signature_on_a_quiet_airframe(quiet):
    """Motor 1 works harder (its thrust is down) and the airframe shakes in its x-y plane,
    where it did not before (measured: +52 us; VIBE x/y 0.003 -> 4.9 m/s/s)."""
    sig = fault_signature(quiet.tables, quiet.faults[0])
    assert abs(sig["rcou_excess_before_us"]) < 2.0
    assert 30.0 < sig["rcou_excess_in_us"] < 90.0
    assert sig["vibexy_before"] < 0.05 and sig["vibexy_in"] > 2.0
    assert sig["accxy_std_in"] > 20 * sig["accxy_std_before"]
    assert sig["armed_kept"] == 1.0 and sig["auto_kept"] == 1.0


def test_cleared_at_its_end(quiet):
    vibe = quiet.tables["VIBE"]
    after = vibe[(vibe.TimeUS > (T1 + 5) * 1e6) & (vibe.TimeUS < (T1 + 25) * 1e6)]
    assert len(after) and after[["VibeX", "VibeY"]].to_numpy().max() < 0.05
    rcou = quiet.tables["RCOU"]
    w = rcou[(rcou.TimeUS > (T1 + 10) * 1e6) & (rcou.TimeUS < (T1 + 30) * 1e6)]
    out = w[["C1", "C2", "C3", "C4"]].to_numpy(float)
    assert abs((out[:, 0] - out.mean(axis=1)).mean()) < 2.0
    rec = quiet.faults[0]
    assert (rec["type"], rec["label"]) == ("prop_damage", 14)
    assert rec["params_end"]["TLM_VIB_IMB"] == 0.0


def test_relative_to_the_airframe_own_values():
    """An airframe with its own rotor frequency keeps it; one with an unbalanced propeller of
    its own gets that propeller worse, and back to its own imbalance at the end."""
    ft = FAULT_TYPES["prop_damage"]
    assert ft.flown_value("SIM_VIB_MOT_MAX", 150.0, 120.0) == 120.0
    assert ft.flown_value("SIM_VIB_MOT_MAX", 150.0, 0.0) == 150.0
    assert ft.flown_value("TLM_VIB_IMB", 20.0, 5.0) == 25.0
    assert ft.flown_value("TLM_VIB_IMB", 0.0, 5.0) == 5.0
    assert ft.flown_value("TLM_VIB_IMB_MOT", 1.0, 3.0) == 3.0
    assert ft.flown_value("TLM_VIB_IMB_MOT", 0.0, 3.0) == 3.0
    assert ft.flown_value("TLM_VIB_IMB_MOT", 1.0, 0.0) == 1.0
    assert ft.flown_value("SIM_ENGINE_MUL", 0.9, 1.0) == 0.9


def test_flown_on_an_unbalanced_vibrating_airframe():
    own = Params({"SIM_ACC1_RND": 3.0, "SIM_ACC2_RND": 3.0, "SIM_VIB_MOT_MAX": 120.0,
                  "TLM_VIB_IMB_MOT": 3.0, "TLM_VIB_IMB": 5.0, "TLM_VIB_CMD_REF": 0.55})
    log = fly(1, faults=FaultSchedule([Fault("prop_damage", T0, T1)]), seed=3, params=own)
    rec = log.faults[0]
    assert rec["params_start"]["SIM_VIB_MOT_MAX"] == 120.0
    assert rec["params_start"]["TLM_VIB_IMB_MOT"] == 3.0
    assert rec["params_start"]["TLM_VIB_IMB"] == 25.0
    assert rec["params_end"]["TLM_VIB_IMB"] == 5.0
    assert rec["params_end"]["SIM_VIB_MOT_MAX"] == 120.0


def test_generate_draw_gives_whole_parameter_sets():
    start, end = fault_params("prop_damage", {"imbalance": 27.5, "mul": 0.85, "motor": 3},
                              35.0)
    assert start == {"SIM_VIB_MOT_MAX": 150.0, "TLM_VIB_IMB_MOT": 3.0, "TLM_VIB_IMB": 27.5,
                     "SIM_ENGINE_FAIL": 4.0, "SIM_ENGINE_MUL": 0.85}
    assert end == {"SIM_VIB_MOT_MAX": 0.0, "TLM_VIB_IMB_MOT": 0.0, "TLM_VIB_IMB": 0.0,
                   "SIM_ENGINE_FAIL": 1.0, "SIM_ENGINE_MUL": 1.0}
    Fault("prop_damage", 10, 20, params_start=start, params_end=end)  # a valid fault


def test_generate_draws_every_motor_of_a_quad():
    from tlm_process.generate.scenario import magnitude_knobs

    knob = magnitude_knobs()["prop_damage"]["motor"]
    assert knob.how == "choice" and list(knob.default) == [1, 2, 3, 4]
    assert set(knob.limits) == set(range(1, 9))


def test_damage_on_another_motor():
    """The draw's motor 3: its output works harder (its thrust is down), the others do not,
    and the fault's signature reads that motor's excess."""
    start, end = fault_params("prop_damage", {"imbalance": 30.0, "mul": 0.85, "motor": 3},
                              35.0)
    log = fly(1, faults=FaultSchedule([Fault("prop_damage", T0, T1, params_start=start,
                                             params_end=end)]), seed=3)
    rcou = log.tables["RCOU"]
    w = rcou[(rcou.TimeUS > (T0 + 5) * 1e6) & (rcou.TimeUS < T1 * 1e6)]
    out = w[["C1", "C2", "C3", "C4"]].to_numpy(float)
    excess = (out - out.mean(axis=1, keepdims=True)).mean(axis=0)
    assert excess[2] > 40.0 and excess[2] == excess.max()
    sig = fault_signature(log.tables, log.faults[0])
    assert sig["rcou_excess_in_us"] == pytest.approx(excess[2], abs=5.0)
    assert sig["vibexy_in"] > 2.0


def test_changes_at_one_instant_are_one_step():
    """An imbalance set before its motor and rotor frequency at the same instant is one
    consistent step; the same changes a second apart leave an imbalance without a motor,
    which is refused."""
    p = Params()
    rows = build_schedule(p, [(10.0, "TLM_VIB_IMB", 20.0), (10.0, "TLM_VIB_IMB_MOT", 1.0),
                              (10.0, "SIM_VIB_MOT_MAX", 150.0)])
    assert len(rows) and np.all(rows[:, 0] == 10_000_000)
    with pytest.raises(ParamError, match="TLM_VIB_IMB needs"):
        build_schedule(p, [(10.0, "TLM_VIB_IMB", 20.0), (11.0, "TLM_VIB_IMB_MOT", 1.0),
                           (11.0, "SIM_VIB_MOT_MAX", 150.0)])
    with pytest.raises(ParamError, match="TLM_VIB_IMB needs"):
        build_schedule(p, [(10.0, "TLM_VIB_IMB", 20.0), (10.0, "TLM_VIB_IMB_MOT", 1.0)])
