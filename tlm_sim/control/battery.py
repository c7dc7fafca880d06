"""ArduPilot's battery monitor and ArduCopter's battery failsafe (sitl-faults.md §7).

Monitor (AP_BattMonitor with SITL's analog sensor, ``BATT_MONITOR`` 4), updated at 10 Hz from
the simulated battery's voltage and current: consumed charge (mAh) and energy (Wh) integrated
from the current, remaining capacity in percent of ``BATT_CAPACITY`` (whole percent, rounded
down, 100 when the capacity is 0), and the internal-resistance estimate that gives the resting
voltage ``VoltR = V + I R``:

* it learns only while current flows and the current differs from its low-passed value;
* a positive ratio -(V - V_filt) / (I - I_filt) pulls the estimate with a weight of
  0.1 |I - I_filt| / I_max (I_max: largest current so far), so a step of the voltage without
  the current that explains it (SIM_BATT_VOLTAGE changed in flight) moves it by about
  0.1 dV / I_max per update until the filters catch up: battery_s45 goes from 0.002 to
  0.027 ohm at 12.6 -> 10.2 V and to 0.049 ohm when the voltage comes back, which is why its
  VoltR reads 11.14 V in the window and 13.96 V afterwards;
* it is capped by the voltage drop from the highest voltage seen over the current rise since;
* voltage and current are low-passed with a 0.5 s time constant (at most half the step).

tlm's SITL battery holds its voltage exactly (no sag at infinite capacity), so the estimator
starts at the resistance the fitted sag ``TLM_BATT_SAG_HOV`` implies at the hover current
``TLM_REF_CURR`` and with its filters at the first reading: in a flight with a steady
voltage it never moves and the motors' voltage compensation (:mod:`tlm_sim.control.mixer`)
is exactly the fitted one. The mixer adds ``I (R - R0)`` to its resting-voltage estimate.

Failsafe (armed only, 10 Hz, in ArduPilot's order): critical voltage (below ``BATT_CRT_VOLT``
for longer than ``BATT_LOW_TIMER``), critical remaining capacity (``BATT_CRT_MAH``), low
voltage (``BATT_LOW_VOLT`` for longer than ``BATT_LOW_TIMER``), low capacity
(``BATT_LOW_MAH``); ``BATT_LOW_TIMER`` 0 disables the voltage checks. The state only
escalates (none < low < critical) and is latched: a voltage that returns clears nothing and
logs no ERR 6/0. On an escalation whose action (``BATT_FS_LOW_ACT`` / ``BATT_FS_CRT_ACT``) is
at least as severe as any taken before (Copter's priority: Terminate, Land / Brake->Land,
RTL, SmartRTL->Land, SmartRTL->RTL, DO_LAND_START->RTL, None): ERR 6/1 and the action is
handed to the vehicle logic (``BATT_FS_ACT``, taken by :mod:`tlm_sim.control.modes`). The
MSG texts ("Battery 1 is low 10.20V used 977 mAh", "Battery Failsafe") are rendered from the
ERR row and BAT (:mod:`tlm_sim.flightlog.texts`): a second ERR 6/1 of a flight reads
"critical".
"""

from tlm_sim import ardupilot as AP
from tlm_sim._jit import tick_jit
from tlm_sim.control import events as E
from tlm_sim.control import layout as C

MONITOR_DT_S = 0.1  # AP_BattMonitor read rate (10 Hz)
RES_FILT_TC_S = 0.5  # time constant of the estimator's voltage and current filters
RES_GAIN = 0.1  # resistance estimate weight per relative current change

FS_NONE, FS_LOW, FS_CRITICAL = 0, 1, 2

# BATT_FS_*_ACT values (Copter's FailsafeAction)
ACT_NONE, ACT_LAND, ACT_RTL, ACT_SMARTRTL_RTL, ACT_SMARTRTL_LAND = 0, 1, 2, 3, 4
ACT_TERMINATE, ACT_DO_LAND_START, ACT_BRAKE_LAND = 5, 6, 7
#: priority rank of each action (lower = more severe); an escalation acts only when its
#: action ranks at least as high as every action taken before
ACTION_RANK = (6.0, 1.0, 2.0, 4.0, 3.0, 0.0, 5.0, 1.0)
NO_RANK = 99.0


@tick_jit
def battery_monitor_init(c, g, volt):
    """Monitor state before its first reading: estimator at the fitted resistance, filters at
    ``volt`` [V], no failsafe."""
    c[C.BM_RES] = g[C.G_BATT_RES0]
    c[C.BM_VFILT] = volt
    c[C.BM_IFILT] = 0.0
    c[C.BM_VREF] = volt
    c[C.BM_IREF] = 0.0
    c[C.BM_LAST_T] = -1.0
    c[C.BATT_LOW_T0] = -1.0
    c[C.BATT_CRT_T0] = -1.0
    c[C.BATT_FS_RANK] = NO_RANK
    c[C.BATT_FS_ACT] = -1.0


@tick_jit
def _resistance_update(c, dt, volt, curr):
    """One step of the internal-resistance estimator (see the module docstring)."""
    if curr <= 0.0:
        return
    c[C.BM_IMAX] = max(c[C.BM_IMAX], curr)
    di = curr - c[C.BM_IFILT]
    if di == 0.0:
        return
    if volt > c[C.BM_VREF]:
        c[C.BM_VREF] = volt
        c[C.BM_IREF] = curr
    a_filt = min(max(dt / (dt + RES_FILT_TC_S), 0.0), 0.5)
    a_res = min(1.0, RES_GAIN * abs(di) / c[C.BM_IMAX])
    est = -(volt - c[C.BM_VFILT]) / di
    if est > 0.0:
        c[C.BM_RES] += a_res * (est - c[C.BM_RES])
    if c[C.BM_VREF] > volt and curr > c[C.BM_IREF]:
        c[C.BM_RES] = min(c[C.BM_RES], (c[C.BM_VREF] - volt) / (curr - c[C.BM_IREF]))
    c[C.BM_VFILT] += a_filt * (volt - c[C.BM_VFILT])
    c[C.BM_IFILT] += a_filt * (curr - c[C.BM_IFILT])


@tick_jit
def _below_for(c, slot, t_s, volt, threshold, timer):
    """Voltage timer of one threshold: True once ``volt`` has stayed below ``threshold`` for
    longer than ``timer`` [s] (``slot``: the time it went below, -1 while above)."""
    if threshold <= 0.0 or volt >= threshold:
        c[slot] = -1.0
        return False
    if c[slot] < 0.0:
        c[slot] = t_s
        return False
    return timer > 0.0 and t_s - c[slot] > timer + 1e-6


@tick_jit
def failsafe_state(c, g, t_s):
    """The battery state this reading gives (FS_*), in ArduPilot's order of checks."""
    volt = c[C.BM_VOLT]
    timer = g[C.G_BATT_LOW_TIMER]
    remaining = g[C.G_BATT_CAPACITY] - c[C.BM_MAH]
    if _below_for(c, C.BATT_CRT_T0, t_s, volt, g[C.G_BATT_CRT_VOLT], timer):
        return FS_CRITICAL
    if g[C.G_BATT_CRT_MAH] > 0.0 and remaining < g[C.G_BATT_CRT_MAH]:
        return FS_CRITICAL
    if _below_for(c, C.BATT_LOW_T0, t_s, volt, g[C.G_BATT_LOW_VOLT], timer):
        return FS_LOW
    if g[C.G_BATT_LOW_MAH] > 0.0 and remaining < g[C.G_BATT_LOW_MAH]:
        return FS_LOW
    return FS_NONE


@tick_jit
def battery_monitor(c, g, t_us, volt, curr, ev):
    """The 10 Hz battery monitor and failsafe check at ``t_us``; ``volt`` [V], ``curr`` [A]:
    the simulated battery. Logs ERR 6/1 on an escalation that acts and leaves the action in
    ``c[BATT_FS_ACT]``."""
    t_s = t_us * 1e-6
    if t_s < c[C.BM_NEXT_T]:
        return
    c[C.BM_NEXT_T] = t_s + MONITOR_DT_S - 1e-7
    if c[C.BM_VREF] <= 0.0:
        battery_monitor_init(c, g, volt)
    dt = t_s - c[C.BM_LAST_T] if c[C.BM_LAST_T] >= 0.0 else 0.0
    c[C.BM_LAST_T] = t_s
    c[C.BM_VOLT] = volt
    c[C.BM_CURR] = curr
    mah = curr * dt / 3.6
    c[C.BM_MAH] += mah
    c[C.BM_WH] += 0.001 * mah * volt
    cap = g[C.G_BATT_CAPACITY]
    c[C.BM_REMPCT] = 100.0 if cap <= 0.0 else float(
        int(min(max(100.0 * (cap - c[C.BM_MAH]) / cap, 0.0), 100.0)))
    _resistance_update(c, dt, volt, curr)
    if c[C.ARMED] == 0.0:
        c[C.BATT_LOW_T0] = -1.0
        c[C.BATT_CRT_T0] = -1.0
        return
    state = failsafe_state(c, g, t_s)
    if state <= c[C.BATT_FS]:
        return
    c[C.BATT_FS] = state
    act = g[C.G_BATT_FS_CRT_ACT] if state == FS_CRITICAL else g[C.G_BATT_FS_LOW_ACT]
    rank = ACTION_RANK[int(act)]
    if rank <= c[C.BATT_FS_RANK]:
        c[C.BATT_FS_RANK] = rank
        E.log_err(ev, t_us, AP.ERR_FAILSAFE_BATT, AP.ERR_CODE_FAILSAFE)
        c[C.BATT_FS_ACT] = act


@tick_jit
def resting_voltage(c):
    """The monitor's resting-voltage estimate V + I R [V] (BAT.VoltR)."""
    return c[C.BM_VOLT] + c[C.BM_CURR] * c[C.BM_RES]
