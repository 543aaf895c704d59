#!/usr/bin/env python3
"""P(face) of Die 1 against its aluminium volume fraction, with 95% bands, to a PNG.

Die 1 (scenes/paper/die1.toml) rebuilt as a steel cube whose bottom slab, a fraction x of its
height, is aluminium (as scenes/paper/sweeps/volume-ratio.toml does): x = 1/30 ... 29/30. Every
point tosses the same throws (common random numbers), so the curves are smooth.

    PYTHONPATH=build/python /usr/bin/python3 python/examples/sweep_aluminium.py --tosses 20000

DICESIM_EXAMPLE_TOSSES overrides the default number of tosses per point (the tests use it).
"""
import argparse
import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt

import dicesim

REPO = Path(__file__).resolve().parents[2]
# One aluminium region below the cut z <= offset; offset = 0.03 x - 0.015 m for fraction x.
SLAB = '[{ material = "aluminium", cuts = [{ normal = [0, 0, 1], offset = {} }] }]'


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tosses", type=int, default=int(os.environ.get("DICESIM_EXAMPLE_TOSSES", 10000)),
                    help="tosses per point")
    ap.add_argument("--out", default="sweep_aluminium.png", help="PNG file to write")
    ap.add_argument("--scene", default=str(REPO / "scenes/paper/die1.toml"))
    args = ap.parse_args()

    scene = dicesim.load_scene(args.scene, set={"die.material": "steel"})
    sweep = dicesim.sweep(scene, "die.regions", "1/30:29/30:1/30", args.tosses,
                          template=SLAB, scale=0.03, shift=-0.015)

    fig, ax = plt.subplots(figsize=(8, 5))
    x = sweep.values
    for i, label in enumerate(sweep[0].labels):
        p = [r.p[i] for r in sweep.points]
        lo = [r.ci95[i, 0] for r in sweep.points]
        hi = [r.ci95[i, 1] for r in sweep.points]
        (line,) = ax.plot(x, p, marker=".", label=f"face {label}")
        ax.fill_between(x, lo, hi, color=line.get_color(), alpha=0.15, linewidth=0)
    ax.axhline(1 / len(sweep[0].labels), color="grey", linestyle=":", linewidth=1)
    ax.set_xlabel("aluminium volume fraction x (bottom slab; face 1 on the steel side)")
    ax.set_ylabel("P(face), 95% Wilson band")
    ax.set_title(f"Die 1, steel/aluminium slab: {args.tosses} tosses per point, fidelity {sweep[0].fidelity}")
    ax.legend(ncol=3)
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out} ({len(sweep)} points, {sweep.elapsed_s:.2f} s)")


if __name__ == "__main__":
    main()
