"""Issue 21: the autopilot's and the simulator's evidence messages (ARM, ORGN, LDET, MOTB, MISE,
SIM2, AUXF, ERR) and the flight text, against the SITL log of the same scenario (normal_s11),
``tlm crosscheck``'s message comparison, and pymavlink's tools on a tlm ``.bin``.

One cross-check of normal_s11 (its flight is ``r["_log"]``) serves every test here.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from tests.conftest import reference_path
from tlm_sim import ardupilot as AP
from tlm_sim.flightlog import LOGGED_MESSAGES, SCHEMAS, read_bin, read_schemas
from tlm_sim.flightlog.binwriter import message_types, msg_table, write_bin
from tlm_sim.flightlog.texts import text_kind
from tlm_sim.geo import latlon_to_ne

REF = "normal_s11"
NEW = ("ARM", "ORGN", "LDET", "MOTB", "MISE", "SIM2", "AUXF", "ERR", "ANG")


@pytest.fixture(scope="module")
def cc():
    from tlm_process.crosscheck.compare import crosscheck

    return crosscheck(reference_path(f"{REF}.bin"))


@pytest.fixture(scope="module")
def log(cc):
    return cc["_log"]


@pytest.fixture(scope="module")
def sitl():
    return read_bin(reference_path(f"{REF}.bin"),
                    types=[*NEW, "ATT", "EV", "MSG", "CMD", "MAG", "BAT", "SIM", "CTUN"])


@pytest.fixture(scope="module")
def written(log, tmp_path_factory):
    path = tmp_path_factory.mktemp("bin") / "flight.bin"
    write_bin(log, path)
    return path, read_bin(path)


def test_ang_is_att_row_for_row_with_the_loop_interval(written, sitl):
    """ANG (written from ATT) has SITL's layout and holds ATT's rows with Dt = 1/400 s; SITL's
    ANG also equals its ATT row for row."""
    t = written[1]
    ang, att = t["ANG"], t["ATT"]
    cols = ["TimeUS", "DesRoll", "Roll", "DesPitch", "Pitch", "DesYaw", "Yaw"]
    pd.testing.assert_frame_equal(ang[cols].reset_index(drop=True),
                                  att[cols].reset_index(drop=True), check_dtype=False)
    assert np.allclose(ang["Dt"], 0.0025)
    s_ang, s_att = sitl["ANG"], sitl["ATT"]
    assert np.array_equal(s_ang["TimeUS"], s_att["TimeUS"])
    assert np.allclose(s_ang["Roll"], s_att["Roll"])
    assert abs(float(np.median(s_ang["Dt"])) - 0.0025) < 2e-6  # SITL: its measured interval
    assert read_schemas(reference_path(f"{REF}.bin"))["ANG"].fmt == SCHEMAS["ANG"].fmt


def _ev_times(t: dict[str, pd.DataFrame], ev_id: int) -> list[int]:
    ev = t["EV"]
    return [int(x) for x in ev[ev.Id == ev_id].TimeUS]


# --- presence, layouts, rates -------------------------------------------------------------------


def test_every_message_is_written_with_sitl_layout(written):
    path, tables = written
    ref = read_schemas(reference_path(f"{REF}.bin"))
    mine = read_schemas(path)
    for name in NEW:
        assert len(tables[name]), name
        assert (mine[name].fmt, mine[name].columns, mine[name].units, mine[name].mults) == (
            ref[name].fmt, ref[name].columns, ref[name].units, ref[name].mults), name
        assert SCHEMAS[name].columns == ref[name].columns


def test_periodic_rates_within_ten_percent_of_sitl(log):
    rates = json.loads(reference_path(f"{REF}.json").read_text())["log_message_rates"]
    for name in ("MOTB", "SIM2"):
        t = log.tables[name]["TimeUS"].to_numpy(np.float64)
        hz = (len(t) - 1) / ((t[-1] - t[0]) * 1e-6)
        assert hz == pytest.approx(rates[name]["rate_hz"], rel=0.10), name
    # on-event messages: as many as SITL's (ARM 2, ORGN 4, MISE 92) or near it (LDET 127)
    for name in ("ARM", "ORGN", "MISE"):
        assert len(log.tables[name]) == rates[name]["count"], name
    assert 0.5 * rates["LDET"]["count"] <= len(log.tables["LDET"]) <= 1.5 * rates["LDET"]["count"]


def test_each_periodic_message_comes_at_its_schema_rate_the_rate_of_its_task(normal_flight):
    """A logged message's schema rate_hz is the rate of the task that writes it: one of the
    main loop's task rates (tlm_sim.ardupilot.TASK_RATES_HZ, whence the loop's divisors) or,
    for GPS/GPA, the GPS epochs' (SIM_GPS1_HZ); each instance's rows of a flight come one
    period apart (to a physics tick: the loop runs on the 833 us physics clock)."""
    from tlm_sim.flight import PHYSICS_DT_US

    task_rates = set(AP.TASK_RATES_HZ.values())
    for name in LOGGED_MESSAGES:
        sch = SCHEMAS[name]
        if sch.rate_hz == 0:
            continue
        writer = normal_flight.params["SIM_GPS1_HZ"] if name in ("GPS", "GPA") else (
            sch.rate_hz if sch.rate_hz in task_rates else None)
        assert writer == sch.rate_hz, f"{name}: no task at its {sch.rate_hz} Hz"
        df = normal_flight.tables[name]
        groups = df.groupby(sch.instance_field) if sch.instance_field else [(0, df)]
        for inst, rows in groups:
            period = float(np.median(np.diff(rows["TimeUS"].to_numpy(np.float64))))
            assert abs(period - 1e6 / sch.rate_hz) <= PHYSICS_DT_US, (name, inst, period)


def test_task_periods_are_whole_main_loop_ticks(monkeypatch):
    from tlm_sim.flight import TEN_HZ_LOG_TICKS, task_ticks

    assert TEN_HZ_LOG_TICKS * AP.TASK_RATES_HZ["ten_hz_logging_loop"] == AP.LOOP_RATE_HZ
    monkeypatch.setitem(AP.TASK_RATES_HZ, "three_hz_loop", 3)
    with pytest.raises(ValueError, match="does not divide"):
        task_ticks("three_hz_loop")


# --- values from the simulator ------------------------------------------------------------------


def test_arm_rows_are_the_arming_and_disarming_events_as_sitl_logs_them(log, sitl):
    arm, ev = log.tables["ARM"], log.tables["EV"]
    assert arm.TimeUS.tolist() == _ev_times(log.tables, 10) + _ev_times(log.tables, 11)
    cols = ["ArmState", "ArmChecks", "Forced", "Method"]
    # arming by MAVLink with ARMING_CHECK 1; disarming at the end of the mission (MISSIONEXIT)
    assert arm[cols].values.tolist() == sitl["ARM"][cols].values.tolist() == [
        [1, 1, 0, AP.ARM_METHOD_MAVLINK], [0, 0, 0, AP.ARM_METHOD_MISSIONEXIT]]
    assert int(ev[ev.Id == 18].TimeUS.iloc[0]) == int(arm.TimeUS.iloc[1])  # landed, disarmed


def test_radio_failsafe_rtl_disarms_as_landed():
    """RTL mode (the RC failsafe) lands and disarms by the land detector: Method 13, as SITL's
    rc_s15 and combined_s21."""
    from tlm_sim import fly

    log = fly(3, faults=[(120.0, "SIM_RC_FAIL", 1), (150.0, "SIM_RC_FAIL", 0)], seed=2)
    arm = log.tables["ARM"]
    assert arm.Method.tolist() == [AP.ARM_METHOD_MAVLINK, AP.ARM_METHOD_LANDED]
    assert arm.TimeUS.iloc[1] == _ev_times(log.tables, 11)[0]


def test_orgn_is_the_origin_and_the_home_at_arming(log, sitl):
    orgn, home = log.tables["ORGN"], log.mission.home
    assert orgn.Type.tolist() == sitl["ORGN"].Type.tolist() == [0, 1, 0, 1]
    first, armed = orgn.TimeUS.iloc[0], _ev_times(log.tables, 10)[0]
    assert (orgn.TimeUS.iloc[:2] == first).all() and (orgn.TimeUS.iloc[2:] == armed).all()
    assert _ev_times(log.tables, 25) == [first]  # EV SET_HOME with the first home
    origin = orgn[orgn.Type == 0]
    assert np.allclose(origin[["Lat", "Lng", "Alt"]].to_numpy(), np.array(home), atol=1e-7)
    # home at arming: the EKF position then (POS), within its logging resolution
    pos = log.tables["POS"]
    p = pos.iloc[int(np.searchsorted(pos.TimeUS, armed)) - 1]
    h = orgn.iloc[3]
    assert (h.Lat, h.Lng) == pytest.approx((p.Lat, p.Lng), abs=2e-7)
    assert h.Alt == pytest.approx(p.Alt, abs=0.02)


def test_ldet_follows_the_land_detector_and_the_landing(log):
    ld, tables = log.tables["LDET"], log.tables
    took_off = _ev_times(tables, 28)[0]
    landed = _ev_times(tables, 18)[0]
    flags = ld.Flags.to_numpy()
    t = ld.TimeUS.to_numpy()
    is_landed = (flags & AP.LDET_LANDED) != 0
    # landed before the takeoff (the disarmed / ground-idle state: flags 3), not in flight,
    # landed from the land-complete event on
    assert (flags[t < took_off] == AP.LDET_LANDED + AP.LDET_LANDED_MAYBE).all()
    assert not is_landed[(t >= took_off) & (t < landed)].any()
    assert is_landed[t >= landed].all() and t[is_landed].min() <= landed + 20000
    # the final second: every condition met (1776 = lower limit, mix at min, stationary, slow
    # descent, no rangefinder / weight-on-wheels), the count climbing 8 per 20 ms to 400
    final = ld[(ld.TimeUS > landed - 1.1e6) & (ld.TimeUS < landed)]
    assert ((final.Flags & 1776) == 1776).all()
    steps = np.diff(final.Count.to_numpy())
    assert np.median(steps) == 8 and final.Count.max() >= 390
    assert (np.diff(t // 1000) >= 20).all()  # at most 50 Hz (whole milliseconds, as SITL's)


def test_motb_is_the_mixers_battery_compensation(log, sitl):
    p = log.params
    m, bat, ctun = log.tables["MOTB"], log.tables["BAT"], log.tables["CTUN"]
    e = p["MOT_THST_EXPO"]
    assert np.allclose(m.LiftMax, m.BatVolt * (1 - e) + e * m.BatVolt**2, atol=1e-6)
    # the voltage ratio: a resting-voltage estimate over MOT_BAT_VOLT_MAX (the mixer's own sag
    # model, within 0.03 V of the battery monitor's VoltR: 0.0035 V in cruise)
    x = pd.merge_asof(m, bat[["TimeUS", "VoltR"]], on="TimeUS")
    ratio = x.VoltR.clip(p["MOT_BAT_VOLT_MIN"], p["MOT_BAT_VOLT_MAX"]) / p["MOT_BAT_VOLT_MAX"]
    assert np.abs(x.BatVolt - ratio).max() < 0.0025
    assert np.abs(x.BatVolt - ratio).median() < 0.0005
    assert (m.ThLimit == 1).all() and (m.FailFlags == 2).all()  # no boost, balanced
    y = pd.merge_asof(m, ctun[["TimeUS", "ThO"]], on="TimeUS")
    armed = (m.TimeUS > _ev_times(log.tables, 10)[0] + 5e6) & (
        m.TimeUS < _ev_times(log.tables, 11)[0] - 5e6)
    assert np.abs(y.ThrOut - y.ThO)[armed].max() < 0.02
    assert (m.ThrAvMx[armed] >= m.ThrOut[armed] - 1e-6).all()
    # cruise means as SITL's (LiftMax 0.9844, BatVolt 0.9905, ThrAvMx 0.372, ThrOut 0.365)
    s = sitl["MOTB"]
    for col, tol in (("LiftMax", 0.003), ("BatVolt", 0.003), ("ThrAvMx", 0.02),
                     ("ThrOut", 0.02)):
        assert m[col][armed].mean() == pytest.approx(s[col].iloc[600:4400].mean(), abs=tol), col


def test_mise_rows_are_the_mission_items_as_they_start(log, sitl, written):
    mise, cmd = log.tables["MISE"], written[1]["CMD"]
    fields = [c for c in SCHEMAS["MISE"].columns if c != "TimeUS"]
    items = cmd.set_index("CNum").loc[mise.CNum, [c for c in fields if c != "CNum"]]
    assert np.array_equal(mise[[c for c in fields if c != "CNum"]].to_numpy(), items.to_numpy())
    assert mise.CNum.tolist() == list(range(1, len(cmd)))  # takeoff ... RTL, once each
    # one row per waypoint reached, then the RTL item
    assert len(mise[mise.CId == 16]) == log.meta["waypoints_reached"]
    assert mise.CId.iloc[0] == 22 and mise.CId.iloc[-1] == 20
    # SITL's items, altitudes to the centimetre (ArduPilot stores them in whole centimetres)
    assert np.array_equal(mise[[f for f in fields if f != "Alt"]].to_numpy(float),
                          sitl["MISE"][[f for f in fields if f != "Alt"]].to_numpy(float))
    assert np.abs(mise.Alt.to_numpy() - sitl["MISE"].Alt.to_numpy()).max() <= 0.0101
    # when: the same time since arming as SITL's, to a few seconds over 6 minutes
    arm_tlm, arm_sitl = _ev_times(log.tables, 10)[0], _ev_times(sitl, 10)[0]
    dt = (mise.TimeUS.to_numpy() - arm_tlm) - (sitl["MISE"].TimeUS.to_numpy() - arm_sitl)
    assert np.abs(dt).max() * 1e-6 < 5.0


def test_sim2_is_the_simulators_truth(log, sitl):
    s2, sim = log.tables["SIM2"], log.tables["SIM"]
    home = log.mission.home
    same = s2[s2.TimeUS.isin(sim.TimeUS)].set_index("TimeUS").loc[sim.TimeUS]
    n, e = latlon_to_ne(sim.Lat.to_numpy(), sim.Lng.to_numpy(), home[0], home[1])
    assert np.abs(same.PN.to_numpy() - n).max() < 0.05
    assert np.abs(same.PE.to_numpy() - e).max() < 0.05
    assert np.abs(-same.PD.to_numpy() - (sim.Alt.to_numpy() - home[2])).max() < 0.01
    # the velocity is the position's rate
    t = s2.TimeUS.to_numpy() * 1e-6
    for p, v in (("PN", "VN"), ("PE", "VE"), ("PD", "VD")):
        rate = np.diff(s2[p].to_numpy()) / np.diff(t)
        mid = 0.5 * (s2[v].to_numpy()[1:] + s2[v].to_numpy()[:-1])
        assert np.percentile(np.abs(rate - mid), 99) < 0.05, p
    assert (s2.UFC == 0).all() and (s2.ASpdU == log.params["SIM_SPEEDUP"]).all()
    # the pitot airspeed in cruise, without wind: as SITL's (3.17 m/s against 3.41 over
    # ground, 3 % of the time zero when the flow comes from behind)
    arm, dis = _ev_times(log.tables, 10)[0], _ev_times(log.tables, 11)[0]
    cruise = s2[(s2.TimeUS > arm + 20e6) & (s2.TimeUS < dis - 60e6)]
    ref = sitl["SIM2"]
    ref_arm, ref_dis = _ev_times(sitl, 10)[0], _ev_times(sitl, 11)[0]
    ref_cruise = ref[(ref.TimeUS > ref_arm + 20e6) & (ref.TimeUS < ref_dis - 60e6)]
    assert cruise.As.mean() == pytest.approx(ref_cruise.As.mean(), rel=0.05)
    assert (cruise.As == 0).mean() == pytest.approx((ref_cruise.As == 0).mean(), abs=0.02)


def test_boot_err_is_the_first_compass_turning_healthy_as_in_sitl(log, sitl):
    for t in (log.tables, sitl):
        first = t["ERR"].iloc[0]
        assert (int(first.Subsys), int(first.ECode)) == (3, 0)
        assert int(first.TimeUS) <= int(t["MAG"].TimeUS.iloc[0])
    assert [(int(a), int(b)) for a, b in zip(log.tables["ERR"].Subsys, log.tables["ERR"].ECode,
                                             strict=True)] == [(3, 0)]


def test_auxf_and_its_text_are_the_rc7_switch_as_sitl_logs_them(written, sitl):
    tables = written[1]
    cols = ["function", "pos", "source", "index", "result"]
    assert tables["AUXF"][cols].values.tolist() == sitl["AUXF"][cols].values.tolist()
    msg = tables["MSG"]
    t = msg[msg.Message == "RC7: SaveWaypoint LOW"].TimeUS.tolist()
    assert t == tables["AUXF"].TimeUS.tolist()


# --- flight text --------------------------------------------------------------------------------


def test_mission_text_follows_the_mise_rows_as_sitl_writes_it(log, sitl):
    msg = msg_table(log)
    mission = msg[msg.Message.str.startswith(("Mission:", "Reached command"))]
    ref = sitl["MSG"][sitl["MSG"].Message.str.startswith(("Mission:", "Reached command"))]
    assert mission.Message.tolist() == ref.Message.tolist()
    starts = mission[mission.Message.str.startswith("Mission:")]
    assert starts.TimeUS.tolist() == log.tables["MISE"].TimeUS.tolist()
    reached = mission[mission.Message.str.startswith("Reached")]
    assert len(reached) == log.meta["waypoints_reached"]


def test_startup_and_event_texts_are_sitls(log, sitl):
    mine = [str(m) for m in msg_table(log).Message]
    for text in ("RC Protocol: UDP", "New mission", "New rally", "New fence", "Frame: QUAD/PLUS",
                 "Flight plan received", "Field Elevation Set: 584m", "Arming motors",
                 "Disarming motors", "RC7: SaveWaypoint LOW"):
        assert text in mine, text
        assert text in set(sitl["MSG"].Message), text
    hits = [m for m in mine if m.startswith("SIM Hit ground at")]
    assert len(hits) == 1 and re.fullmatch(r"SIM Hit ground at \d+\.\d{6} m/s", hits[0])


def test_text_kind_masks_numbers_and_ids():
    assert text_kind("Reached command #12") == "Reached command #N"
    assert text_kind("ArduCopter V4.7.0-dev (2598e9d4)") == "ArduCopter VN-dev (<id>)"
    assert text_kind("3d1219c7c4c5404aaa1f6d2a48adfda4") == "<id>"
    assert text_kind("Battery 1 is low 10.20V used 977 mAh") == "Battery N is low NV used N mAh"
    assert text_kind("EKF3 IMU0 is using GPS") == "EKFN IMUN is using GPS"


# --- tlm crosscheck: message types and MSG kinds -------------------------------------------------


def test_crosscheck_pins_what_only_sitl_writes_to_the_documented_list(cc, log):
    """Everything SITL's normal_s11 writes that tlm does not is documented
    (tlm_process.crosscheck.messages), and no documented entry is written by tlm by now: when
    tlm learns a message or a text, its entry goes (this test then names it as stale)."""
    from tlm_process.crosscheck.messages import SITL_ONLY_TEXT_KINDS, SITL_ONLY_TYPES

    m = cc["messages"]
    assert m["undocumented_types_only_sitl"] == []
    assert m["undocumented_text_kinds_only_sitl"] == []
    assert m["undocumented_text_kinds_only_tlm"] == []
    assert m["stale_types"] == [] and m["stale_text_kinds"] == []
    assert m["types_only_tlm"] == []
    assert set(m["types_only_sitl"]) <= set(SITL_ONLY_TYPES)
    assert set(m["text_kinds_only_sitl"]) <= set(SITL_ONLY_TEXT_KINDS)
    # the message types of this part of issue 21 are no longer missing
    assert not set(NEW) & set(m["types_only_sitl"])
    assert set(NEW) <= set(message_types(log))
    assert m["message_types"]["sitl"] == 65


def test_with_the_boot_phase_every_sitl_text_kind_but_bookkeeping_is_written():
    """With SITL's start-up flown (TLM_BOOT_PHASE 1) tlm writes every text kind of normal_s11
    but the firmware's git id, the instance id and the parameter-storage line; the entries
    documented as boot-phase-only are then exactly the ones tlm writes."""
    from tlm_process.crosscheck.compare import crosscheck
    from tlm_process.crosscheck.messages import _BOOT, SITL_ONLY_TEXT_KINDS

    m = crosscheck(reference_path(f"{REF}.bin"), params={"TLM_BOOT_PHASE": 1})["messages"]
    assert sorted(m["text_kinds_only_sitl"]) == ["<id>", "ArduCopter VN-dev (<id>)",
                                                 "Param space used: N/N"]
    boot_only = {k for k, why in SITL_ONLY_TEXT_KINDS.items() if why == _BOOT}
    assert set(m["stale_text_kinds"]) <= boot_only and m["stale_types"] == []
    assert {"Arm: Need Position Estimate", "PreArm: Need Position Estimate"} <= set(
        m["stale_text_kinds"])


def test_crosscheck_report_has_the_messages_section(cc):
    from tlm_process.crosscheck.compare import format_report, to_json

    text = format_report(cc)
    assert "## Messages and flight text" in text and "| `MAV` |" in text
    assert to_json(cc)["messages"]["types_only_tlm"] == []


# --- pymavlink's tools ---------------------------------------------------------------------------


def _tool(name: str, *args: str) -> str:
    r = subprocess.run([sys.executable, "-m", f"pymavlink.tools.{name}", *args],
                       capture_output=True, text=True, timeout=300, check=False)
    assert r.returncode == 0, r.stderr[-2000:]
    return r.stdout


def test_pymavlink_tools_read_a_tlm_bin_as_sitls(written, log):
    path = str(written[0])
    dump = _tool("mavlogdump", "--types", "ARM,ORGN,MISE,MOTB,SIM2,LDET,AUXF", path)
    lines = dump.splitlines()
    for name in ("ARM", "ORGN", "MISE", "MOTB", "SIM2", "LDET", "AUXF"):
        n = sum(f": {name} {{" in ln for ln in lines)
        assert n == len(written[1][name]), name
    assert re.search(r": ARM \{TimeUS : \d+, ArmState : 1, ArmChecks : 1, Forced : 0, "
                     r"Method : 1\}", dump)
    modes = _tool("mavflightmodes", path)
    names = re.findall(r"MAV\.flightmode=(\w+)", modes)
    assert names == ["STABILIZE", "GUIDED", "AUTO"]  # the MODE rows, as Copter modes
    ft = _tool("mavflighttime", path)
    ref = _tool("mavflighttime", str(reference_path(f"{REF}.bin")))

    def seconds(out: str) -> int:
        mm, ss = re.search(r"Total time in air: (\d+):(\d+)", out).groups()
        return int(mm) * 60 + int(ss)

    assert seconds(ft) == pytest.approx(seconds(ref), rel=0.10)


def test_tlm_crosscheck_param_flies_the_log_with_overrides(tmp_path, capsys):
    """``tlm crosscheck --param NAME=VALUE`` flies SITL's scenario with the override (recorded
    in the JSON); a malformed or unknown one is one line and exit 2 before any flying."""
    from tlm_process.cli import main

    log = str(reference_path(f"{REF}.bin"))
    assert main(["crosscheck", log, "--param", "TLM_BOOT_PHASE"]) == 2
    assert "--param expects NAME=VALUE" in capsys.readouterr().err
    assert main(["crosscheck", log, "--param", "NO_SUCH_PARAM=1"]) == 2
    assert "NO_SUCH_PARAM" in capsys.readouterr().err
    out = tmp_path / "r.json"
    assert main(["crosscheck", log, "--param", "tlm_boot_phase=1", "--json", str(out)]) in (0, 1)
    r = json.loads(out.read_text())
    assert r["scenario"]["overrides"] == {"TLM_BOOT_PHASE": 1.0}
    assert "PreArm: Need Position Estimate" in r["messages"]["stale_text_kinds"]
