"""Missions: Algorithm 1 + Savitzky-Golay against the reference sidecars, builtins, WPL files."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from tests.conftest import reference_path
from tlm_sim.geo import HOME_CMAC, latlon_to_ne, ne_to_latlon
from tlm_sim.mission import (
    BUILTIN_IDS,
    Mission,
    MissionError,
    allocate_intervals,
    builtin_mission,
    interpolate_waypoints,
    make_mission,
    random_loop,
    read_wpl,
    smooth_altitudes,
    write_wpl,
)

SIDECARS = ["normal_s11", "gps_s12", "accel_s13", "engine_s14", "rc_s15", "combined_s21"]
# The reference driver drew the loop and then the altitudes from one
# np.random.default_rng(seed); this many doubles of the stream went to the loop first
# (found by searching the stream for the stored raw altitudes).
ALT_STREAM_OFFSET = {
    "normal_s11": 348,
    "gps_s12": 73,
    "accel_s13": 1668,
    "engine_s14": 44,
    "rc_s15": 203,
    "combined_s21": 464,
}
LATLON_TOL = 1e-12  # deg (~0.1 um); 2 of the 540 reference lat values differ by 1 ulp


def _sidecar(name: str) -> dict:
    path = reference_path(f"{name}.json")
    return json.loads(path.read_text())["mission"]


# ----------------------------------------------------------------------------- golden
@pytest.mark.parametrize("name", SIDECARS)
def test_sidecar_latlon_reproduced(name):
    m = _sidecar(name)
    raw = np.array(m["raw_waypoints"])
    ref = np.array(m["waypoints"])
    assert raw.shape == (6, 2)
    for exact in (False, True):
        got = interpolate_waypoints(raw, m["n_waypoints"], exact_count=exact)
        assert got.shape == (m["n_waypoints"], 2)
        np.testing.assert_allclose(got, ref[:, :2], rtol=0, atol=LATLON_TOL)
    # the driver asked for 90 and got 89-91: rint(share of 89 intervals) per segment
    assert len(interpolate_waypoints(raw, 90)) == m["n_waypoints"]
    assert len(interpolate_waypoints(raw, 90, exact_count=True)) == 90


@pytest.mark.parametrize("name", SIDECARS)
def test_sidecar_altitudes_from_stored_raw(name):
    """Smoothing the stored (0.001 m) raw draws gives the alt column to within one 0.01 step."""
    m = _sidecar(name)
    ref = np.array(m["waypoints"])[:, 2]
    got = smooth_altitudes(np.array(m["altitudes_raw_m"]), 21, 3)
    assert np.all(np.abs(got - ref) <= 0.01 + 1e-9)
    assert np.count_nonzero(got != ref) <= 2
    np.testing.assert_array_equal(np.round(ref, 2), ref)  # rounded to 0.01 m


@pytest.mark.parametrize("name", SIDECARS)
def test_sidecar_whole_mission_from_seed(name):
    """Same generator stream as the driver: every column reproduced, altitudes bit-exact."""
    m = _sidecar(name)
    raw = np.array(m["raw_waypoints"])
    ref = np.array(m["waypoints"])
    rng = np.random.default_rng(m["seed"])
    rng.random(ALT_STREAM_OFFSET[name])
    mis = make_mission(raw, 90, rng=rng, seed=m["seed"])
    assert mis.n_waypoints == m["n_waypoints"]
    np.testing.assert_array_equal(np.round(mis.altitudes_raw, 3), m["altitudes_raw_m"])
    np.testing.assert_array_equal(mis.waypoints[:, 2], ref[:, 2])
    np.testing.assert_allclose(mis.waypoints[:, :2], ref[:, :2], rtol=0, atol=LATLON_TOL)
    assert abs(mis.path_length_m - m["path_length_m"]) <= 0.05 + 1e-9


@pytest.mark.parametrize("name", SIDECARS)
def test_from_sidecar(name):
    m = _sidecar(name)
    mis = Mission.from_sidecar(reference_path(f"{name}.json"))
    assert mis.name == name and mis.seed == m["seed"]
    assert mis.home == HOME_CMAC
    assert mis.savgol == (21, 3)
    assert mis.n_waypoints == m["n_waypoints"]
    np.testing.assert_array_equal(mis.waypoints, m["waypoints"])
    # path_length_m is the horizontal flat-earth length, printed to 0.1 m
    assert round(mis.path_length_m, 1) == pytest.approx(m["path_length_m"], abs=1e-9)
    assert mis.path_length_3d_m > mis.path_length_m
    # the first waypoint is home; takeoff goes to its altitude (README item 2)
    np.testing.assert_array_equal(mis.waypoints[0, :2], HOME_CMAC[:2])
    np.testing.assert_array_equal(mis.raw_waypoints[0], HOME_CMAC[:2])
    assert mis.takeoff_alt == m["waypoints"][0][2]
    ned = mis.ned()
    assert ned.shape == (m["n_waypoints"], 3)
    np.testing.assert_array_equal(ned[0], [0.0, 0.0, -m["waypoints"][0][2]])
    np.testing.assert_array_equal(ned[:, 2], -mis.waypoints[:, 2])
    assert np.hypot(ned[:, 0], ned[:, 1]).max() < 400.0  # "within about 400 m of home"


# ----------------------------------------------------------------- Algorithm 1 properties
@st.composite
def raw_polylines(draw):
    """2-8 raw points within 2 km of CMAC, consecutive points at least 1 m apart."""
    k = draw(st.integers(2, 8))
    ne = draw(
        st.lists(st.tuples(st.floats(-2000, 2000), st.floats(-2000, 2000)), min_size=k, max_size=k)
    )
    ne = np.array(ne)
    assume(np.all(np.hypot(*np.diff(ne, axis=0).T) > 1.0))
    lat, lon = ne_to_latlon(ne[:, 0], ne[:, 1], *HOME_CMAC[:2])
    return np.column_stack([lat, lon])


@settings(max_examples=150, deadline=None)
@given(raw=raw_polylines(), n=st.integers(2, 300), exact=st.booleans())
def test_algorithm1_properties(raw, n, exact):
    segs = len(raw) - 1
    assume(n - 1 >= segs)
    out = interpolate_waypoints(raw, n, exact_count=exact)
    # endpoints and every raw point present, in order, bit-exact
    np.testing.assert_array_equal(out[0], raw[0])
    np.testing.assert_array_equal(out[-1], raw[-1])
    idx = []
    for p in raw:
        hits = np.flatnonzero(np.all(out == p, axis=1))
        assert hits.size >= 1
        idx.append(int(hits[hits >= (idx[-1] if idx else 0)][0]))
    assert idx == sorted(idx) and idx[0] == 0 and idx[-1] == len(out) - 1
    # counts
    if exact:
        assert len(out) == n
    else:
        assert abs(len(out) - n) <= math.ceil(segs / 2) + segs  # rint error + min-1 rule
    # every point lies on its segment's straight line in (lat, lon) - the paper's
    # LineLon = k * LineLat + b - and the points are equally spaced along it
    for s in range(segs):
        a, b = out[idx[s]], out[idx[s + 1]]
        seg = out[idx[s] : idx[s + 1] + 1]
        d = b - a
        length = float(np.hypot(*d))
        rel = seg - a
        cross = (rel[:, 0] * d[1] - rel[:, 1] * d[0]) / length
        along = (rel @ d) / length
        assert np.abs(cross).max() < 1e-12  # deg
        assert along.min() > -1e-12 and along.max() < length + 1e-12
        steps = np.hypot(*np.diff(seg, axis=0).T)
        assert steps.max() - steps.min() < 1e-12


@settings(max_examples=100, deadline=None)
@given(
    lengths=st.lists(st.floats(1.0, 1000.0), min_size=1, max_size=10),
    n_int=st.integers(10, 400),
)
def test_allocation_proportional(lengths, n_int):
    lengths = np.array(lengths)
    assume(n_int >= len(lengths))
    share = lengths / lengths.sum() * n_int
    k_exact = allocate_intervals(lengths, n_int, exact_count=True)
    assert k_exact.sum() == n_int and np.all(k_exact >= 1)
    k_round = allocate_intervals(lengths, n_int)
    assert np.all(k_round >= 1)
    small = share < 0.5  # rint would give 0: the min-1 rule lifts these to 1
    np.testing.assert_array_equal(k_round[small], 1)
    np.testing.assert_array_equal(k_round[~small], np.rint(share[~small]))
    if np.all(share >= 1.0):  # no segment needs lifting: plain largest remainder
        assert np.all(np.abs(k_exact - share) < 1.0)
    else:  # lifted segments take from the others, never more than needed
        assert np.abs(k_exact - share).sum() <= 2 * np.count_nonzero(share < 1.0) + len(share)


def test_algorithm1_edge_cases():
    one = np.array([HOME_CMAC[:2]])
    np.testing.assert_array_equal(interpolate_waypoints(one, 90), one)
    dup = np.array([HOME_CMAC[:2], HOME_CMAC[:2], [-35.362, 149.166]])
    out = interpolate_waypoints(dup, 10, exact_count=True)
    assert len(out) == 10 and np.all(out[0] == dup[0]) and np.all(out[-1] == dup[-1])
    with pytest.raises(MissionError, match="same position"):
        interpolate_waypoints(np.array([HOME_CMAC[:2], HOME_CMAC[:2]]), 10)
    with pytest.raises(MissionError, match="n_waypoints"):
        interpolate_waypoints(dup, 1)
    with pytest.raises(MissionError, match="cannot keep"):
        interpolate_waypoints(np.array(random_loop(HOME_CMAC, 1)), 4, exact_count=True)
    with pytest.raises(MissionError, match="point 1 is not finite"):
        interpolate_waypoints(np.array([[0.0, 0.0], [np.nan, 1.0]]), 10)
    with pytest.raises(MissionError, match="shape"):
        interpolate_waypoints(np.zeros((3, 3)), 10)


def test_smooth_altitudes_behaviour():
    rng = np.random.default_rng(0)
    raw = rng.uniform(15, 25, 90)
    sm = smooth_altitudes(raw, 21, 3, decimals=None)
    assert np.std(np.diff(sm)) < 0.2 * np.std(np.diff(raw))  # much gentler (paper Fig. 4)
    assert abs(sm.mean() - raw.mean()) < 0.3
    # a cubic is reproduced exactly by a polyorder-3 Savitzky-Golay filter
    x = np.linspace(-1, 1, 50)
    cubic = 20 + 2 * x - 3 * x**2 + x**3
    np.testing.assert_allclose(smooth_altitudes(cubic, 21, 3, decimals=None), cubic, atol=1e-9)
    np.testing.assert_array_equal(smooth_altitudes(raw, 21, 3), np.round(sm, 2))
    # shorter than the window: the window shrinks; too short to fit: unsmoothed
    assert smooth_altitudes(raw[:8], 21, 3).shape == (8,)
    np.testing.assert_array_equal(smooth_altitudes(raw[:3], 21, 3, decimals=None), raw[:3])
    with pytest.raises(MissionError):
        smooth_altitudes(raw, 20, 3)


# --------------------------------------------------------------------------- generation
def test_random_loop_many_seeds():
    lengths = []
    for seed in range(300):
        raw = random_loop(HOME_CMAC, np.random.default_rng(seed))
        assert raw.shape == (6, 2)
        np.testing.assert_array_equal(raw[0], HOME_CMAC[:2])
        n, e = latlon_to_ne(raw[:, 0], raw[:, 1], *HOME_CMAC[:2])
        r = np.hypot(n, e)[1:]
        assert r.max() <= 400.0 and r.min() >= 80.0
        length = float(np.sum(np.hypot(np.diff(n), np.diff(e))))
        assert 1100.0 <= length <= 1300.0
        lengths.append(length)
    # the accepted lengths fill the window rather than hugging one end
    assert np.percentile(lengths, 10) < 1150 and np.percentile(lengths, 90) > 1250
    # deterministic in the seed, different across seeds
    np.testing.assert_array_equal(random_loop(HOME_CMAC, 5), random_loop(HOME_CMAC, 5))
    assert not np.array_equal(random_loop(HOME_CMAC, 5), random_loop(HOME_CMAC, 6))


def test_random_loop_impossible():
    with pytest.raises(MissionError, match="no loop"):
        random_loop(HOME_CMAC, 0, length_range_m=(5000.0, 6000.0), max_tries=50)


def test_make_mission_defaults():
    raw = random_loop(HOME_CMAC, 3)
    m = make_mission(raw, seed=3)
    assert 88 <= m.n_waypoints <= 92
    assert m.seed == 3 and m.savgol == (21, 3) and m.home == HOME_CMAC
    raw_alt = m.altitudes_raw
    assert raw_alt is not None and raw_alt.min() >= 15.0 and raw_alt.max() < 25.0
    np.testing.assert_array_equal(m.waypoints[:, 2], smooth_altitudes(raw_alt, 21, 3))
    np.testing.assert_array_equal(m.raw_waypoints, raw)
    assert 1100 <= m.path_length_m <= 1300
    assert make_mission(raw, seed=3) == m  # same seed, same mission
    assert make_mission(raw, seed=4) != m
    assert make_mission(raw, 60, exact_count=True, seed=3).n_waypoints == 60
    with pytest.raises(MissionError, match="alt_range"):
        make_mission(raw, alt_range=(25.0, 15.0))


# ----------------------------------------------------------------------------- builtins
BUILTIN_PINNED = {1: (90, 1260.4), 2: (90, 1245.2), 3: (90, 1283.5), 4: (90, 1205.8)}


def test_builtin_missions():
    assert BUILTIN_IDS == (1, 2, 3, 4)
    centroids = []
    for k in BUILTIN_IDS:
        m = builtin_mission(k)
        n_wp, length = BUILTIN_PINNED[k]
        assert m.n_waypoints == n_wp
        assert round(m.path_length_m, 1) == length
        assert 1100 <= m.path_length_m <= 1300
        assert m.name == f"builtin-{k}" and m.home == HOME_CMAC
        assert m.raw_waypoints.shape == (6, 2)
        np.testing.assert_array_equal(m.waypoints[0, :2], HOME_CMAC[:2])
        assert 15.0 <= m.waypoints[:, 2].min() and m.waypoints[:, 2].max() <= 25.0
        ned = m.ned()
        assert np.hypot(ned[:, 0], ned[:, 1]).max() <= 400.0
        centroids.append(ned[:, :2].mean(axis=0))
        assert builtin_mission(k) is m  # cached, immutable
    # four different loops: their centroids are at least 100 m apart pairwise
    c = np.array(centroids)
    dist = np.hypot(*(c[:, None, :] - c[None, :, :]).transpose(2, 0, 1))
    assert dist[np.triu_indices(4, 1)].min() > 100.0


@pytest.mark.parametrize("bad", [0, 5, -1, "1", 1.0, True])
def test_builtin_unknown(bad):
    with pytest.raises(MissionError, match="no built-in mission"):
        builtin_mission(bad)


# ------------------------------------------------------------------------------ Mission
def _wp(n=5, home=HOME_CMAC):
    lat, lon = ne_to_latlon(np.arange(n) * 10.0, np.zeros(n), *home[:2])
    return np.column_stack([lat, lon, np.full(n, 20.0)])


def test_mission_frozen_and_readonly():
    m = Mission(_wp())
    with pytest.raises(dataclasses.FrozenInstanceError):
        m.name = "x"  # type: ignore[misc]
    with pytest.raises(ValueError):
        m.waypoints[0, 0] = 0.0
    assert m.takeoff_alt == 20.0 and m.raw_waypoints.shape == (5, 2)
    assert m.path_length_m == pytest.approx(40.0, abs=1e-9)
    assert dataclasses.replace(m, takeoff_alt=5.0).takeoff_alt == 5.0


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda w: w.__setitem__((17, 0), np.nan), "waypoint 17 has NaN latitude"),
        (lambda w: w.__setitem__((3, 1), np.inf), "waypoint 3 has infinite longitude"),
        (lambda w: w.__setitem__((4, 2), np.nan), "waypoint 4 has NaN altitude"),
        (lambda w: w.__setitem__((2, 0), 95.0), "waypoint 2 has latitude 95"),
        (lambda w: w.__setitem__((6, 1), 181.0), "waypoint 6 has longitude 181"),
        (lambda w: w.__setitem__((8, 2), -0.5), "waypoint 8 has altitude -0.5 m"),
        (lambda w: w.__setitem__((9, 2), 10_001.0), "waypoint 9 has altitude 10001 m"),
        (lambda w: w.__setitem__((11, 0), HOME_CMAC[0] + 0.5), "waypoint 11 is 55659 m from home"),
    ],
)
def test_mission_error_names_culprit(mutate, message):
    w = _wp(20)
    mutate(w)
    with pytest.raises(MissionError, match=message):
        Mission(w)


def test_mission_error_other_cases():
    assert issubclass(MissionError, ValueError)
    with pytest.raises(MissionError, match="no waypoints"):
        Mission(np.zeros((0, 3)))
    with pytest.raises(MissionError, match=r"shape \(N, 3\)"):
        Mission(np.zeros((4, 2)))
    with pytest.raises(MissionError, match="home has NaN latitude"):
        Mission(_wp(), home=(np.nan, 149.0, 584.0))
    with pytest.raises(MissionError, match="altitudes_raw must have shape"):
        Mission(_wp(5), altitudes_raw=np.zeros(4))
    with pytest.raises(MissionError, match="savgol"):
        Mission(_wp(), savgol=(20, 3))
    with pytest.raises(MissionError, match="takeoff altitude"):
        Mission(_wp(), takeoff_alt=-1.0)
    with pytest.raises(MissionError, match="raw waypoint 1 has NaN latitude"):
        Mission(_wp(), raw_waypoints=np.array([HOME_CMAC[:2], [np.nan, 149.0]]))


# ---------------------------------------------------------------------------------- WPL
def _missions_for_wpl():
    out = [builtin_mission(k) for k in BUILTIN_IDS]
    out.append(make_mission(random_loop(HOME_CMAC, 42), seed=42))
    zurich = (47.397742, 8.545594, 488.0)
    out.append(Mission(_wp(7, zurich), home=zurich, takeoff_alt=7.25))
    return out


@pytest.mark.parametrize("idx", range(6))
def test_wpl_round_trip_exact(tmp_path, idx):
    m = _missions_for_wpl()[idx]
    p = write_wpl(m, tmp_path / "m.waypoints")
    back = read_wpl(p)
    assert back.home == m.home
    np.testing.assert_array_equal(back.waypoints, m.waypoints)  # bit-exact
    assert back.takeoff_alt == m.takeoff_alt
    assert back.name == "m"
    # layout: header, home, takeoff, N waypoints, RTL
    lines = p.read_text().splitlines()
    assert lines[0] == "QGC WPL 110"
    rows = [ln.split("\t") for ln in lines[1:]]
    assert len(rows) == m.n_waypoints + 3 and all(len(r) == 12 for r in rows)
    assert [r[0] for r in rows] == [str(i) for i in range(len(rows))]
    assert rows[0][1:4] == ["1", "0", "16"] and float(rows[0][10]) == m.home[2]
    assert rows[1][2:4] == ["3", "22"] and float(rows[1][10]) == m.takeoff_alt
    assert all(r[2:4] == ["3", "16"] for r in rows[2:-1])
    assert rows[-1][3] == "20"


def test_wpl_tolerates_missing_takeoff_and_rtl(tmp_path):
    m = builtin_mission(2)
    p = write_wpl(m, tmp_path / "bare.txt", takeoff=False, rtl=False)
    assert len(p.read_text().splitlines()) == m.n_waypoints + 2
    back = read_wpl(p)
    np.testing.assert_array_equal(back.waypoints, m.waypoints)
    assert back.takeoff_alt == m.waypoints[0, 2]


def test_wpl_absolute_frame_and_spaces(tmp_path):
    lat, lon, alt0 = HOME_CMAC
    text = (
        "QGC WPL 110\n"
        f"0 1 0 16 0 0 0 0 {lat} {lon} {alt0} 1\n"
        f"1 0 0 16 0 0 0 0 {lat + 0.001} {lon} {alt0 + 12.5} 1\n"
        f"2 0 3 16 0 0 0 0 {lat + 0.002} {lon} 15 1\n"
        "3 0 3 20 0 0 0 0 0 0 0 1\n"
    )
    p = tmp_path / "abs.waypoints"
    p.write_text(text)
    m = read_wpl(p)
    np.testing.assert_allclose(m.waypoints[:, 2], [12.5, 15.0])
    assert m.takeoff_alt == 12.5


def _home_line() -> str:
    lat, lon, alt0 = HOME_CMAC
    return f"0\t1\t0\t16\t0\t0\t0\t0\t{lat}\t{lon}\t{alt0}\t1\n"


def _wp_line(seq: int, lat: object = HOME_CMAC[0], cmd: int = 16, frame: int = 3) -> str:
    return f"{seq}\t0\t{frame}\t{cmd}\t0\t0\t0\t0\t{lat}\t{HOME_CMAC[1]}\t20\t1\n"


@pytest.mark.parametrize(
    ("body", "message"),
    [
        ("QGC WPL 999\n" + _home_line(), r":1: expected header"),
        ("", "empty file"),
        ("QGC WPL 110\n" + _home_line() + "1\t0\t3\t16\t0\n", r":3: expected 12 fields"),
        ("QGC WPL 110\n" + _home_line() + _wp_line(1, lat="abc"), r":3: bad number"),
        ("QGC WPL 110\n" + _home_line() + _wp_line(2), r":3: sequence number 2, expected 1"),
        ("QGC WPL 110\n" + _home_line() + _wp_line(1, cmd=17),
         r":3: unsupported command 17 \(tlm flies 16 NAV_WAYPOINT"),
        ("QGC WPL 110\n" + _home_line() + _wp_line(1, frame=10), r":3: unsupported frame 10"),
        (
            "QGC WPL 110\n" + _home_line() + _wp_line(1) + _wp_line(2, lat="nan"),
            r":4: waypoint 1 has NaN latitude",
        ),
        (
            "QGC WPL 110\n" + _home_line() + _wp_line(1, cmd=20) + _wp_line(2),
            r":4: NAV_WAYPOINT item after RETURN_TO_LAUNCH",
        ),
        ("QGC WPL 110\n" + _home_line(), "no waypoints"),
        ("QGC WPL 110\n" + _wp_line(0, cmd=22), r":2: item 0 must be home"),
    ],
)
def test_wpl_bad_files(tmp_path, body, message):
    p = tmp_path / "bad.waypoints"
    p.write_text(body)
    with pytest.raises(MissionError, match=message):
        read_wpl(p)


def test_wpl_missing_file(tmp_path):
    with pytest.raises(MissionError, match="cannot read"):
        read_wpl(tmp_path / "nope.waypoints")
