"""Flat-earth latitude/longitude <-> local north/east conversions, as ArduPilot does them.

ArduPilot stores positions as integer 1e-7 degrees and converts small offsets with a
flat-earth model (``Location::get_distance_NE`` / ``Location::offset_latlng``):

* one unit of 1e-7 degree of latitude is ``LOCATION_SCALING_FACTOR`` =
  0.011131884502145034 m, i.e. :data:`M_PER_DEG_LAT` = 111318.84502145034 m per degree;
* a degree of longitude is that times ``longitude_scale(lat) = cos(lat)``, clamped below at
  0.01, evaluated at the *mid latitude* of the two points.

Using the mid latitude in both directions makes :func:`ne_to_latlon` the exact inverse of
:func:`latlon_to_ne` (up to float rounding): the forward map computes north from the latitude
difference alone, so the inverse recovers the latitude first and then knows the mid latitude.

All functions take and return degrees and metres. North/east are the first two axes of the
NED earth frame whose origin is the given home position. The vectorised functions broadcast
over numpy arrays; the ``*_scalar`` variants are numba ``@njit`` functions for the flight loop.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tlm_sim.ardupilot import M_PER_DEG_LAT

#: ArduPilot's lower clamp of the longitude scale (cos(lat)) near the poles
MIN_LONGITUDE_SCALE: float = 0.01

#: SITL's default start location (CMAC, Canberra): latitude deg, longitude deg, altitude m AMSL
HOME_CMAC: tuple[float, float, float] = (-35.363261, 149.165230, 584.0)
#: SITL's default start heading at CMAC, degrees clockwise from north
HOME_HEADING_DEG: float = 353.0

__all__ = [
    "HOME_CMAC",
    "HOME_HEADING_DEG",
    "M_PER_DEG_LAT",
    "MIN_LONGITUDE_SCALE",
    "latlon_to_ne",
    "latlon_to_ne_scalar",
    "longitude_scale",
    "ne_to_latlon",
    "ne_to_latlon_scalar",
]


def longitude_scale(lat_deg: np.ndarray | float) -> np.ndarray | float:
    """cos(latitude) clamped to >= 0.01, as ArduPilot's ``Location::longitude_scale``.

    Args:
        lat_deg: latitude, degrees (scalar or array).

    Returns:
        The metres-per-degree-of-longitude factor relative to a degree of latitude.
    """
    return np.maximum(np.cos(np.radians(lat_deg)), MIN_LONGITUDE_SCALE)


def latlon_to_ne(
    lat: np.ndarray | float,
    lon: np.ndarray | float,
    home_lat: float,
    home_lon: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Flat-earth offset of (lat, lon) from home, in metres.

    Args:
        lat, lon: position(s), degrees; arrays broadcast against each other.
        home_lat, home_lon: origin, degrees.

    Returns:
        ``(north_m, east_m)`` float64 arrays (0-d for scalar input): NED north/east of the
        position relative to home.
    """
    lat = np.asarray(lat, dtype=np.float64)
    lon = np.asarray(lon, dtype=np.float64)
    north = (lat - home_lat) * M_PER_DEG_LAT
    dlon = _wrap_180(lon - home_lon)
    east = dlon * M_PER_DEG_LAT * longitude_scale(0.5 * (lat + home_lat))
    return north, east


def ne_to_latlon(
    north_m: np.ndarray | float,
    east_m: np.ndarray | float,
    home_lat: float,
    home_lon: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of :func:`latlon_to_ne`: home offset by (north, east) metres.

    Args:
        north_m, east_m: NED north/east offsets from home, metres; arrays broadcast.
        home_lat, home_lon: origin, degrees.

    Returns:
        ``(lat_deg, lon_deg)`` float64 arrays; longitude wrapped to [-180, 180).
    """
    north_m = np.asarray(north_m, dtype=np.float64)
    east_m = np.asarray(east_m, dtype=np.float64)
    lat = home_lat + north_m / M_PER_DEG_LAT
    lon = home_lon + east_m / (M_PER_DEG_LAT * longitude_scale(0.5 * (lat + home_lat)))
    return lat, _wrap_180(lon)


def _wrap_180(deg: np.ndarray) -> np.ndarray:
    """Wrap angles to [-180, 180) degrees; values already in range are returned unchanged."""
    deg = np.asarray(deg, dtype=np.float64)
    out_of_range = (deg < -180.0) | (deg >= 180.0)
    if np.any(out_of_range):
        deg = np.where(out_of_range, (deg + 180.0) % 360.0 - 180.0, deg)
    return deg


@njit(cache=True, nogil=True)
def _longitude_scale_scalar(lat_deg: float) -> float:
    s = math.cos(math.radians(lat_deg))
    return s if s > MIN_LONGITUDE_SCALE else MIN_LONGITUDE_SCALE


@njit(cache=True, nogil=True)
def _wrap_180_scalar(deg: float) -> float:
    if deg < -180.0 or deg >= 180.0:
        return (deg + 180.0) % 360.0 - 180.0
    return deg


@njit(cache=True, nogil=True)
def latlon_to_ne_scalar(
    lat: float, lon: float, home_lat: float, home_lon: float
) -> tuple[float, float]:
    """Scalar, numba-callable :func:`latlon_to_ne`: returns (north_m, east_m)."""
    north = (lat - home_lat) * M_PER_DEG_LAT
    dlon = _wrap_180_scalar(lon - home_lon)
    east = dlon * M_PER_DEG_LAT * _longitude_scale_scalar(0.5 * (lat + home_lat))
    return north, east


@njit(cache=True, nogil=True)
def ne_to_latlon_scalar(
    north_m: float, east_m: float, home_lat: float, home_lon: float
) -> tuple[float, float]:
    """Scalar, numba-callable :func:`ne_to_latlon`: returns (lat_deg, lon_deg)."""
    lat = home_lat + north_m / M_PER_DEG_LAT
    lon = home_lon + east_m / (M_PER_DEG_LAT * _longitude_scale_scalar(0.5 * (lat + home_lat)))
    return lat, _wrap_180_scalar(lon)


def earth_field_ned(dec_deg: float, inc_deg: float, intensity_ga: float) -> np.ndarray:
    """Earth magnetic field NED [gauss] from declination/inclination [deg] and intensity [gauss].

    Positive inclination points the field down (northern hemisphere); ArduPilot SITL's default
    location (Canberra) has inclination about -66 deg, i.e. the field points up.
    """
    dec = math.radians(dec_deg)
    inc = math.radians(inc_deg)
    h = intensity_ga * math.cos(inc)
    return np.array([h * math.cos(dec), h * math.sin(dec), intensity_ga * math.sin(inc)])
