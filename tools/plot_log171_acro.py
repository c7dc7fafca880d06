"""docs/img/log171_acro_flip.png: the real log171's ACRO part and tlm's replay of it.

log171 (dronekit/dronekit-la-testdata, CC BY-SA 3.0) switches from LOITER to ACRO at 217.2 s
and flips at 239.0 s after the pilot's full pitch stick back, then forward. tlm re-flies the
log from its RCIN (``tlm crosscheck``'s replay) with the log's ACRO settings; this draws roll,
pitch and the roll / pitch sticks of both from 212 to 245 s::

    PYTHONPATH=. .venv/bin/python tools/plot_log171_acro.py [--log PATH] [--out PNG]
"""

from __future__ import annotations

import argparse
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LOG = ROOT.parent / "shared" / "reference" / "real" / "log171.bin"
WINDOW_S = (212.0, 245.0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--log", type=Path, default=LOG, help="log171.bin")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "img" / "log171_acro_flip.png")
    args = ap.parse_args()

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from tlm_process.pilot.replay import replay
    from tlm_sim import ardupilot as AP

    r = replay(args.log)
    ref, ours = r["_tables"], r["_log"].tables
    a, b = WINDOW_S
    fig, axes = plt.subplots(3, 1, figsize=(10, 7.5), sharex=True)
    for ax, col in zip(axes, ("Roll", "Pitch"), strict=False):
        for tables, name, style in ((ref, "log171", "-"), (ours, "tlm, re-flown", "--")):
            att = tables["ATT"]
            w = att[(att.TimeUS >= a * 1e6) & (att.TimeUS <= b * 1e6)]
            ax.plot(w.TimeUS * 1e-6, w[col], style, lw=1.2, label=name)
        ax.set_ylabel(f"{col.lower()} [deg]")
        ax.grid(alpha=0.3)
    rc = ref["RCIN"]
    w = rc[(rc.TimeUS >= a * 1e6) & (rc.TimeUS <= b * 1e6)]
    for ch, name in (("C1", "roll stick"), ("C2", "pitch stick (high = back)")):
        axes[2].plot(w.TimeUS * 1e-6, w[ch], lw=1.2, label=f"RCIN {ch}, {name}")
    axes[2].set_ylabel("RCIN [us]")
    axes[2].grid(alpha=0.3)
    acro = ref["MODE"]
    t_acro = float(acro.TimeUS[acro.ModeNum == AP.MODE_ACRO].iloc[0]) * 1e-6
    for ax in axes:
        ax.axvspan(t_acro, b, color="0.93", zorder=0)
        ax.legend(loc="lower left", fontsize=8)
    axes[0].text(t_acro + 0.3, axes[0].get_ylim()[1] * 0.85, "ACRO (ACRO_TRAINER 0)", fontsize=9)
    axes[-1].set_xlabel("log time [s]")
    fig.suptitle("log171 (dronekit-la-testdata, CC BY-SA 3.0): the pilot's ACRO flip, "
                 "and tlm re-flown from its RCIN")
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=90)
    plt.close(fig)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
