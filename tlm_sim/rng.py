"""A small, fast, seedable random generator for per-sample sensor noise inside numba code.

xorshift64* (Vigna 2016) with its state in a one-element uint64 array, seeded through
splitmix64. The IMUs draw ~10^4 numbers per simulated second and the wind turbulence two
Gaussians and a direction every physics tick: numba's ``np.random`` (a Mersenne Twister behind
a thread-local state lookup) made the turbulence a large share of the physics tick.
"""

import math

import numpy as np

from tlm_sim._jit import tick_jit

_MUL = np.uint64(2685821657736338717)
_INV53 = 1.0 / 9007199254740992.0  # 2^-53


#: first stream id of the sensor noise streams (ids 1 and 2 are the old shared sensor stream
#: and the wind turbulence)
SENSOR_STREAM_BASE = 16


def new_streams(seed: int, n: int, base: int = SENSOR_STREAM_BASE) -> np.ndarray:
    """``n`` independent generator states for ``seed`` (streams ``base .. base + n - 1``), as
    the rows of an (n, 1) array: row ``k`` is passed to :func:`uniform_pm1` as ``rng[k]``."""
    return np.stack([new_rng(seed, base + k) for k in range(n)])


def new_rng(seed: int, stream: int = 0) -> np.ndarray:
    """Generator state for (seed, stream): splitmix64 of the pair, never zero."""
    z = (int(seed) * 0x9E3779B97F4A7C15 + int(stream) * 0xD1B54A32D192ED03 + 0x632BE59BD9B4E019)
    z &= 0xFFFFFFFFFFFFFFFF
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & 0xFFFFFFFFFFFFFFFF
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & 0xFFFFFFFFFFFFFFFF
    z ^= z >> 31
    return np.array([z or 1], dtype=np.uint64)


@tick_jit
def uniform_pm1(state):
    """Uniform draw in [-1, 1) (SITL's rand_float range); advances state[0]."""
    x = state[0]
    x ^= x >> np.uint64(12)
    x ^= x << np.uint64(25)
    x ^= x >> np.uint64(27)
    state[0] = x
    r = (x * _MUL) >> np.uint64(11)
    return 2.0 * (r * _INV53) - 1.0


@tick_jit
def _disc_point(state, s_min):
    """A point (u, v) drawn uniformly in the unit disc by rejection, with s = u^2 + v^2 in
    (s_min, 1); advances state[0]."""
    while True:
        u = uniform_pm1(state)
        v = uniform_pm1(state)
        s = u * u + v * v
        if s_min < s < 1.0:
            return u, v, s


@tick_jit
def normal_pair(state):
    """Two independent standard normal draws (Marsaglia's polar method); advances state[0]."""
    u, v, s = _disc_point(state, 0.0)
    f = math.sqrt(-2.0 * math.log(s) / s)
    return u * f, v * f


@tick_jit
def unit_pair(state):
    """A direction drawn uniformly on the unit circle, as (cos, sin) of a uniform angle,
    without trigonometry (a point drawn in the unit disc, normalised); advances state[0]."""
    u, v, s = _disc_point(state, 1e-12)
    r = 1.0 / math.sqrt(s)
    return u * r, v * r
