"""Regenerate the normal-flight section of docs/fidelity.md: tlm vs the genuine SITL log.

    python tools/fidelity_normal.py [--reference ../shared/reference/sitl] [--out docs/fidelity.md]

Flies normal_s11's own mission (from its sidecar) in tlm and compares flight metrics.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from tlm_process.reference import compare_with_reference

HEADER = """# Fidelity: tlm vs genuine ArduCopter SITL

Regenerate with `python tools/fidelity_normal.py` (the test `tests/test_reference_compare.py`
checks the same metrics against the tolerances below on every run).

## Normal flight: `normal_s11.bin` (ArduCopter 4.7.0-dev SITL) vs tlm flying the same mission

tlm flies the mission recorded in `normal_s11.json` (90 waypoints, 1215 m) with its default
parameters (the log's own parameter set) and seed 11. Phases: armed = EV 10 to EV 11; cruise =
AUTO from 20 s after its start to 60 s before disarming; ground = the 8 s before arming.

"""

NOTES = """
Notes:
* IMU noise: SITL's IMU1 matches SITL's stated base noise (0.01 m/s^2, 0.04 deg/s uniform);
  IMU0 in the reference logs shows half of it, so tlm scales IMU0's noise by `TLM_INS1_NSE_SC`
  0.5 (fitted, mechanism not identified).
* `acc_z_std_cruise` (no tolerance yet): tlm's vertical acceleration varies more in cruise than
  SITL's (0.09 vs 0.05 m/s^2). A likely cause, not yet verified: tlm's EKF has no output
  predictor (EKF3 blends corrections into its output over EK3_TAU_OUTPUT), so the controllers
  see small position steps at each GPS fusion. Left for the calibration issue.
* tlm arms at `TLM_ARM_TIME` (10 s after boot) instead of SITL's ~42 s (GPS and EKF start-up);
  the armed flight time above is unaffected.
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    here = Path(__file__).resolve().parents[1]
    ap.add_argument("--reference", default=str(here.parent / "shared" / "reference" / "sitl"))
    ap.add_argument("--out", default=str(here / "docs" / "fidelity.md"))
    args = ap.parse_args()
    ref = Path(args.reference)
    table = compare_with_reference(str(ref / "normal_s11.bin"), str(ref / "normal_s11.json"))
    lines = ["| metric | tlm | SITL | difference | tolerance | within |",
             "|---|---|---|---|---|---|"]
    for r in table.itertuples():
        ok = "" if r.ok is None else ("yes" if r.ok else "**no**")
        lines.append(f"| {r.metric} | {r.tlm:.4g} | {r.sitl:.4g} | {r.diff:+.3g} | {r.tolerance} "
                     f"| {ok} |")
    Path(args.out).write_text(HEADER + "\n".join(lines) + "\n" + NOTES)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
