"""The power module: the battery voltage and current as the autopilot's battery monitor reads
them.

SITL feeds the simulated battery's terminal voltage [V] and current [A] to the analog battery
monitor's pins (BATT_MONITOR 4) without noise or quantisation; tlm does the same, once per
main-loop tick, so the autopilot (``tlm_sim.control.battery``, the mixer's voltage
compensation) reads a sensor, not the truth state.
"""

from tlm_sim._jit import tick_jit
from tlm_sim.dynamics import layout as X
from tlm_sim.sensors import layout as S


@tick_jit
def power_module_read(s, x):
    """Sample the battery's voltage and current from the truth state x into s (PM_VOLT [V],
    PM_CURR [A])."""
    s[S.PM_VOLT] = x[X.BATT_V]
    s[S.PM_CURR] = x[X.BATT_I]
