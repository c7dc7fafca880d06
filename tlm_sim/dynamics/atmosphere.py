"""1976 US Standard Atmosphere, troposphere only (ArduPilot ``AP_Baro_atmosphere``).

Geometric altitude ``h`` [m AMSL] is converted to geopotential altitude
``h' = R0 h / (R0 + h)``; temperature falls linearly at 6.5 K/km from 288.15 K; pressure and
density follow the hydrostatic power laws. Valid below 11 km (the copter never gets there).
All functions are scalar ``@njit`` functions usable from the flight loop and from Python.
"""

from __future__ import annotations

from tlm_sim._jit import tick_jit
from tlm_sim.ardupilot import GRAVITY_MSS

#: sea-level standard pressure [Pa], temperature [K], density [kg/m^3]
P0_PA: float = 101325.0
T0_K: float = 288.15
RHO0: float = 1.225
#: tropospheric temperature lapse rate [K/m]
LAPSE_K_PER_M: float = 0.0065
#: specific gas constant of dry air [J/(kg K)]
R_AIR: float = 287.053
#: effective Earth radius for geopotential altitude [m]
R0_M: float = 6356766.0
#: pressure exponent g / (L R) of the troposphere power law
_P_EXP: float = GRAVITY_MSS / (LAPSE_K_PER_M * R_AIR)


@tick_jit
def temperature_ratio(alt_amsl_m: float) -> float:
    """Return ``T / T0`` at geometric altitude ``alt_amsl_m`` [m AMSL] (dimensionless)."""
    hgp = R0_M * alt_amsl_m / (R0_M + alt_amsl_m)
    return (T0_K - LAPSE_K_PER_M * hgp) / T0_K


@tick_jit
def air_density(alt_amsl_m: float) -> float:
    """Air density [kg/m^3] at geometric altitude ``alt_amsl_m`` [m AMSL]."""
    return RHO0 * temperature_ratio(alt_amsl_m) ** (_P_EXP - 1.0)


@tick_jit
def air_density_gradient(alt_amsl_m: float) -> float:
    """Derivative of the air density with geometric altitude [kg/m^4] at ``alt_amsl_m``."""
    theta = temperature_ratio(alt_amsl_m)
    dhgp_dh = (R0_M / (R0_M + alt_amsl_m)) ** 2
    return RHO0 * (_P_EXP - 1.0) * theta ** (_P_EXP - 2.0) * (-LAPSE_K_PER_M / T0_K) * dhgp_dh


@tick_jit
def pressure_temperature(alt_amsl_m: float) -> tuple[float, float]:
    """Static pressure [Pa] and temperature [K] at geometric altitude ``alt_amsl_m`` [m AMSL]."""
    theta = temperature_ratio(alt_amsl_m)
    return P0_PA * theta**_P_EXP, T0_K * theta


@tick_jit
def eas_to_tas(alt_amsl_m: float) -> float:
    """Equivalent-to-true airspeed ratio ``sqrt(rho0 / rho)`` at ``alt_amsl_m`` [m AMSL]."""
    return (RHO0 / air_density(alt_amsl_m)) ** 0.5
