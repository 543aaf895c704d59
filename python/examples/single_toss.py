#!/usr/bin/env python3
"""One toss of Die 1: the centre of mass's height and the die's energy against time, to a PNG.

Between impacts the centre of mass flies ballistically and the energy (kinetic, translational and
rotational, plus m g z) is constant; each impact takes some away.

    PYTHONPATH=build/python /usr/bin/python3 python/examples/single_toss.py --index 77
"""
import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt
import numpy as np

import dicesim

REPO = Path(__file__).resolve().parents[2]


def height_curve(t, samples_per_flight=60):
    """The COM height z(t) from release to the last impact, sampled along each ballistic flight."""
    g = t["gravity"]
    imp = t["impacts"]
    # Each flight starts from the release or a rebound and ends at the next contact.
    starts = [(0.0, t["initial_state"]["position"][2], t["initial_state"]["velocity"][2])]
    starts += [(ti, z, vz) for ti, z, vz in zip(imp["t"], imp["after"]["position"][:, 2], imp["after"]["velocity"][:, 2])]
    ends = list(imp["t"]) + [t["t_end"]]
    times, heights = [], []
    for (t0, z0, vz0), t1 in zip(starts, ends):
        s = np.linspace(0.0, t1 - t0, samples_per_flight)
        times.append(t0 + s)
        heights.append(z0 + vz0 * s - 0.5 * g * s**2)
    return np.concatenate(times), np.concatenate(heights)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--index", type=int, default=77, help="toss index (the same toss a run with --seed makes)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", default="single_toss.png", help="PNG file to write")
    ap.add_argument("--scene", default=str(REPO / "scenes/paper/die1.toml"))
    args = ap.parse_args()

    scene = dicesim.load_scene(args.scene)
    t = dicesim.toss_one(scene, args.index, seed=args.seed)
    imp = t["impacts"]
    time, z = height_curve(t)

    # Energy is a step function: constant in flight, lower after each impact.
    et = np.concatenate([[0.0], np.repeat(imp["t"], 2), [t["t_end"]]])
    ev = np.concatenate([[t["initial_state"]["energy"]],
                         np.column_stack([imp["before"]["energy"], imp["after"]["energy"]]).ravel(),
                         [imp["after"]["energy"][-1]]])

    fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
    ax1.plot(time, 1e3 * z)
    ax1.plot(imp["t"], 1e3 * imp["before"]["position"][:, 2], "o", markersize=3, label="impacts")
    ax1.set_ylabel("COM height (mm)")
    ax1.legend()
    ax2.plot(et, ev)
    ax2.set_yscale("log")
    ax2.set_xlabel("time since release (s)")
    ax2.set_ylabel("energy (J)")
    ax1.set_title(f"Die 1, toss {args.index} (seed {args.seed}): {t['bounces']} impacts, face {t['face']} up "
                  f"({t['status']}, fidelity {t['fidelity']})")
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}: {t['bounces']} impacts, face {t['face']}, {t['t_end']:.3f} s")


if __name__ == "__main__":
    main()
