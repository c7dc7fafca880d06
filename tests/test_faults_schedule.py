"""Fault types, fault schedules (dict/file/shorthand forms, validation, the paper's sequence,
parameter changes), paper-era parameter aliases and the Eq. 3 satellite jitter. No flights."""

from __future__ import annotations

import json
import math
import pickle
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.conftest import REFERENCE, reference_path
from tlm_sim.faults import (
    FAULT_TYPES,
    Fault,
    FaultSchedule,
    FaultScheduleError,
    ParamChange,
    Trigger,
    jitter_nsats,
)
from tlm_sim.faults.satellites import (
    DEFAULT_MU,
    FAULT_SATS,
    NORMAL_SATS,
    satellite_curve,
    satellite_weights,
)
from tlm_sim.faults.schedule import PAPER_GAP_S, PAPER_HOLD_S, PAPER_ORDER
from tlm_sim.params import (
    ALIASES,
    PARAM_INFO,
    ParamError,
    Params,
    UnknownParamError,
    UnmodelledParamError,
    UnmodelledParamWarning,
    is_modelled,
)

SIDECARS = sorted(REFERENCE.glob("*.json"))


def _sidecar_param(path):
    """A sidecar as a test parameter, named after its flight."""
    return pytest.param(path, id=path.stem)


def one_line_error(fn, *args, match: str | None = None, **kw) -> FaultScheduleError:
    """Call ``fn``; assert it raises a FaultScheduleError with a one-line message."""
    with pytest.raises(FaultScheduleError, match=match) as info:
        fn(*args, **kw)
    msg = str(info.value)
    assert msg and "\n" not in msg and msg == msg.strip()
    return info.value


# ---------------------------------------------------------------------------------------------
# fault types
# ---------------------------------------------------------------------------------------------

def test_fault_types_and_their_stable_labels():
    assert list(FAULT_TYPES) == ["gps", "accel", "engine", "rc", "gyro", "baro", "compass",
                                 "gps_glitch", "motor_partial", "vibration", "battery",
                                 "gps_jam", "accel_samples", "prop_damage"]
    assert [t.label for t in FAULT_TYPES.values()] == list(range(1, 15))
    assert dict(FAULT_TYPES["gps"].params_start) == {"SIM_GPS1_ENABLE": 0}
    assert dict(FAULT_TYPES["gps"].params_end) == {"SIM_GPS1_ENABLE": 1}
    assert dict(FAULT_TYPES["accel"].params_start) == {"SIM_ACCEL1_FAIL": 1, "SIM_ACCEL2_FAIL": 1}
    assert dict(FAULT_TYPES["accel"].params_end) == {"SIM_ACCEL1_FAIL": 0, "SIM_ACCEL2_FAIL": 0}
    assert dict(FAULT_TYPES["engine"].params_start) == {"SIM_ENGINE_MUL": 0}
    assert dict(FAULT_TYPES["engine"].params_end) == {"SIM_ENGINE_MUL": 1}
    assert dict(FAULT_TYPES["rc"].params_start) == {"SIM_RC_FAIL": 1}
    assert dict(FAULT_TYPES["rc"].params_end) == {"SIM_RC_FAIL": 0}
    with pytest.raises(TypeError):
        FAULT_TYPES["gps"].params_start["SIM_GPS1_ENABLE"] = 1  # type: ignore[index]


def test_fault_type_params_are_valid_and_end_restores_defaults():
    """Every fault parameter is a tlm parameter, and clearing a fault restores tlm's default
    (the reference flights' healthy values)."""
    defaults = Params()
    for ftype in FAULT_TYPES.values():
        Params(dict(ftype.params_start))
        assert set(ftype.params_start) == set(ftype.params_end)
        for name, value in ftype.params_end.items():
            assert defaults[name] == value, name
            assert defaults[name] != ftype.params_start[name]


@pytest.mark.parametrize("sidecar", [_sidecar_param(p) for p in SIDECARS])
def test_fault_types_match_the_reference_sidecars(sidecar):
    faults = json.loads(reference_path(sidecar.name).read_text())["faults"]
    for rec in faults:
        ftype = FAULT_TYPES[rec["type"]]
        assert ftype.label == rec["label"]
        assert dict(ftype.params_start) == rec["params_start"]
        assert dict(ftype.params_end) == rec["params_end"]


def test_paper_constants_match_the_reference_combined_flight():
    """The combined reference flight's planned gaps/holds lie in PAPER_GAP_S / PAPER_HOLD_S,
    in PAPER_ORDER, and its logged windows are consecutive (no overlap)."""
    side = json.loads(reference_path("combined_s21.json").read_text())
    plan = side["fault_schedule"]
    assert tuple(p["type"] for p in plan) == PAPER_ORDER
    for p in plan:
        assert PAPER_GAP_S[0] <= p["at"] <= PAPER_GAP_S[1]
        assert PAPER_HOLD_S[0] <= p["hold"] <= PAPER_HOLD_S[1]
    windows = [(f["start_time_us"], f["end_time_us"]) for f in side["faults"]]
    assert all(a < b for a, b in windows)
    assert all(windows[i][1] < windows[i + 1][0] for i in range(len(windows) - 1))


# ---------------------------------------------------------------------------------------------
# triggers
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize(("text", "kind", "value"), [
    (60, "time", 60.0), (60.5, "time", 60.5), (np.float64(7.25), "time", 7.25),
    (np.int64(3), "time", 3.0), (0, "time", 0.0), ("60", "time", 60.0), ("60.5s", "time", 60.5),
    (" 12 s ", "time", 12.0), (".5", "time", 0.5), ("1e2", "time", 100.0),
    ("wp40", "wp", 40.0), ("WP7", "wp", 7.0), (" wp 3 ", "wp", 3.0),
])
def test_trigger_parse(text, kind, value):
    t = Trigger.parse(text)
    assert (t.kind, t.value) == (kind, value) and isinstance(t.value, float)
    assert Trigger.parse(t) is t


@pytest.mark.parametrize(("bad", "match"), [
    (-1, "negative"), (float("nan"), "not finite"), (float("inf"), "not finite"),
    ("1e999", "not finite"), ("wp0", "not a waypoint number"), ("wp-3", "not a time"),
    ("wp2.5", "not a time"), ("abc", "not a time"), ("", "not a time"), (True, "bool"),
    (None, "NoneType"), ([1], "list"), ("-5", "not a time"),
])
def test_trigger_parse_errors(bad, match):
    err = one_line_error(Trigger.parse, bad, "start", match=match)
    assert str(err).startswith("start ")


def test_trigger_direct_construction_and_text():
    assert Trigger("time", 60) == Trigger("time", 60.0) == Trigger.parse("60s")
    assert Trigger("wp", 40) != Trigger("time", 40)
    assert hash(Trigger("wp", 4)) == hash(Trigger("wp", 4.0))
    assert str(Trigger("time", 60)) == "60 s" and str(Trigger("time", 60.25)) == "60.25 s"
    assert str(Trigger("wp", 40)) == "wp40"
    assert Trigger("time", 60.0).to_value() == 60 and isinstance(
        Trigger("time", 60.0).to_value(), int)
    assert Trigger("time", 60.5).to_value() == 60.5
    assert Trigger("wp", 40).to_value() == "wp40"
    assert Trigger("wp", 1).comparable(Trigger("wp", 9))
    assert not Trigger("wp", 1).comparable(Trigger("time", 9))
    one_line_error(Trigger, "distance", 5, match="kind 'distance'")
    one_line_error(Trigger, "wp", 1.5, match="waypoint 1.5 is not")
    one_line_error(Trigger, "wp", 0, match="waypoint 0 is not")
    one_line_error(Trigger, "time", -0.1, match="negative")
    one_line_error(Trigger, "time", "60", match="not a number")


# ---------------------------------------------------------------------------------------------
# faults
# ---------------------------------------------------------------------------------------------

def test_fault_defaults_and_coercion():
    f = Fault("GPS ", 60, "110s")
    assert f.type == "gps" and f.label == 1 and f.fault_type is FAULT_TYPES["gps"]
    assert f.start == Trigger("time", 60) and f.end == Trigger("time", 110)
    assert dict(f.params_start) == {"SIM_GPS1_ENABLE": 0}
    assert dict(f.params_end) == {"SIM_GPS1_ENABLE": 1}
    same = Fault("gps", Trigger("time", 60.0), Trigger("time", 110.0),
                 params_start={"SIM_GPS1_ENABLE": 0})
    assert f == same and hash(f) == hash(same)
    assert len({f, same}) == 1
    assert Fault("rc", "wp5").end is None
    assert [Fault(n, 1, 2).label for n in FAULT_TYPES] == list(range(1, 15))
    with pytest.raises(TypeError):
        f.params_start["SIM_GPS1_ENABLE"] = 1  # type: ignore[index]
    with pytest.raises(AttributeError):
        f.start = Trigger("time", 1)  # type: ignore[misc]


def test_fault_param_overrides():
    one = Fault("accel", 10, 20, params_start={"SIM_ACCEL1_FAIL": 1})
    assert dict(one.params_start) == {"SIM_ACCEL1_FAIL": 1}
    assert dict(one.params_end) == {"SIM_ACCEL1_FAIL": 0}  # clears only what it set
    custom = Fault("accel", 10, 20, params_start={"SIM_ACCEL2_FAIL": -9.81},
                   params_end={"SIM_ACCEL2_FAIL": 0.5})
    assert dict(custom.params_start) == {"SIM_ACCEL2_FAIL": -9.81}
    assert dict(custom.params_end) == {"SIM_ACCEL2_FAIL": 0.5}
    noisy = Fault("gps", 10, 20, params_start={"SIM_GPS1_NOISE": 5},
                  params_end={"SIM_GPS1_NOISE": 0})
    assert dict(noisy.params_end) == {"SIM_GPS1_NOISE": 0}
    held = Fault("gps", 10, params_start={"SIM_GPS1_NOISE": 5})  # no end: none needed
    assert held.end is None


def test_fault_paper_names_come_out_canonical():
    f = Fault("gps", 60, 110, params_start={"SIM_GPS_DISABLE": 1},
              params_end={"SIM_GPS_DISABLE": 0})
    assert dict(f.params_start) == {"SIM_GPS1_ENABLE": 0.0}
    assert dict(f.params_end) == {"SIM_GPS1_ENABLE": 1.0}
    assert f == Fault("gps", 60, 110)
    g = Fault("gps", 60, 110, params_start={"SIM_GPS_NUMSATS": 4},
              params_end={"SIM_GPS_NUMSATS": 10})
    assert dict(g.params_start) == {"SIM_GPS1_NUMSATS": 4}
    assert all(c.name == "SIM_GPS1_NUMSATS" for c in FaultSchedule((g,)).param_changes())


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"type": "gsp", "start": 1}, r"unknown fault type 'gsp' \(did you mean 'gps'\?\)"),
    ({"type": "enigne", "start": 1}, "did you mean 'engine'"),
    ({"type": "wind", "start": 1}, "unknown fault type 'wind'; known: gps, accel"),
    ({"type": 3, "start": 1}, "not a string"),
    ({"type": "engine", "start": 120, "end": 90},
     r"^fault \(engine\): end 90 s is before start 120 s$"),
    ({"type": "engine", "start": 120, "end": 120}, "end 120 s is at start 120 s"),
    ({"type": "engine", "start": "wp48", "end": "wp40"}, "end wp40 is before start wp48"),
    ({"type": "rc", "start": "soon"}, r"fault \(rc\): start 'soon' is not a time"),
    ({"type": "rc", "start": 5, "end": float("nan")}, "end time nan s is not finite"),
    ({"type": "gps", "start": 1, "end": 2, "params_start": {"SIM_GPS_ENABLE": 0}},
     "params_start: unknown parameter 'SIM_GPS_ENABLE'"),
    ({"type": "rc", "start": 1, "end": 2, "params_start": {"SIM_RC_FAIL": 5}},
     r"params_start: SIM_RC_FAIL = 5 is out of range \[0, 2\]"),
    ({"type": "rc", "start": 1, "end": 2, "params_end": {"SIM_RC_FAIL": float("inf")}},
     "params_end: SIM_RC_FAIL = inf is not finite"),
    ({"type": "rc", "start": 1, "end": 2, "params_start": {"SIM_RC_FAIL": "x"}},
     "'x' is not a number"),
    ({"type": "rc", "start": 1, "params_start": {}}, "params_start is empty"),
    ({"type": "rc", "start": 1, "params_start": [("SIM_RC_FAIL", 1)]},
     "params_start must be a mapping"),
    ({"type": "rc", "start": 1, "params_end": {"SIM_RC_FAIL": 0}},
     "params_end is given but the fault has no end"),
    ({"type": "gps", "start": 1, "end": 2, "params_start": {"SIM_GPS1_NOISE": 5}},
     "give params_end: a gps fault does not know how to clear SIM_GPS1_NOISE"),
    ({"type": "gps", "start": 1, "end": 2,
      "params_start": {"SIM_GPS1_ENABLE": 0, "SIM_GPS_DISABLE": 1}},
     "params_start sets SIM_GPS1_ENABLE twice"),
])
def test_fault_errors(kwargs, match):
    one_line_error(Fault, match=match, **kwargs)


def test_fault_mixed_kinds_are_not_compared():
    f = Fault("gps", "wp10", 5)  # ends at 5 s or at wp10: not comparable, so accepted
    assert f.start.kind == "wp" and f.end == Trigger("time", 5)


def test_fault_str_is_one_line():
    assert str(Fault("accel", 120, 150)) == (
        "accel (label 2): 120 s -> 150 s; start SIM_ACCEL1_FAIL=1, SIM_ACCEL2_FAIL=1; "
        "end SIM_ACCEL1_FAIL=0, SIM_ACCEL2_FAIL=0")
    assert str(Fault("rc", "wp12")) == "rc (label 4): wp12 -> end of flight; start SIM_RC_FAIL=1"


# ---------------------------------------------------------------------------------------------
# schedule: construction, validation, order
# ---------------------------------------------------------------------------------------------

def test_schedule_container():
    s = FaultSchedule((Fault("gps", 60, 110), Fault("rc", 200)))
    assert len(s) == 2 and list(s) == list(s.faults) and s[1].type == "rc"
    assert FaultSchedule([Fault("gps", 1, 2)]).faults == (Fault("gps", 1, 2),)  # list -> tuple
    assert len(FaultSchedule()) == 0 and str(FaultSchedule()) == "no faults"
    assert FaultSchedule().param_changes() == []
    lines = str(s).splitlines()
    assert len(lines) == 2 and lines[0].startswith("0 gps (label 1): 60 s -> 110 s")
    assert lines[1].startswith("1 rc (label 4): 200 s -> end of flight")
    assert hash(s) == hash(FaultSchedule((Fault("gps", 60, 110), Fault("rc", 200))))


@pytest.mark.parametrize(("faults", "match"), [
    ("gps:1-2", "faults must be a sequence of Fault, got str"),
    (Fault("gps", 1, 2), "got Fault"),
    ([Fault("gps", 1, 2), {"fault": "rc"}], r"^fault 2: is a dict, not a Fault$"),
])
def test_schedule_construction_errors(faults, match):
    one_line_error(FaultSchedule, faults, match=match)


@pytest.mark.parametrize(("specs", "match"), [
    (["gps:60-110", "rc:100-120"],
     r"^fault 2 \(rc\): start 100 s is before the end 110 s of fault 1 \(gps\); "
     "faults must not overlap$"),
    (["gps:60-110", "rc:10-20"],
     r"fault 2 \(rc\): start 10 s is before the start 60 s of fault 1 \(gps\); list faults in "
     "the order they happen"),
    (["engine:wp40-wp48", "gps:wp45-wp50"],
     r"fault 2 \(gps\): start wp45 is before the end wp48 of fault 1 \(engine\); "
     "faults must not overlap"),
    (["gps:wp10-140", "rc:130-150"], r"fault 2 \(rc\): start 130 s is before the end 140 s"),
    (["gps:60-wp20", "rc:wp5-200"],
     r"fault 2 \(rc\): start wp5 is before the end wp20 of fault 1 \(gps\)"),
    (["gps:60-wp20", "rc:wp30-50"],
     r"fault 2 \(rc\): end 50 s is before the start 60 s of fault 1 \(gps\); list faults"),
    (["gps:100-110", "accel:wp5-wp6", "rc:50-60"],
     r"fault 3 \(rc\): start 50 s is before the start 100 s of fault 1 \(gps\)"),
    (["gps:60-", "rc:100-120"],
     r"^fault 1 \(gps\): has no end \(held until the flight ends\) but fault 2 \(rc\) comes "
     "after it"),
])
def test_schedule_order_errors(specs, match):
    one_line_error(FaultSchedule.from_shorthand, specs, match=match)


def test_schedule_boundaries_may_touch():
    s = FaultSchedule.from_shorthand(["gps:60-110", "rc:110-120", "engine:wp3-wp5",
                                      "accel:wp5-wp9"])
    assert [c.edge for c in s.param_changes()][:3] == ["start", "end", "start"]


def test_validate_bounds():
    s = FaultSchedule.from_shorthand(["gps:wp3-wp40", "rc:200-300"])
    s.validate()
    s.validate(n_waypoints=40, max_time_s=300)
    s.validate(n_waypoints=np.int64(90), max_time_s=np.float64(1e3))
    one_line_error(s.validate, n_waypoints=39,
                   match=r"^fault 1 \(gps\): end wp40 is beyond the mission's last waypoint "
                         r"wp39$")
    one_line_error(s.validate, max_time_s=250.5,
                   match=r"^fault 2 \(rc\): end 300 s is after the end of the flight "
                         r"\(250.5 s\)$")
    one_line_error(s.validate, n_waypoints=0, match="n_waypoints must be a whole number >= 1")
    one_line_error(s.validate, n_waypoints=True, match="n_waypoints")
    one_line_error(s.validate, n_waypoints=12.0, match="n_waypoints")
    one_line_error(s.validate, max_time_s=float("inf"), match="max_time_s must be a finite")
    one_line_error(s.validate, max_time_s=-1, match="max_time_s")
    one_line_error(s.validate, max_time_s=0, match="max_time_s")
    one_line_error(FaultSchedule.from_shorthand, ["gps:wp3-wp40"], n_waypoints=10,
                   match="wp40 is beyond")
    one_line_error(FaultSchedule.from_dict, [{"fault": "rc", "start": 600}], max_time_s=500,
                   match=r"fault 1 \(rc\): start 600 s is after")


# ---------------------------------------------------------------------------------------------
# param_changes
# ---------------------------------------------------------------------------------------------

def test_param_changes_order_and_fields():
    s = FaultSchedule.from_dict({"faults": [
        {"fault": "accel", "start": 60, "end": 90},
        {"fault": "engine", "start": "wp40", "end": "wp48"},
        {"fault": "gps", "start": 200, "params_start": {"SIM_GPS_DISABLE": 1}},
    ]})
    assert s.param_changes() == [
        ParamChange("time", 60.0, "SIM_ACCEL1_FAIL", 1.0, 0, "start"),
        ParamChange("time", 60.0, "SIM_ACCEL2_FAIL", 1.0, 0, "start"),
        ParamChange("time", 90.0, "SIM_ACCEL1_FAIL", 0.0, 0, "end"),
        ParamChange("time", 90.0, "SIM_ACCEL2_FAIL", 0.0, 0, "end"),
        ParamChange("wp", 40.0, "SIM_ENGINE_MUL", 0.0, 1, "start"),
        ParamChange("wp", 48.0, "SIM_ENGINE_MUL", 1.0, 1, "end"),
        ParamChange("time", 200.0, "SIM_GPS1_ENABLE", 0.0, 2, "start"),
    ]
    c = s.param_changes()[0]
    assert (c.kind, c.at, c.name, c.value, c.fault, c.edge) == (
        "time", 60.0, "SIM_ACCEL1_FAIL", 1.0, 0, "start")


def test_pickle_round_trip():
    """Schedules travel to worker processes (mappingproxy itself cannot be pickled)."""
    s = FaultSchedule.from_dict([{"fault": "accel", "start": 1, "end": 2,
                                  "params_start": {"SIM_ACCEL1_FAIL": 3}},
                                 {"fault": "rc", "start": "wp4"}])
    t = pickle.loads(pickle.dumps(s))
    assert t == s and t.param_changes() == s.param_changes()
    with pytest.raises(TypeError):
        t[0].params_start["SIM_ACCEL1_FAIL"] = 0  # type: ignore[index]
    ftype = pickle.loads(pickle.dumps(FAULT_TYPES["accel"]))
    assert ftype == FAULT_TYPES["accel"]
    with pytest.raises(TypeError):
        ftype.params_end["SIM_ACCEL1_FAIL"] = 1  # type: ignore[index]


def test_param_changes_apply_to_params():
    """Applying a schedule's changes in order to Params leaves every fault cleared."""
    s = FaultSchedule.paper(5)
    p = Params()
    for c in s.param_changes():
        p = p.updated({c.name: c.value})
    assert p == Params()


# ---------------------------------------------------------------------------------------------
# dict and file forms
# ---------------------------------------------------------------------------------------------

def test_dict_form_examples():
    d = {"faults": [{"fault": "gps", "start": 60, "end": 110},
                    {"fault": "engine", "start": "wp40", "end": "wp48"},
                    {"fault": "accel", "start": 120.5, "end": 150,
                     "params_start": {"SIM_ACCEL1_FAIL": 2}},
                    {"fault": "rc", "start": 200}]}
    s = FaultSchedule.from_dict(d)
    assert s.to_dict() == {"faults": [
        {"fault": "gps", "start": 60, "end": 110},
        {"fault": "engine", "start": "wp40", "end": "wp48"},
        {"fault": "accel", "start": 120.5, "end": 150, "params_start": {"SIM_ACCEL1_FAIL": 2}},
        {"fault": "rc", "start": 200}]}
    assert FaultSchedule.from_dict(d["faults"]) == s  # bare list
    assert FaultSchedule.from_dict({"faults": None}) == FaultSchedule()
    assert FaultSchedule.from_dict([]) == FaultSchedule()
    paper_names = FaultSchedule.from_dict([{"fault": "gps", "start": 1, "end": 2,
                                            "params_start": {"SIM_GPS_DISABLE": 1},
                                            "params_end": {"SIM_GPS_DISABLE": 0}}])
    assert paper_names.to_dict() == {"faults": [{"fault": "gps", "start": 1, "end": 2}]}
    custom_end = FaultSchedule.from_dict([{"fault": "engine", "start": 1, "end": 2,
                                           "params_end": {"SIM_ENGINE_MUL": 0.5}}])
    assert custom_end.to_dict()["faults"][0]["params_end"] == {"SIM_ENGINE_MUL": 0.5}


@pytest.mark.parametrize(("d", "match"), [
    ({"fault": [{"fault": "gps", "start": 1}]}, "unknown key 'fault' in a fault schedule"),
    ({}, "needs a 'faults' list"),
    ({"faults": {"fault": "gps"}}, "must be a list of fault mappings, got dict"),
    ({"faults": "gps:1-2"}, "got str"),
    (42, "got int"),
    ([{"fault": "gps", "strat": 1}],
     r"^fault 1 \(gps\): unknown key 'strat' \(did you mean 'start'\?\)"),
    ([{"fault": "gps", "start": 1, "end": 2}, {"fault": "rc"}],
     r"^fault 2 \(rc\): missing 'start'$"),
    ([{"start": 1}], r"^fault 1: missing 'fault'$"),
    ([{"fault": "gsp", "start": 1}], r"^fault 1: unknown fault type 'gsp'"),
    (["gps:1-2"], r"^fault 1: expected a mapping like"),
    ([{"fault": "gps", "start": 1, "end": 2}, {"fault": "engine", "start": 120, "end": 90}],
     r"^fault 2 \(engine\): end 90 s is before start 120 s$"),
    ([{"fault": "rc", "start": 1, "params_start": {"SIM_RCFAIL": 1}}],
     r"^fault 1 \(rc\): params_start: unknown parameter 'SIM_RCFAIL' \(did you mean "
     "SIM_RC_FAIL"),
])
def test_from_dict_errors(d, match):
    one_line_error(FaultSchedule.from_dict, d, match=match)


def test_files_round_trip_and_formats(tmp_path):
    s = FaultSchedule.from_shorthand(["gps:60.5-110", "engine:wp40-wp48", "rc:200-"])
    for suffix in (".json", ".yaml", ".yml", ".JSON"):
        path = s.to_file(tmp_path / f"sched{suffix}")
        assert FaultSchedule.from_file(path) == s
        assert FaultSchedule.from_file(str(path)) == s
    assert json.loads((tmp_path / "sched.json").read_text()) == s.to_dict()
    assert yaml.safe_load((tmp_path / "sched.yaml").read_text()) == s.to_dict()
    hand = tmp_path / "hand.yaml"
    hand.write_text("faults:\n  - fault: gps\n    start: 60\n    end: 110\n"
                    "  - {fault: engine, start: wp40, end: wp48}\n")
    assert FaultSchedule.from_file(hand) == FaultSchedule.from_shorthand(
        ["gps:60-110", "engine:wp40-wp48"])
    bare = tmp_path / "bare.json"
    bare.write_text('[{"fault": "rc", "start": "wp3"}]')
    assert FaultSchedule.from_file(bare) == FaultSchedule((Fault("rc", "wp3"),))


def test_file_errors(tmp_path):
    one_line_error(FaultSchedule.from_file, tmp_path / "x.txt",
                   match="unsupported fault schedule file type '.txt'")
    one_line_error(FaultSchedule().to_file, tmp_path / "x", match="file type '\\(none\\)'")
    one_line_error(FaultSchedule.from_file, tmp_path / "missing.json",
                   match="cannot read fault schedule .*missing.json")
    bad_json = tmp_path / "bad.json"
    bad_json.write_text('{"faults": [')
    one_line_error(FaultSchedule.from_file, bad_json, match=r"bad.json: invalid JSON: ")
    bad_yaml = tmp_path / "bad.yaml"
    bad_yaml.write_text("faults:\n  - fault: gps\n   start: [1\n")
    err = one_line_error(FaultSchedule.from_file, bad_yaml, match=r"bad.yaml: invalid YAML: ")
    assert err.source == str(bad_yaml)
    content = tmp_path / "content.yaml"
    content.write_text("faults:\n  - {fault: gps, start: 60, end: 110}\n"
                       "  - {fault: engine, start: 120, end: 90}\n")
    err = one_line_error(FaultSchedule.from_file, content)
    assert str(err) == f"{content}: fault 2 (engine): end 90 s is before start 120 s"
    assert (err.index, err.fault_type) == (1, "engine")
    assert err.reason == "end 90 s is before start 120 s"
    one_line_error(FaultSchedule.from_file, content.with_name("c2.yaml"), match="cannot read")
    bounds = tmp_path / "bounds.json"
    FaultSchedule.from_shorthand(["gps:wp3-wp40"]).to_file(bounds)
    one_line_error(FaultSchedule.from_file, bounds, n_waypoints=20,
                   match=r"bounds.json: fault 1 \(gps\): end wp40 is beyond")


# ---------------------------------------------------------------------------------------------
# shorthand
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize(("spec", "start", "end"), [
    ("gps:60-110", Trigger("time", 60), Trigger("time", 110)),
    ("engine:wp40-wp48", Trigger("wp", 40), Trigger("wp", 48)),
    ("rc:200-", Trigger("time", 200), None),
    ("rc:200", Trigger("time", 200), None),
    ("accel:120+30", Trigger("time", 120), Trigger("time", 150)),
    ("accel:0.1+0.2", Trigger("time", 0.1), Trigger("time", 0.3)),
    ("gps:wp10-140", Trigger("wp", 10), Trigger("time", 140)),
    ("GPS:60.5s-wp12", Trigger("time", 60.5), Trigger("wp", 12)),
    ("engine : 10 - 20", Trigger("time", 10), Trigger("time", 20)),
])
def test_shorthand_forms(spec, start, end):
    (f,) = FaultSchedule.from_shorthand([spec])
    assert (f.start, f.end) == (start, end)


def test_shorthand_single_string():
    a = FaultSchedule.from_shorthand("gps:60-110, engine:wp40-wp48 rc:200-")
    b = FaultSchedule.from_shorthand(["gps:60-110", "engine:wp40-wp48", "rc:200-"])
    assert a == b and [f.type for f in a] == ["gps", "engine", "rc"]
    assert FaultSchedule.from_shorthand([]) == FaultSchedule.from_shorthand("") == FaultSchedule()


@pytest.mark.parametrize(("specs", "match"), [
    (["gps60-110"], r"^fault 1: cannot read 'gps60-110'; expected TYPE:START-END"),
    (["gps:60-110", "engine:"], r"^fault 2: cannot read 'engine:'"),
    (["gps:60--110"], "cannot read"),
    (["gsp:60-110"], r"^fault 1: unknown fault type 'gsp' \(did you mean 'gps'\?\)"),
    (["gps:soon-110"], r"^fault 1 \(gps\): start 'soon' is not a time"),
    (["gps:60-later"], r"^fault 1 \(gps\): end 'later' is not a time"),
    (["gps:wp0-wp4"], r"start waypoint 0 is not a waypoint number"),
    (["accel:wp10+30"], r"^fault 1 \(accel\): 'accel:wp10\+30': a duration \(\+\) needs a start "
                        "time in s, not wp10$"),
    (["accel:10+wp3"], r"duration 'wp3' is not a number of seconds"),
    (["accel:10+"], r"duration '' is not a number of seconds"),
    (["accel:10+0"], r"duration must be > 0 s"),
    (["accel:10-5"], r"^fault 1 \(accel\): end 5 s is before start 10 s$"),
    ([7], r"^fault 1: shorthand 7 is not a string"),
])
def test_shorthand_errors(specs, match):
    one_line_error(FaultSchedule.from_shorthand, specs, match=match)


# ---------------------------------------------------------------------------------------------
# the paper's sequence
# ---------------------------------------------------------------------------------------------

def check_paper(s: FaultSchedule, auto_start_s: float) -> None:
    assert tuple(f.type for f in s) == PAPER_ORDER
    assert [f.label for f in s] == [1, 2, 3, 4]
    prev_end = auto_start_s
    tol = 0.05 + 1e-9  # boundary times are rounded to 0.1 s
    for f in s:
        assert f.start.kind == "time" and f.end is not None and f.end.kind == "time"
        for t in (f.start.value, f.end.value):
            assert abs(t * 10 - round(t * 10)) < 1e-6  # on the 0.1 s grid
        assert PAPER_GAP_S[0] - tol <= f.start.value - prev_end <= PAPER_GAP_S[1] + tol
        assert PAPER_HOLD_S[0] - 1e-9 <= f.end.value - f.start.value <= PAPER_HOLD_S[1] + 1e-9
        prev_end = f.end.value


@given(seed=st.integers(0, 2**63 - 1),
       auto=st.one_of(st.just(20.0), st.floats(0, 600, allow_nan=False)))
def test_paper_sequence_properties(seed, auto):
    s = FaultSchedule.paper(seed, auto_start_s=auto)
    check_paper(s, auto)
    assert s == FaultSchedule.paper(seed, auto_start_s=auto)  # deterministic
    assert FaultSchedule.from_dict(s.to_dict()) == s


def test_paper_sequence_examples():
    s = FaultSchedule.paper(21)
    assert s == FaultSchedule.paper(21) and s != FaultSchedule.paper(22)
    check_paper(s, 20.0)
    assert FaultSchedule.paper(np.int64(21)) == s
    shifted = FaultSchedule.paper(21, auto_start_s=30.0)
    assert [round(f.start.value - 10, 1) for f in shifted] == [f.start.value for f in s]
    # over many seeds the draws cover their ranges (not a constant)
    gaps = [FaultSchedule.paper(k)[0].start.value - 20 for k in range(200)]
    assert min(gaps) < 16 and max(gaps) > 24
    for bad in (-1, 1.5, True, "3"):
        one_line_error(FaultSchedule.paper, bad, match="seed must be a whole number >= 0")
    for bad_t in (-1.0, float("nan"), float("inf")):
        one_line_error(FaultSchedule.paper, 1, auto_start_s=bad_t, match="auto_start_s")


# ---------------------------------------------------------------------------------------------
# property tests: random valid schedules round-trip
# ---------------------------------------------------------------------------------------------

@st.composite
def schedules(draw) -> FaultSchedule:
    """Random valid schedules: boundaries non-decreasing per kind, start < end per fault,
    times on a 0.1 s grid (so they also have a shorthand form), optional overrides."""
    n = draw(st.integers(0, 5))
    t, wp = 0, 1  # next allowed time [0.1 s units], next allowed waypoint
    faults = []
    for i in range(n):
        name = draw(st.sampled_from(list(FAULT_TYPES)))
        bounds = []
        last = i == n - 1
        has_end = not last or draw(st.booleans())
        for k in range(2 if has_end else 1):
            step = draw(st.integers(0 if k == 0 else 1, 5000))
            if draw(st.booleans()):
                t += step
                bounds.append(Trigger("time", t / 10))
            else:
                wp += step % 50 if k == 0 else max(1, step % 50)
                bounds.append(Trigger("wp", wp))
        if len(bounds) == 2 and bounds[0].kind == bounds[1].kind and \
                bounds[1].value <= bounds[0].value:
            continue  # defensive; the steps above make this unreachable
        kw = {}
        if name == "accel" and draw(st.booleans()):
            kw["params_start"] = {"SIM_ACCEL1_FAIL": draw(st.floats(-200, 200))}
        if name == "gps" and draw(st.booleans()):
            kw["params_start"] = {"SIM_GPS_DISABLE": 1}
        if name == "engine" and has_end and draw(st.booleans()):
            kw["params_end"] = {"SIM_ENGINE_MUL": draw(st.floats(0, 2))}
        faults.append(Fault(name, bounds[0], bounds[1] if has_end else None, **kw))
    return FaultSchedule(tuple(faults))


def to_shorthand(f: Fault) -> str:
    def txt(t: Trigger) -> str:
        return str(t).replace(" s", "")
    return f"{f.type}:{txt(f.start)}-{txt(f.end) if f.end is not None else ''}"


@given(schedules())
def test_random_schedules_round_trip_dict(s):
    d = s.to_dict()
    assert FaultSchedule.from_dict(d) == s
    assert FaultSchedule.from_dict(d["faults"]) == s
    assert FaultSchedule.from_dict(json.loads(json.dumps(d))) == s
    assert FaultSchedule.from_dict(yaml.safe_load(yaml.safe_dump(d))) == s
    assert len(str(s).splitlines()) == max(len(s), 1)
    changes = s.param_changes()
    assert [c.fault for c in changes] == sorted(c.fault for c in changes)
    for c in changes:
        assert c.name in Params() and c.name not in ALIASES
        assert c.kind == getattr(s[c.fault], c.edge).kind


@given(schedules())
@settings(max_examples=40, suppress_health_check=[HealthCheck.too_slow])
def test_random_schedules_round_trip_files(s):
    with tempfile.TemporaryDirectory() as tmp:
        for suffix in (".json", ".yaml"):
            path = s.to_file(Path(tmp) / f"s{suffix}")
            assert FaultSchedule.from_file(path) == s


@given(schedules())
def test_random_schedules_round_trip_shorthand(s):
    plain = FaultSchedule(tuple(Fault(f.type, f.start, f.end) for f in s))
    specs = [to_shorthand(f) for f in plain]
    assert FaultSchedule.from_shorthand(specs) == plain
    assert FaultSchedule.from_shorthand(",".join(specs)) == plain


json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-10, 300) | st.floats(allow_nan=True)
    | st.sampled_from(["gps", "rc", "wp3", "wp0", "60", "x", "start", "SIM_RC_FAIL"]),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(
        st.sampled_from(["fault", "start", "end", "params_start", "params_end", "faults",
                         "SIM_RC_FAIL", "SIM_GPS_DISABLE", "x"]), inner, max_size=4),
    max_leaves=12)


@given(json_values)
def test_from_dict_never_fails_otherwise(d):
    """Arbitrary input gives a schedule or a one-line FaultScheduleError, nothing else."""
    try:
        s = FaultSchedule.from_dict(d)
    except FaultScheduleError as exc:
        assert "\n" not in str(exc) and str(exc)
    else:
        assert FaultSchedule.from_dict(s.to_dict()) == s


# ---------------------------------------------------------------------------------------------
# paper-era parameter aliases (tlm_sim.params.ALIASES)
# ---------------------------------------------------------------------------------------------

def test_gps_disable_alias_inverts():
    assert Params({"SIM_GPS_DISABLE": 1})["SIM_GPS1_ENABLE"] == 0
    assert Params({"SIM_GPS_DISABLE": 0})["SIM_GPS1_ENABLE"] == 1
    assert Params({"SIM_GPS_DISABLE": 2})["SIM_GPS1_ENABLE"] == 0  # any non-zero disables
    with pytest.warns(UnmodelledParamWarning, match="SIM_GPS2_ENABLE=1"):  # GPS 2: not modelled
        assert Params.from_values({"SIM_GPS2_DISABLE": 0})["SIM_GPS2_ENABLE"] == 1
    p = Params({"SIM_GPS_DISABLE": 1})
    assert "SIM_GPS_DISABLE" not in p and p.changed() == {"SIM_GPS1_ENABLE": 0.0}
    assert p.updated(SIM_GPS_DISABLE=0) == Params()
    assert Params.from_parm_text("SIM_GPS_DISABLE 1\nSIM_GPS_HZ 10\n") == Params(
        {"SIM_GPS1_ENABLE": 0, "SIM_GPS1_HZ": 10})
    with pytest.raises(ParamError, match="SIM_GPS_DISABLE = nan is not finite"):
        Params({"SIM_GPS_DISABLE": float("nan")})


def test_aliases_are_well_formed():
    current = Params()
    for old, alias in ALIASES.items():
        assert alias.target in current, old
        assert old not in current, old  # an alias must not hide a current name
        assert old not in PARAM_INFO
        assert len(old) <= 16 and old.startswith(("SIM_", "GPS_", "ACRO_")), old
    targets = [a.target for a in ALIASES.values()]
    assert len(targets) == len(set(targets))
    # Copter 4.1's ACRO gains: x 45 deg/s (Copter's own conversion to 4.2's rates)
    assert Params({"ACRO_YAW_P": 4.5})["ACRO_Y_RATE"] == 202.5
    for name in ("SIM_GPS_HZ", "SIM_GPS_LAG_MS", "SIM_GPS_NUMSATS", "SIM_GPS_NOISE",
                 "SIM_ACC_RND", "SIM_GYR_RND", "SIM_ACC_BIAS_X", "SIM_GYR_SCALE_Z",
                 "SIM_GPS_GLITCH_Y"):
        assert name in ALIASES


@pytest.mark.parametrize("old", sorted(n for n, a in ALIASES.items()
                                       if "DISABLE" not in n and a.convert(3.0) == 3.0))
def test_renamed_aliases_keep_value_and_range(old):
    target = ALIASES[old].target
    info = PARAM_INFO.get(target)
    value = info.max if info is not None else 3.0
    with warnings.catch_warnings():  # a whole set may change a parameter tlm does not model
        warnings.simplefilter("ignore", UnmodelledParamWarning)
        assert Params.from_parm_text(f"{old} {value}\n")[target] == value
    if not is_modelled(target):  # ... but an explicit value is refused, under either name
        with pytest.raises(UnmodelledParamError, match=target):
            Params({old: value})
        return
    assert Params({old: value})[target] == value
    assert Params().updated({old: value}) == Params({target: value})
    if info is not None and math.isfinite(info.max) and info.max < 1e6:
        with pytest.raises(ParamError, match=target):
            Params({old: info.max + 1})


def test_unknown_names_still_fail():
    with pytest.raises(UnknownParamError):
        Params({"SIM_GPS_DISABLED": 1})


# ---------------------------------------------------------------------------------------------
# satellite jitter (paper Eq. 3)
# ---------------------------------------------------------------------------------------------

def test_satellite_curve_is_eq3():
    mu = 1.3
    x = np.arange(3, 11)
    f = satellite_curve(x, 10, mu)
    assert f[-1] == pytest.approx(10 / (math.sqrt(2 * math.pi) * mu))
    expected = 10 / (math.sqrt(2 * math.pi) * mu) * np.exp(-(((x - 10) / (2 * mu**2)) ** 2))
    np.testing.assert_allclose(f, expected, rtol=1e-14)


@pytest.mark.parametrize(("lo", "hi"), [NORMAL_SATS, FAULT_SATS, (5, 5)])
@pytest.mark.parametrize("mu", [0.3, 1.0, DEFAULT_MU, 4.0])
def test_satellite_weights(lo, hi, mu):
    w = satellite_weights(lo, hi, mu)
    assert w.shape == (hi - lo + 1,) and w.dtype == np.float64
    assert w.sum() == pytest.approx(1.0) and np.all(w >= 0)
    assert np.all(np.diff(w) >= 0)  # Eq. 3 peaks at Max
    f = satellite_curve(np.arange(lo, hi + 1), hi, mu)
    np.testing.assert_allclose(w, f / f.sum())


def test_satellite_weights_errors():
    with pytest.raises(ValueError, match="min_sats 9 is above max_sats 8"):
        satellite_weights(9, 8, 1.0)
    for bad in (0.0, -1.0, float("nan"), float("inf"), True):
        with pytest.raises(ValueError, match="mu must be"):
            satellite_weights(3, 10, bad)
    for lo, hi in ((-1, 5), (3, 256), (3.0, 10)):
        with pytest.raises(ValueError, match="must be a whole number in 0..255"):
            satellite_weights(lo, hi, 1.0)


STATUS = np.array([6] * 5000 + [1] * 5000 + [0, 2, 3, 4, 5], dtype=np.uint8)


def test_jitter_ranges_and_dtype():
    n = jitter_nsats(STATUS, seed=7)
    assert n.dtype == np.uint8 and n.shape == STATUS.shape
    normal, fault = n[STATUS >= 3], n[STATUS < 3]
    assert normal.min() >= 8 and normal.max() <= 20
    assert fault.min() >= 3 and fault.max() <= 10
    assert len(np.unique(normal)) >= 5 and len(np.unique(fault)) >= 4  # visibly jittered
    # the default mu puts most counts where the paper says real ones are (§3.3)
    assert np.mean((normal >= 15) & (normal <= 20)) > 0.88
    assert np.mean((fault >= 5) & (fault <= 10)) > 0.88
    w = satellite_weights(*NORMAL_SATS, DEFAULT_MU)
    assert normal.mean() == pytest.approx(np.dot(np.arange(8, 21), w), abs=0.15)


def test_jitter_status_threshold():
    st_ = np.repeat(np.arange(7), 400)
    n = jitter_nsats(st_, seed=1)
    for s in range(7):
        vals = n[st_ == s]
        if s >= 3:
            assert vals.min() >= 8 and vals.max() > 10
        else:
            assert vals.max() <= 10 and vals.min() < 8


def test_jitter_deterministic_and_rowwise():
    a = jitter_nsats(STATUS, seed=3)
    np.testing.assert_array_equal(a, jitter_nsats(STATUS.astype(np.int64), seed=3))
    np.testing.assert_array_equal(a, jitter_nsats(STATUS.astype(np.float64), seed=3))
    assert not np.array_equal(a, jitter_nsats(STATUS, seed=4))
    flipped = STATUS.copy()
    flipped[100] = 1  # one row loses its fix: only that row changes
    b = jitter_nsats(flipped, seed=3)
    assert np.flatnonzero(a != b).tolist() in ([], [100])
    assert b[100] <= 10
    two_d = jitter_nsats(STATUS[:12].reshape(3, 4), seed=3)
    assert two_d.shape == (3, 4)
    np.testing.assert_array_equal(jitter_nsats(np.array([], dtype=np.uint8), 0),
                                  np.array([], dtype=np.uint8))


@given(seed=st.integers(0, 2**32))
@settings(max_examples=25)
def test_jitter_larger_mu_spreads_more(seed):
    status = np.array([6] * 3000 + [1] * 3000)
    prev = None
    for mu in (0.8, 1.5, 2.5):
        n = jitter_nsats(status, seed, mu=mu).astype(float)
        stds = (n[:3000].std(), n[3000:].std())
        if prev is not None:
            assert stds[0] > prev[0] and stds[1] > prev[1]
        prev = stds


def test_jitter_errors():
    with pytest.raises(ValueError, match="seed must be"):
        jitter_nsats(STATUS, seed=-1)
    with pytest.raises(ValueError, match="seed must be"):
        jitter_nsats(STATUS, seed=1.5)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="status must hold finite numbers"):
        jitter_nsats(np.array([6.0, np.nan]), seed=1)
    with pytest.raises(ValueError, match="status must hold finite numbers"):
        jitter_nsats(np.array(["6"]), seed=1)
    with pytest.raises(ValueError, match="mu must be"):
        jitter_nsats(STATUS, seed=1, mu=0)
