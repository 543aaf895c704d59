#!/usr/bin/env python3
"""P(face) of Die 1 against its aluminium volume fraction, with 95% bands, to a PNG.

The seed study's sec. 5.4 sweep, scenes/paper/sweeps/volume-ratio.toml: Die 1's materials and face
map, rebuilt per point as a steel cube whose bottom slab, a fraction k/30 of its height, is
aluminium (face 1 on the steel side, face 6 on the aluminium side). Every point tosses the same
throws (common random numbers), so the curves are smooth.

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


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tosses", type=int, default=int(os.environ.get("DICESIM_EXAMPLE_TOSSES", 10000)),
                    help="tosses per point")
    ap.add_argument("--out", default="sweep_aluminium.png", help="PNG file to write")
    ap.add_argument("--sweep", default=str(REPO / "scenes/paper/sweeps/volume-ratio.toml"))
    args = ap.parse_args()

    sweep = dicesim.sweep_file(args.sweep, n=args.tosses)
    df = sweep.to_pandas() if _has_pandas() else None

    fig, ax = plt.subplots(figsize=(8, 5))
    x = sweep.values
    labels = sweep[0].labels
    for i, label in enumerate(labels):
        p = [r.p[i] for r in sweep.points]
        lo = [r.ci95[i, 0] for r in sweep.points]
        hi = [r.ci95[i, 1] for r in sweep.points]
        (line,) = ax.plot(x, p, marker=".", label=f"face {label}")
        ax.fill_between(x, lo, hi, color=line.get_color(), alpha=0.15, linewidth=0)
    ax.axhline(1 / len(labels), color="grey", linestyle=":", linewidth=1)
    ax.set_xlabel(sweep.key)
    ax.set_ylabel("P(face), 95% Wilson band")
    ax.set_title(f"{sweep.title}\n{args.tosses} tosses per point, fidelity {sweep[0].fidelity}")
    ax.legend(ncol=3)
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out} ({len(sweep)} points, {sweep.elapsed_s:.2f} s)")
    if df is not None:
        print(df.pivot(index="x", columns="face", values="p").round(4).to_string())


def _has_pandas():
    try:
        import pandas  # noqa: F401
        return True
    except ImportError:
        return False


if __name__ == "__main__":
    main()
