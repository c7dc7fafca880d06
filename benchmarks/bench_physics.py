"""Benchmark: real-time factor of the 1200 Hz physics alone (no sensors, EKF, autopilot, logs).

Runs :func:`tlm_sim.dynamics.body.run_ticks` (wind, air density, motors, rigid body, ground,
battery, sensor smoothing) for as many ticks as a paper-length flight at a constant motor PWM
that hovers (found by bisection first), 100 m up, and prints the best of several runs. Set beside
``bench_fly.py``'s loop figure it tells how much of the full stack's time the physics takes:
the full stack can never run faster than this.

    python benchmarks/bench_physics.py [--seconds 470] [--repeat 5]
"""

from __future__ import annotations

import argparse

import numpy as np
from _timing import best_of  # benchmarks/_timing.py (scripts run from this folder)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=470.0, help="simulated seconds per run")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()

    from tlm_sim.dynamics import layout as X
    from tlm_sim.dynamics.body import init_state, run_ticks, set_airborne
    from tlm_sim.dynamics.frame import F_FRAME_HEIGHT, build_frame
    from tlm_sim.flight import PHYSICS_DT_US
    from tlm_sim.profiles import profile_params
    from tlm_sim.rng import new_rng

    frame = build_frame(profile_params("current", None))
    dt = PHYSICS_DT_US * 1e-6
    n = int(args.seconds / dt)
    pwm = np.zeros(4)

    def run(ticks: int, pwm_us: float) -> np.ndarray:
        """The state after ``ticks`` physics ticks from 100 m up at ``pwm_us`` (the set-up
        before run_ticks takes microseconds)."""
        x = np.zeros(X.N_STATE)
        init_state(x, frame, 0.0)
        set_airborne(x, frame, 100.0, 0.4)
        pwm[:] = pwm_us
        run_ticks(x, pwm, frame, dt, 0.0, ticks, new_rng(1, 2))
        return x

    lo, hi = 1000.0, 2000.0  # hover PWM: no vertical velocity after 2 s
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        if run(int(2.0 / dt), mid)[X.VD] > 0.0:  # still sinking: more thrust
            lo = mid
        else:
            hi = mid
    hover = 0.5 * (lo + hi)
    climb = -(run(n, hover)[X.PD] + 100.0 + frame[F_FRAME_HEIGHT])
    best = best_of(lambda: run(n, hover), args.repeat)
    sim = n * dt
    print(f"physics only at hover PWM {hover:.1f} us ({climb:+.1f} m height change), {n} ticks "
          f"of {PHYSICS_DT_US} us ({sim:.0f} s simulated), best of {args.repeat}: "
          f"{best * 1e3:.1f} ms = {sim / best:.0f}x real time, {best / n * 1e9:.0f} ns per tick")


if __name__ == "__main__":
    main()
