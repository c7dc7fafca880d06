"""Flight metrics that compare a tlm flight with a genuine ArduCopter SITL log.

The same function reads both: a tlm ``FlightLog.tables`` and the tables ``read_bin`` gives for a
reference ``.bin``. Phases come from the logs themselves: armed/disarmed from EV 10/11, AUTO from
the MODE table, the return leg from the last 60 s before disarming.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd

ARMED, DISARMED = 10, 11
AUTO = 3


def time_window(df: pd.DataFrame | None, t0_us: float, t1_us: float) -> pd.DataFrame:
    """Rows of df with t0_us <= TimeUS <= t1_us (an empty frame for a missing table or one
    without TimeUS)."""
    if df is None or "TimeUS" not in df:
        return pd.DataFrame()
    return df[(df.TimeUS >= t0_us) & (df.TimeUS <= t1_us)]


def _rate_hz(df: pd.DataFrame, inst: str | None, t0: float, t1: float) -> float:
    d = time_window(df, t0, t1)
    n = len(d) if inst is None else len(d[d[inst] == 0])
    return n / ((t1 - t0) * 1e-6)


def flight_metrics(tables: Mapping[str, pd.DataFrame]) -> dict[str, float]:
    """Scalar metrics of a normal (fault-free) AUTO flight.

    Keys: flight_time_s (armed), cruise_speed_ms (median GPS ground speed in AUTO, first 20 s
    and last 60 s armed excluded), max_speed_ms, takeoff_climb_ms (max GPS climb rate before
    AUTO), land_descent_ms (median descent rate over the last 3 m), cruise_throttle (CTUN.ThO
    median in AUTO cruise), hover_throttle_learned (last CTUN.ThH while armed),
    acc_noise_ground / gyr_noise_ground (std of IMU0 AccZ [m/s^2] and GyrX [rad/s] in the 8 s
    before arming), acc_z_std_cruise (IMU0 AccZ std in cruise), vibe_x_cruise_imu0/1 (mean VibeX
    in cruise), pitch_cruise_deg (median ATT.Pitch in cruise), and rates [Hz] of GPS, IMU, RATE,
    VIBE per instance over the armed period.
    """
    ev = tables["EV"]
    armed_t = float(ev[ev.Id == ARMED].TimeUS.iloc[0])
    disarm = ev[ev.Id == DISARMED]
    disarm_t = float(disarm.TimeUS.iloc[-1]) if len(disarm) else float(tables["GPS"].TimeUS.max())
    mode = tables["MODE"]
    auto_t = float(mode[mode.Mode == AUTO].TimeUS.iloc[0])
    c0, c1 = auto_t + 20e6, disarm_t - 60e6
    gps = tables["GPS"]
    cruise_gps = time_window(gps, c0, c1)
    pre = time_window(gps, armed_t, auto_t)
    imu = tables["IMU"]
    imu0 = imu[imu.I == 0]
    ground = time_window(imu0, armed_t - 8e6, armed_t - 0.5e6)
    cruise_imu = time_window(imu0, c0, c1)
    ctun = tables["CTUN"]
    vibe = tables["VIBE"]
    att = tables["ATT"]
    sim = tables.get("SIM")
    land = pd.DataFrame()
    if sim is not None and len(sim):
        s = time_window(sim, disarm_t - 60e6, disarm_t)
        h = s.Alt - float(sim.Alt.iloc[0])
        s = s[(h < 3.0) & (h > 0.3)]
        if len(s) > 2:
            land = s
    descent = float("nan")
    if len(land) > 2:
        dt = np.diff(land.TimeUS.to_numpy(float)) * 1e-6
        dh = -np.diff(land.Alt.to_numpy(float))
        descent = float(np.median(dh / dt))
    out = {
        "flight_time_s": (disarm_t - armed_t) * 1e-6,
        "cruise_speed_ms": float(cruise_gps.Spd.median()),
        "max_speed_ms": float(gps.Spd.max()),
        "takeoff_climb_ms": float((-pre.VZ).max()) if len(pre) else float("nan"),
        "land_descent_ms": descent,
        "cruise_throttle": float(time_window(ctun, c0, c1).ThO.median()),
        "hover_throttle_learned": float(time_window(ctun, armed_t, disarm_t).ThH.iloc[-1]),
        "acc_noise_ground": float(ground.AccZ.std()),
        "gyr_noise_ground": float(ground.GyrX.std()),
        "acc_z_std_cruise": float(cruise_imu.AccZ.std()),
        "vibe_x_cruise_imu0": float(time_window(vibe[vibe.IMU == 0], c0, c1).VibeX.mean()),
        "vibe_x_cruise_imu1": float(time_window(vibe[vibe.IMU == 1], c0, c1).VibeX.mean()),
        "pitch_cruise_deg": float(time_window(att, c0, c1).Pitch.median()),
        "rate_GPS_hz": _rate_hz(gps, None, armed_t, disarm_t),
        "rate_IMU_hz": _rate_hz(imu, "I", armed_t, disarm_t),
        "rate_RATE_hz": _rate_hz(tables["RATE"], None, armed_t, disarm_t),
        "rate_VIBE_hz": _rate_hz(vibe, "IMU", armed_t, disarm_t),
    }
    return out


#: metric -> (absolute tolerance, relative tolerance) for tlm vs SITL on the same mission
TOLERANCES: dict[str, tuple[float, float]] = {
    "flight_time_s": (0.0, 0.10),
    "cruise_speed_ms": (0.3, 0.0),
    "max_speed_ms": (0.3, 0.0),
    "takeoff_climb_ms": (0.4, 0.0),
    "land_descent_ms": (0.15, 0.0),
    "cruise_throttle": (0.03, 0.0),
    "hover_throttle_learned": (0.02, 0.0),
    "pitch_cruise_deg": (1.5, 0.0),
    "acc_noise_ground": (0.0, 0.3),
    "gyr_noise_ground": (0.0, 0.4),
    "vibe_x_cruise_imu0": (0.0, 0.4),
    "vibe_x_cruise_imu1": (0.0, 0.4),
    "rate_GPS_hz": (0.0, 0.02),
    "rate_IMU_hz": (0.0, 0.02),
    "rate_RATE_hz": (0.0, 0.02),
    "rate_VIBE_hz": (0.0, 0.02),
}


def compare(tlm: Mapping[str, float], sitl: Mapping[str, float]) -> pd.DataFrame:
    """Table of metric, tlm, sitl, difference, tolerance and whether it is within tolerance."""
    rows = []
    for k in sitl:
        a, b = tlm[k], sitl[k]
        tol = TOLERANCES.get(k)
        ok = None
        tol_txt = ""
        if tol is not None:
            lim = max(tol[0], tol[1] * abs(b))
            ok = bool(abs(a - b) <= lim)
            tol_txt = f"±{lim:.3g}"
        rows.append({"metric": k, "tlm": a, "sitl": b, "diff": a - b, "tolerance": tol_txt,
                     "ok": ok})
    return pd.DataFrame(rows)


def compare_with_reference(ref_bin: str, sidecar: str, seed: int = 11) -> pd.DataFrame:
    """Fly the reference log's own mission (from its sidecar) in tlm and compare the metrics."""
    from tlm_sim import Mission, fly
    from tlm_sim.flightlog import read_bin

    log = fly(Mission.from_sidecar(sidecar), seed=seed)
    ref = read_bin(ref_bin, types=["GPS", "IMU", "RATE", "VIBE", "CTUN", "ATT", "EV", "MODE",
                                   "SIM"])
    return compare(flight_metrics(log.tables), flight_metrics(ref))
