"""The statistics ``tlm fit`` matches: what a steady segment of any ArduCopter log says about
the vehicle's noise, vibration and hover (issue 40).

Works on tables as :func:`tlm_process.logread.read_log_tables` gives them (Copter 3.x to 4.x,
real, SITL or tlm): ``TimeUS`` everywhere, extra IMUs folded into ``IMU`` with ``I``. Per
segment ``[t0, t1]`` (µs):

* ``hover_thr``: mean motor throttle (CTUN ``ThO``, Copter 3.x ``ThrOut`` / 1000), 0..1;
* ``roll_std_deg`` / ``pitch_std_deg``: standard deviation of ATT Roll / Pitch [deg];
* ``acc_{x,y,z}_std``: IMU 0's logged accelerations, standard deviation per axis [m/s^2];
* ``gyr_{x,y,z}_std_dps``: IMU 0's logged rates, standard deviation per axis [deg/s];
* ``rate_{roll,pitch}_err_std_dps``: RATE achieved minus desired rate [deg/s] (Copter 3.x
  logs RATE in centidegrees per second: the unit is read from the log itself, see
  :func:`rate_unit`);
* ``vibe_{x,y,z}``: mean VIBE of IMU 0 [m/s^2] (NaN where the log has no VIBE, as Copter 3.3).

A standard deviation over a segment mixes the sensor's noise with the flight's own motion;
a steady segment (:mod:`tlm_process.fit.segment`) keeps the motion small.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import pandas as pd

from tlm_process.logread import motor_columns, rates_in_centidegrees
from tlm_process.reference import time_window

__all__ = ["ASYM_NAMES", "STAT_NAMES", "StatsError", "imu0_rows", "motor_asymmetry", "rate_unit",
           "segment_stats"]

#: every statistic :func:`segment_stats` returns, in report order
STAT_NAMES = ("hover_thr", "roll_std_deg", "pitch_std_deg",
              "acc_x_std", "acc_y_std", "acc_z_std",
              "gyr_x_std_dps", "gyr_y_std_dps", "gyr_z_std_dps",
              "rate_roll_err_std_dps", "rate_pitch_err_std_dps",
              "att_roll_err_std_deg", "att_pitch_err_std_deg",
              "vibe_x", "vibe_y", "vibe_z")


#: the motor outputs' static asymmetry (:func:`motor_asymmetry`) [us]
ASYM_NAMES = ("mot_roll_us", "mot_pitch_us", "mot_yaw_us")


class StatsError(ValueError):
    """The log lacks what a statistic needs in the segment (one line, for the command)."""


def imu0_rows(tables: Mapping[str, pd.DataFrame]) -> pd.DataFrame | None:
    """IMU 0's rows of the IMU table (the whole table when it has no instance column ``I``;
    None without IMU)."""
    imu = tables.get("IMU")
    if imu is None:
        return None
    return imu[imu.I == 0] if "I" in imu else imu


def _std(s: pd.Series) -> float:
    s = pd.to_numeric(s, errors="coerce").dropna()
    return float(s.std()) if len(s) > 2 else math.nan


def rate_unit(tables: Mapping[str, pd.DataFrame]) -> float:
    """Degrees per second per unit of the log's RATE ``R``/``P`` columns: 1 (Copter 4.x, deg/s)
    or 0.01 (Copter 3.x, centidegrees/s), whichever makes RATE's roll rate agree in size with
    IMU 0's gyro (:func:`tlm_process.logread.rates_in_centidegrees`; tables read by
    :func:`~tlm_process.logread.read_log_tables` are in degrees per second already); 1 when
    either is missing."""
    rate = tables.get("RATE")
    return 0.01 if rate is not None and rates_in_centidegrees(rate, tables.get("IMU")) else 1.0


def throttle_out(ctun: pd.DataFrame) -> pd.Series:
    """CTUN's throttle output 0..1 (ThO; Copter 3.x's ThrOut 0..1000 scaled)."""
    if "ThO" in ctun:
        return pd.to_numeric(ctun.ThO, errors="coerce")
    if "ThrOut" in ctun:  # Copter 3.x: 0..1000
        return pd.to_numeric(ctun.ThrOut, errors="coerce") / 1000.0
    raise StatsError("the log's CTUN has no throttle output (ThO or ThrOut)")


def segment_stats(tables: Mapping[str, pd.DataFrame], t0_us: float, t1_us: float,
                  unit: float | None = None) -> dict[str, float]:
    """Every :data:`STAT_NAMES` statistic over ``[t0_us, t1_us]``; ``unit``: degrees per second
    per RATE unit (default :func:`rate_unit` of the tables). Raises :class:`StatsError` when the
    segment has no IMU, ATT or CTUN rows."""
    imu = time_window(imu0_rows(tables), t0_us, t1_us)
    att = time_window(tables.get("ATT"), t0_us, t1_us)
    ctun = time_window(tables.get("CTUN"), t0_us, t1_us)
    for name, df in (("IMU", imu), ("ATT", att), ("CTUN", ctun)):
        if len(df) < 3:
            raise StatsError(f"no {name} rows between {t0_us * 1e-6:.1f} s and "
                             f"{t1_us * 1e-6:.1f} s")
    out = {"hover_thr": float(throttle_out(ctun).mean()),
           "roll_std_deg": _std(att.Roll), "pitch_std_deg": _std(att.Pitch)}
    for ax in "xyz":
        out[f"acc_{ax}_std"] = _std(imu[f"Acc{ax.upper()}"])
        out[f"gyr_{ax}_std_dps"] = math.degrees(_std(imu[f"Gyr{ax.upper()}"]))
    rate = time_window(tables.get("RATE"), t0_us, t1_us)
    u = rate_unit(tables) if unit is None else unit
    for name, des, got in (("roll", "RDes", "R"), ("pitch", "PDes", "P")):
        ok = len(rate) > 2 and des in rate and got in rate
        out[f"rate_{name}_err_std_dps"] = _std((rate[got] - rate[des]) * u) if ok else math.nan
    for name, des, got in (("roll", "DesRoll", "Roll"), ("pitch", "DesPitch", "Pitch")):
        ok = des in att and got in att
        out[f"att_{name}_err_std_deg"] = _std(att[got] - att[des]) if ok else math.nan
    vibe = time_window(tables.get("VIBE"), t0_us, t1_us)
    if len(vibe) and "IMU" in vibe:
        vibe = vibe[vibe.IMU == 0]
    for ax in "xyz":
        col = f"Vibe{ax.upper()}"
        out[f"vibe_{ax}"] = float(vibe[col].mean()) if len(vibe) and col in vibe else math.nan
    return {k: out[k] for k in STAT_NAMES}


def motor_asymmetry(tables: Mapping[str, pd.DataFrame], t0_us: float, t1_us: float,
                    params: Mapping[str, float]) -> dict[str, float]:
    """How unequally the motors run over ``[t0_us, t1_us]``: each motor's mean RCOU output
    less their mean, projected on the frame's roll, pitch and yaw mixer factors [us]
    (``mot_roll_us``, ``mot_pitch_us``, ``mot_yaw_us``: the steady output that balances the
    airframe; front motors working harder give a positive pitch, right ones a negative roll,
    counter-clockwise ones a positive yaw, ArduPilot's factors). The frame from ``params``
    (FRAME_CLASS / FRAME_TYPE, or Copter 3.x's FRAME); NaN without RCOU rows."""
    from tlm_sim.frames import FrameError, frame_for

    nan = dict.fromkeys(ASYM_NAMES, math.nan)
    try:
        frame_type = params.get("FRAME_TYPE", params.get("FRAME", 1.0))
        layout = frame_for(params.get("FRAME_CLASS", 1.0), frame_type)
    except FrameError:
        return nan
    rcou = time_window(tables.get("RCOU"), t0_us, t1_us)
    cols = motor_columns(rcou, dict(params)) if len(rcou) >= 3 else []
    if len(cols) != layout.n_motors:
        return nan
    mean = rcou[cols].apply(pd.to_numeric, errors="coerce").mean().to_numpy(float)
    dev = mean - mean.mean()
    roll, pitch, yaw = (np.asarray(f, dtype=float) for f in layout.mixer_factors())
    return {"mot_roll_us": float(dev @ roll / (roll @ roll)),
            "mot_pitch_us": float(dev @ pitch / (pitch @ pitch)),
            "mot_yaw_us": float(dev @ yaw / (yaw @ yaw))}
