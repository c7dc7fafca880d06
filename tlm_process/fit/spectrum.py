"""What spectrum a log's IMU rows reveal over a segment (``tlm fit``, issue 40).

A log keeps IMU 0's samples at its logging rate (Copter 3.3: ~50 Hz, 4.x: 25 Hz in tlm and
SITL), after the INS low-pass filters. Whatever of the rotor vibration passes them shows
aliased into 0..rate/2; the rest of the variance is the airframe's own motion. For each axis of
the gyro and the accelerometer, :func:`imu_spectra` gives the Welch power spectral density of
the rows, and :func:`band_shares` how the variance splits over :data:`BANDS_HZ` and where its
strongest peak above :data:`PEAK_FROM_HZ` lies: enough to see whether a fitted vehicle's noise
sits where the log's does (slow motion, or vibration aliased near the Nyquist frequency).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd

from tlm_process.fit.stats import imu0_rows
from tlm_process.reference import time_window

__all__ = ["BANDS_HZ", "CHANNELS", "PEAK_FROM_HZ", "Spectrum", "band_shares",
           "format_spectra", "imu_spectra"]

#: frequency bands the variance is split over [Hz] (the last one up to the Nyquist frequency)
BANDS_HZ: tuple[tuple[float, float], ...] = ((0.0, 1.0), (1.0, 3.0), (3.0, 8.0),
                                             (8.0, math.inf))
#: the strongest peak is looked for above this frequency [Hz] (below it lies the motion)
PEAK_FROM_HZ = 3.0
#: (name, IMU column, scale to the unit shown): the gyro in deg/s, the accelerometer in m/s^2
CHANNELS: tuple[tuple[str, str, float], ...] = (
    ("gyr_x", "GyrX", math.degrees(1.0)), ("gyr_y", "GyrY", math.degrees(1.0)),
    ("gyr_z", "GyrZ", math.degrees(1.0)),
    ("acc_x", "AccX", 1.0), ("acc_y", "AccY", 1.0), ("acc_z", "AccZ", 1.0))
#: Welch segment length [rows]
NPERSEG = 256


@dataclass(frozen=True)
class Spectrum:
    """One channel's spectrum: the rows' rate [Hz], the frequencies [Hz] and the power
    spectral density [unit^2 / Hz]."""

    rate_hz: float
    freq_hz: np.ndarray
    psd: np.ndarray


def imu_spectra(tables: Mapping[str, pd.DataFrame], t0_us: float, t1_us: float
                ) -> dict[str, Spectrum]:
    """The Welch spectrum of IMU 0's rows over ``[t0_us, t1_us]`` per :data:`CHANNELS` name
    (a channel the log lacks, or fewer than 16 rows, is left out)."""
    from scipy.signal import welch

    imu = time_window(imu0_rows(tables), t0_us, t1_us)
    out: dict[str, Spectrum] = {}
    if len(imu) < 16:
        return out
    t = imu.TimeUS.to_numpy(float)
    rate = 1e6 / float(np.median(np.diff(t)))
    for name, col, scale in CHANNELS:
        if col not in imu:
            continue
        y = pd.to_numeric(imu[col], errors="coerce").to_numpy(float) * scale
        y = y[np.isfinite(y)]
        if len(y) < 16:
            continue
        f, p = welch(y, fs=rate, nperseg=min(NPERSEG, len(y)), detrend="constant")
        out[name] = Spectrum(rate, f, p)
    return out


def band_shares(s: Spectrum) -> tuple[list[float], float]:
    """(share of the variance in each :data:`BANDS_HZ` band, 0..1; the frequency of the
    strongest peak above :data:`PEAK_FROM_HZ` [Hz], NaN when the rows reach no higher)."""
    total = float(s.psd.sum())
    shares = [float(s.psd[(s.freq_hz >= lo) & (s.freq_hz < hi)].sum()) / total if total > 0
              else math.nan for lo, hi in BANDS_HZ]
    high = s.freq_hz >= PEAK_FROM_HZ
    peak = float(s.freq_hz[high][np.argmax(s.psd[high])]) if high.any() else math.nan
    return shares, peak


def _line(s: Spectrum | None) -> str:
    if s is None:
        return "-"
    shares, peak = band_shares(s)
    bands = " ".join(f"{100 * x:3.0f}" for x in shares)
    return f"{bands}  peak {peak:4.1f} Hz"


def format_spectra(log: Mapping[str, Spectrum], tlm: Mapping[str, Spectrum]) -> str:
    """A table: per channel, the log's and tlm's share of the variance per band [%] and the
    strongest peak above :data:`PEAK_FROM_HZ`."""
    names = [n for n, _, _ in CHANNELS if n in log or n in tlm]
    if not names:
        return "spectrum           (no IMU rows)"
    rate = next(iter(log.values())).rate_hz if log else math.nan
    trate = next(iter(tlm.values())).rate_hz if tlm else math.nan
    bands = " ".join(f"{lo:g}-{hi:g}" if math.isfinite(hi) else f">{lo:g}"
                     for lo, hi in BANDS_HZ)
    lines = [f"spectrum of IMU 0's rows (log at {rate:.0f} Hz, tlm at {trate:.0f} Hz): % of "
             f"the variance per band [Hz] {bands}; the strongest peak above {PEAK_FROM_HZ:g} Hz"]
    for n in names:
        lines.append(f"  {n:<6} log {_line(log.get(n))}   tlm {_line(tlm.get(n))}")
    return "\n".join(lines)
