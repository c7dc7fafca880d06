"""The earth magnetic field at a mission's home: what the simulated compasses measure and what
the EKF, the DCM estimator and the yaw alignment expect (one field per flight, held in the
``TLM_MAG_DEC_DEG`` / ``TLM_MAG_INC_DEG`` / ``TLM_MAG_INT_GA`` parameters).

Where SITL's field comes from (reference firmware 2598e9d4b2): ``Aircraft::update_mag_field_bf``
(SIM_Aircraft.cpp) asks ``AP_Declination::get_mag_field_ef`` for intensity, declination and
inclination at the vehicle's latitude/longitude; the firmware's compass library
(``COMPASS_AUTODEC``), EKF3 (``table_earth_field_ga``, ``EK3_MAG_EF_LIM``) and the arming checks
ask the same tables, so simulated compass and firmware agree. The tables
(``libraries/AP_Declination/tables.cpp``) are IGRF-13 sampled at sea level on a 10-degree grid
(latitude -90..90, longitude -180..180) on the day they were generated (2022-12-29, commit
"AP_Declination: update magnetic field tables", by ``generate/generate.py`` with the ``igrf``
package), read by bilinear interpolation between the four nodes around the position.

tlm evaluates the same model with ``ppigrf`` (the IAGA V-MOD group's pure-Python IGRF, MIT)
at the same nodes and date and interpolates the same way (:func:`sitl_table_field`): over the
grid (|lat| <= 80) its node values differ from the firmware's tables by 0.007 deg rms in
declination (0.07 deg at worst, at 80 N), 0.002 deg rms in inclination and 1.6e-5 gauss rms.

``TLM_MAG_MODEL`` picks what a flight uses (:func:`home_field`):

* 1 (default), SITL: each ``TLM_MAG_*`` left at its default takes SITL's field at home as above;
  at SITL's own default home (CMAC, :data:`tlm_sim.geo.HOME_CMAC`) the defaults are SITL's
  field there as measured from the reference logs (``tools/extract_defaults.py --mag``), so
  flights at CMAC are unchanged.
* 2, IGRF-14 at home (latitude, longitude, home altitude) on the simulated boot date
  (:data:`tlm_sim.flight.BOOT_UTC`): the real field there rather than SITL's 10-degree tables
  (between nodes, |lat| <= 60, they depart from IGRF-13 itself by 0.48 deg rms in declination,
  1.8 deg at the 99th percentile, and 0.35 deg rms, 1.3 deg at worst, in inclination).
* 0: the three ``TLM_MAG_*`` values as given, whatever the home (tlm before issue 22).

With 1 and 2 a ``TLM_MAG_*`` set to any value other than its default is used as given. The
values a flight used are in its parameters (the log's PARM, ``meta.json`` ``params``) and in
``meta["earth_field"]``. The field is fixed at home for the whole flight; SITL re-reads the
tables at the current position, which changes it by < 0.01 deg within 1 km.

Resolved values are rounded to 1e-4 deg and 1e-6 gauss, so that a flight does not depend on
the last bits of numpy's trigonometry on one machine or another.
"""

from __future__ import annotations

import datetime as _dt
import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from tlm_sim.geo import HOME_CMAC
from tlm_sim.params import TLM_DEFAULTS, Params

__all__ = [
    "MAG_PARAMS",
    "SITL_TABLE_DATE",
    "EarthField",
    "home_field",
    "igrf_field",
    "sitl_table_field",
    "with_home_field",
]

#: The field parameters: declination [deg, + east], inclination [deg, + down], intensity [gauss].
MAG_PARAMS = ("TLM_MAG_DEC_DEG", "TLM_MAG_INC_DEG", "TLM_MAG_INT_GA")
#: Day ArduPilot generated the AP_Declination tables of the reference firmware (IGRF-13).
SITL_TABLE_DATE = _dt.datetime(2022, 12, 29)
#: AP_Declination's grid: resolution and the south-west corner [deg].
GRID_RES_DEG = 10.0
GRID_MIN_LAT = -90.0
GRID_MIN_LON = -180.0
_N_LAT = 19  # -90 .. 90
_N_LON = 37  # -180 .. 180
#: How close to CMAC [deg] a home counts as SITL's default home (a log's 1e-7 deg integers).
CMAC_TOL_DEG = 1e-6
#: TLM_MAG_MODEL values.
MODEL_PARAMS, MODEL_SITL, MODEL_IGRF = 0, 1, 2
_DEC_ROUND, _INT_ROUND = 4, 6
_POLE_LAT = 90.0 - 1e-6


@dataclass(frozen=True, slots=True)
class EarthField:
    """A flight's earth field: declination [deg, + east of true north], inclination [deg, +
    down], intensity [gauss], and where it came from (``source``, one line)."""

    declination_deg: float
    inclination_deg: float
    intensity_gauss: float
    source: str

    def values(self) -> tuple[float, float, float]:
        """(declination, inclination, intensity) in the order of :data:`MAG_PARAMS`."""
        return self.declination_deg, self.inclination_deg, self.intensity_gauss

    def as_meta(self) -> dict[str, Any]:
        """The record a flight's ``meta["earth_field"]`` holds."""
        return {"declination_deg": self.declination_deg,
                "inclination_deg": self.inclination_deg,
                "intensity_gauss": self.intensity_gauss, "source": self.source}


def _coeff_file(model: str) -> str:
    """Path of ppigrf's spherical-harmonic coefficient file of ``model`` (IGRF13 / IGRF14)."""
    from ppigrf import ppigrf as _pp

    return {"IGRF13": _pp.shc_fn_igrf13, "IGRF14": _pp.shc_fn_igrf14}[model]


def _igrf(lats: Sequence[float], lons: Sequence[float], alt_km: float, when: _dt.datetime,
          model: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """IGRF (``model``) at geodetic points (lats, lons) [deg], ``alt_km`` above the WGS84
    ellipsoid, on ``when``: declination [deg], inclination [deg], intensity [gauss]."""
    import ppigrf

    # at a pole ppigrf divides by sin(colatitude) = 0: evaluate a hair (~0.1 m) away
    lat = np.clip(np.asarray(lats, float), -_POLE_LAT, _POLE_LAT)
    be, bn, bu = ppigrf.igrf(np.asarray(lons, float), lat, alt_km,
                             when.replace(tzinfo=None), coeff_fn=_coeff_file(model))
    be, bn, bu = (np.ravel(b) for b in (be, bn, bu))  # nT, east / north / up
    h = np.hypot(be, bn)
    return (np.degrees(np.arctan2(be, bn)), np.degrees(np.arctan2(-bu, h)),
            np.sqrt(h * h + bu * bu) * 1e-5)


@functools.lru_cache(maxsize=64)
def igrf_field(lat: float, lon: float, alt_m: float = 0.0,
               when: _dt.datetime = SITL_TABLE_DATE,
               model: str = "IGRF14") -> tuple[float, float, float]:
    """The IGRF field at one place and time (no grid): (declination [deg], inclination [deg],
    intensity [gauss]); ``alt_m`` above the WGS84 ellipsoid; ``model`` "IGRF14" (1900-2030) or
    "IGRF13" (1900-2025, what the firmware's tables were made from)."""
    d, i, f = _igrf([lat], [lon], alt_m / 1000.0, when, model)
    return float(d[0]), float(i[0]), float(f[0])


@functools.cache
def _sitl_cell(i: int, j: int) -> np.ndarray:
    """The AP_Declination grid values at the four nodes (i..i+1 lat, j..j+1 lon): (3, 2, 2)
    declination, inclination, intensity from IGRF-13 on :data:`SITL_TABLE_DATE`."""
    lats = [GRID_MIN_LAT + GRID_RES_DEG * (i + a) for a in (0, 0, 1, 1)]
    lons = [GRID_MIN_LON + GRID_RES_DEG * (j + b) for b in (0, 1, 0, 1)]
    d, inc, f = _igrf(lats, lons, 0.0, SITL_TABLE_DATE, "IGRF13")
    return np.stack([d, inc, f]).reshape(3, 2, 2)


def sitl_table_field(lat: float, lon: float) -> tuple[float, float, float]:
    """SITL's (AP_Declination's) field at (lat, lon) [deg]: (declination [deg], inclination
    [deg], intensity [gauss]), bilinear between the four 10-degree nodes around the point, as
    ``get_mag_field_ef`` reads its tables (out-of-range points clamp to the border cell; the
    declination is interpolated as stored, without unwrapping +-180, as the firmware does)."""
    i = min(max(math.floor((lat - GRID_MIN_LAT) / GRID_RES_DEG), 0), _N_LAT - 2)
    j = min(max(math.floor((lon - GRID_MIN_LON) / GRID_RES_DEG), 0), _N_LON - 2)
    fy = (lat - (GRID_MIN_LAT + GRID_RES_DEG * i)) / GRID_RES_DEG
    fx = (lon - (GRID_MIN_LON + GRID_RES_DEG * j)) / GRID_RES_DEG
    cell = _sitl_cell(i, j)
    out = []
    for k in range(3):
        (sw, se), (nw, ne) = cell[k]
        south = fx * (se - sw) + sw
        north = fx * (ne - nw) + nw
        out.append(float(fy * (north - south) + south))
    return out[0], out[1], out[2]


def _at_cmac(lat: float, lon: float) -> bool:
    return abs(lat - HOME_CMAC[0]) <= CMAC_TOL_DEG and abs(lon - HOME_CMAC[1]) <= CMAC_TOL_DEG


def _rounded(values: Sequence[float]) -> tuple[float, float, float]:
    d, i, f = values
    return round(d, _DEC_ROUND), round(i, _DEC_ROUND), round(f, _INT_ROUND)


def _model_values(model: int, home: Sequence[float], when: _dt.datetime
                  ) -> tuple[tuple[float, float, float], str]:
    """The field ``TLM_MAG_MODEL`` ``model`` (1 or 2) gives at ``home`` and its description."""
    lat, lon, alt = (float(v) for v in home[:3])
    if model == MODEL_IGRF:
        return (_rounded(igrf_field(lat, lon, alt, when, "IGRF14")),
                f"IGRF-14 at home on {when.date().isoformat()} (ppigrf)")
    if _at_cmac(lat, lon):
        return (tuple(TLM_DEFAULTS[n] for n in MAG_PARAMS),  # type: ignore[return-value]
                "SITL at CMAC (tlm's defaults, measured from the reference logs)")
    return (_rounded(sitl_table_field(lat, lon)),
            "SITL's AP_Declination tables at home (IGRF-13 on 2022-12-29, 10-degree grid; "
            "ppigrf)")


def home_field(p: Params, home: Sequence[float], when: _dt.datetime) -> EarthField:
    """The earth field a flight with parameters ``p`` uses at ``home`` (lat deg, lon deg, alt m
    AMSL) on ``when`` (the simulated date, used by ``TLM_MAG_MODEL`` 2): see the module's
    docstring. A ``TLM_MAG_*`` value other than its default always wins."""
    given = tuple(float(p[n]) for n in MAG_PARAMS)
    model = int(p["TLM_MAG_MODEL"])
    if model == MODEL_PARAMS:
        return EarthField(*given, source="parameters (TLM_MAG_MODEL 0)")
    explicit = [n for n in MAG_PARAMS if p[n] != TLM_DEFAULTS[n]]
    if len(explicit) == len(MAG_PARAMS):
        return EarthField(*given, source="parameters (all three set)")
    values, source = _model_values(model, home, when)
    if explicit:
        source += "; set: " + ", ".join(explicit)
    merged = [given[k] if n in explicit else values[k] for k, n in enumerate(MAG_PARAMS)]
    return EarthField(*merged, source=source)


def with_home_field(p: Params, home: Sequence[float], when: _dt.datetime
                    ) -> tuple[Params, EarthField]:
    """``p`` with ``TLM_MAG_*`` set to the field of :func:`home_field` (``p`` itself when they
    already hold it), and that field. Every configuration builder then reads the one field."""
    field = home_field(p, home, when)
    new = dict(zip(MAG_PARAMS, field.values(), strict=True))
    if all(p[n] == v for n, v in new.items()):
        return p, field
    return p.updated(new), field
