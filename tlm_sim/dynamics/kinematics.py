"""Translation step shared by the rigid body and the sensor-smoothing shadow (numba, scalar)."""

from __future__ import annotations

import numpy as np

from tlm_sim._jit import tick_jit
from tlm_sim.dynamics import layout as X

# step_translation's layout: velocity three slots after position, for the truth and the shadow
assert X.VN == X.PN + 3 and X.SVN == X.SPN + 3


@tick_jit
def step_translation(x: np.ndarray, p0: int, an: float, ae: float, ad: float,
                     dt: float) -> tuple[float, float, float]:
    """Semi-implicit Euler over ``dt`` [s]: the NED velocity ``x[p0+3:p0+6]`` [m/s] takes the
    acceleration (an, ae, ad) [m/s^2] first, then the position ``x[p0:p0+3]`` [m] moves with
    the new velocity. Returns the new velocity."""
    vn = x[p0 + 3] + an * dt
    ve = x[p0 + 4] + ae * dt
    vd = x[p0 + 5] + ad * dt
    x[p0 + 3], x[p0 + 4], x[p0 + 5] = vn, ve, vd
    x[p0] += vn * dt
    x[p0 + 1] += ve * dt
    x[p0 + 2] += vd * dt
    return vn, ve, vd
