"""Flat-earth conversions (tlm_sim.geo) against ArduPilot's constants and SITL's own log."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.conftest import close_dfreader, reference_path
from tlm_sim.geo import (
    HOME_CMAC,
    HOME_HEADING_DEG,
    M_PER_DEG_LAT,
    latlon_to_ne,
    latlon_to_ne_scalar,
    ne_to_latlon,
    ne_to_latlon_scalar,
)


def test_constants():
    assert HOME_CMAC == (-35.363261, 149.165230, 584.0)
    assert HOME_HEADING_DEG == 353.0
    # ArduPilot LOCATION_SCALING_FACTOR: metres per 1e-7 degree of latitude
    assert M_PER_DEG_LAT * 1e-7 == pytest.approx(0.011131884502145034, rel=1e-15)


def test_scaling_at_cmac():
    lat0, lon0, _ = HOME_CMAC
    n, e = latlon_to_ne(lat0 + 1e-3, lon0, lat0, lon0)
    assert float(n) == pytest.approx(111.31884502145034, abs=1e-9)
    assert float(e) == 0.0
    n, e = latlon_to_ne(lat0, lon0 + 1e-3, lat0, lon0)
    assert float(n) == 0.0
    # a degree of longitude at -35.36 deg is cos(lat) of a degree of latitude: 90.78 m per 1e-3
    assert float(e) == pytest.approx(111.31884502145034 * math.cos(math.radians(lat0)), rel=1e-9)
    assert float(e) == pytest.approx(90.78, abs=0.01)


def test_vectorised_shapes():
    lat = HOME_CMAC[0] + np.linspace(-0.01, 0.01, 7)
    lon = HOME_CMAC[1] + np.linspace(0.01, -0.01, 7)
    n, e = latlon_to_ne(lat, lon, *HOME_CMAC[:2])
    assert n.shape == e.shape == (7,)
    la, lo = ne_to_latlon(n, e, *HOME_CMAC[:2])
    np.testing.assert_allclose(la, lat, rtol=0, atol=1e-12)
    np.testing.assert_allclose(lo, lon, rtol=0, atol=1e-12)


@settings(max_examples=200, deadline=None)
@given(
    home_lat=st.floats(-80, 80),
    home_lon=st.floats(-179.9, 179.9),
    north=st.floats(-50_000, 50_000),
    east=st.floats(-50_000, 50_000),
)
def test_round_trip_ne_latlon_ne(home_lat, home_lon, north, east):
    lat, lon = ne_to_latlon(north, east, home_lat, home_lon)
    n2, e2 = latlon_to_ne(lat, lon, home_lat, home_lon)
    assert abs(float(n2) - north) < 1e-6
    assert abs(float(e2) - east) < 1e-6
    # the numba scalar versions agree with the vectorised ones
    lat_s, lon_s = ne_to_latlon_scalar(north, east, home_lat, home_lon)
    assert abs(lat_s - float(lat)) < 1e-12 and abs(lon_s - float(lon)) < 1e-12
    n_s, e_s = latlon_to_ne_scalar(float(lat), float(lon), home_lat, home_lon)
    assert abs(n_s - float(n2)) < 1e-9 and abs(e_s - float(e2)) < 1e-9


def test_antimeridian_wrap():
    n, e = latlon_to_ne(0.0, -179.999, 0.0, 179.999)
    assert float(e) == pytest.approx(0.002 * M_PER_DEG_LAT, rel=1e-9)
    lat, lon = ne_to_latlon(0.0, 0.002 * M_PER_DEG_LAT, 0.0, 179.999)
    assert float(lon) == pytest.approx(-179.999, abs=1e-9)
    assert -180.0 <= float(lon) < 180.0


def test_matches_sitl_truth_sim_vs_sim2():
    """SITL logs its true position twice: SIM (lat/lon) and SIM2 (NED metres from home).

    Our flat-earth conversion of SIM must land on SIM2 to a few cm over ~220 m; a spherical
    6371 km model would be ~0.25 m off there. SIM's lat/lon are logged to 1e-7 deg (1.1 cm) and
    the two messages are stamped at different times (SIM2 interpolated), hence the 5 cm.
    """
    log = reference_path("rc_s15.bin")
    from pymavlink import DFReader

    r = DFReader.DFReader_binary(str(log))
    sim, sim2 = [], []
    while True:
        m = r.recv_match(type=["SIM", "SIM2"])
        if m is None or m.TimeUS > 200e6:
            break
        if m.get_type() == "SIM":
            sim.append((m.TimeUS, m.Lat, m.Lng))
        else:
            sim2.append((m.TimeUS, m.PN, m.PE))
    close_dfreader(r)
    sim_a, sim2_a = np.array(sim), np.array(sim2)
    assert len(sim_a) > 1000
    pn = np.interp(sim_a[:, 0], sim2_a[:, 0], sim2_a[:, 1])
    pe = np.interp(sim_a[:, 0], sim2_a[:, 0], sim2_a[:, 2])
    n, e = latlon_to_ne(sim_a[:, 1], sim_a[:, 2], *HOME_CMAC[:2])
    assert np.hypot(n, e).max() > 200.0  # the check covers the whole loop
    assert np.abs(n - pn).max() < 0.05
    assert np.abs(e - pe).max() < 0.05
