"""SITL battery model (ardupilot-reference.md §1.11).

Infinite capacity (``capacity <= 0``, the SITL default): the terminal voltage is
``SIM_BATT_VOLTAGE`` through a 10 Hz low-pass filter. Finite capacity: the resting voltage is
read from a one-cell LiPo discharge curve scaled so that a full cell equals the frame's
``maxVoltage``, minus ``I R``; the remaining charge is integrated from the current; the
terminal voltage is filtered at 10 Hz too. A change of ``SIM_BATT_VOLTAGE`` re-initialises the
battery (filter reset, state of charge read back from the curve), as SITL does.

State in ``x``: ``BATT_V`` terminal voltage [V], ``BATT_I`` current [A], ``BATT_AH`` charge
consumed since start [Ah], ``BATT_VREST`` resting voltage [V], ``BATT_REM_AH`` remaining
charge [Ah], ``BATT_VSET`` the SIM_BATT_VOLTAGE the battery was initialised to [V].
"""

from __future__ import annotations

import math

import numpy as np

from tlm_sim._jit import tick_jit
from tlm_sim.dynamics import layout as X
from tlm_sim.dynamics.frame import F_BATT_CAP_AH, F_BATT_RES, F_BATT_VOLT, F_MAX_VOLT

#: cut-off frequency of the terminal-voltage filter [Hz]
VOLTAGE_FILTER_HZ: float = 10.0

# One-cell LiPo discharge curve: cell voltage [V] and state of charge [%], descending.
_CELL_V = np.array(
    [
        4.173, 4.112, 4.085, 4.071, 4.039, 3.987, 3.943, 3.908, 3.887, 3.854,
        3.833, 3.801, 3.783, 3.742, 3.715, 3.679, 3.636, 3.588, 3.543, 3.503,
        3.462, 3.379, 3.296, 3.218, 3.165, 3.091, 2.977, 2.8, 2.7, 2.5,
        2.3, 2.1, 1.9, 1.6, 1.3, 1.0, 0.6, 0.3, 0.01, 0.001,
    ]
)  # fmt: skip
_CELL_SOC = np.array(
    [
        100.0, 96.15, 92.31, 88.46, 84.62, 80.77, 76.92, 73.08, 69.23, 65.38,
        61.54, 57.69, 53.85, 50.0, 46.15, 42.31, 38.46, 34.62, 30.77, 26.92,
        23.08, 19.23, 15.38, 11.54, 7.69, 3.85, 2.0, 1.5, 1.3, 1.2,
        1.1, 1.0, 0.9, 0.8, 0.7, 0.6, 0.4, 0.2, 0.01, 0.001,
    ]
)  # fmt: skip


@tick_jit
def resting_voltage(soc_pct: float, max_voltage: float) -> float:
    """Resting (open-circuit) pack voltage [V] at state of charge ``soc_pct`` [%]."""
    full = _CELL_V[0]
    for i in range(1, _CELL_V.shape[0]):
        if soc_pct >= _CELL_SOC[i]:
            frac = (soc_pct - _CELL_SOC[i]) / (_CELL_SOC[i - 1] - _CELL_SOC[i])
            cell = _CELL_V[i] + frac * (_CELL_V[i - 1] - _CELL_V[i])
            return cell / full * max_voltage
    return 0.001


@tick_jit
def soc_from_voltage(voltage: float, max_voltage: float) -> float:
    """State of charge [%] whose resting voltage is ``voltage`` [V] (inverse of the curve)."""
    cell = voltage / max_voltage * _CELL_V[0]
    for i in range(1, _CELL_V.shape[0]):
        if cell >= _CELL_V[i]:
            frac = (cell - _CELL_V[i]) / (_CELL_V[i - 1] - _CELL_V[i])
            return _CELL_SOC[i] + frac * (_CELL_SOC[i - 1] - _CELL_SOC[i])
    return 0.0


@tick_jit
def reset_battery(x: np.ndarray, frame: np.ndarray) -> None:
    """(Re)initialise the battery to ``SIM_BATT_VOLTAGE`` (keeps the consumed-charge count)."""
    v = frame[F_BATT_VOLT]
    x[X.BATT_V] = v
    x[X.BATT_VSET] = v
    cap = frame[F_BATT_CAP_AH]
    if cap > 0.0:
        x[X.BATT_REM_AH] = cap * 0.01 * soc_from_voltage(v, frame[F_MAX_VOLT])
        x[X.BATT_VREST] = resting_voltage(100.0 * x[X.BATT_REM_AH] / cap, frame[F_MAX_VOLT])
    else:
        x[X.BATT_REM_AH] = 0.0
        x[X.BATT_VREST] = v


@tick_jit
def init_battery(x: np.ndarray, frame: np.ndarray) -> None:
    """Initialise the battery state at the start of a flight (no charge consumed, no load)."""
    x[X.BATT_I] = 0.0
    x[X.BATT_AH] = 0.0
    reset_battery(x, frame)


@tick_jit
def update_battery(x: np.ndarray, frame: np.ndarray, current: float, dt: float) -> None:
    """Advance the battery by ``dt`` [s] under load ``current`` [A]; updates the BATT_* state."""
    if frame[F_BATT_VOLT] != x[X.BATT_VSET]:
        reset_battery(x, frame)
    x[X.BATT_I] = current
    dah = current * dt / 3600.0
    x[X.BATT_AH] += dah
    cap = frame[F_BATT_CAP_AH]
    if cap > 0.0:
        rem = max(x[X.BATT_REM_AH] - dah, 0.0)
        x[X.BATT_REM_AH] = rem
        vrest = resting_voltage(100.0 * rem / cap, frame[F_MAX_VOLT])
        x[X.BATT_VREST] = vrest
        target = vrest - current * frame[F_BATT_RES]
    else:
        target = frame[F_BATT_VOLT]
        x[X.BATT_VREST] = target
    alpha = dt / (dt + 1.0 / (2.0 * math.pi * VOLTAGE_FILTER_HZ))
    x[X.BATT_V] += alpha * (target - x[X.BATT_V])
