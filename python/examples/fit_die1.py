#!/usr/bin/env python3
"""Die 1's steel density fitted to the seed's 501 hand throws, and how many throws would settle it.

dicesim.fit finds the density that makes the simulated Die 1 match the experiment's face counts
(data/seed-experiments/die1_counts.csv), with a 95% profile-likelihood interval; dicesim.power says
how many throws a chi-square test needs to tell the simulated Die 1 from a fair die. Writes a PNG:
observed frequencies with 95% Wilson bars beside the fitted probabilities.

    PYTHONPATH=build/python /usr/bin/python3 python/examples/fit_die1.py            # impulse, ~15-30 s

DICESIM_EXAMPLE_TOSSES set (the tests): the cheap `static` fidelity and few tosses.
"""
import argparse
import math
import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt

import dicesim

REPO = Path(__file__).resolve().parents[2]


def wilson(k, n, z=1.959963984540054):
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return centre - half, centre + half


def main():
    quick = "DICESIM_EXAMPLE_TOSSES" in os.environ
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fidelity", default="static" if quick else "impulse")
    ap.add_argument("--out", default="fit_die1.png", help="PNG file to write")
    args = ap.parse_args()

    scene = str(REPO / "scenes/paper/die1.toml")
    counts = str(REPO / "data/seed-experiments/die1_counts.csv")
    fit = dicesim.fit(scene, counts, {"materials.steel.density": (3000, 20000)}, fidelity=args.fidelity,
                      n=2000 if quick else 0)
    p = fit["params"][0]
    print(f"steel density {p['estimate']:.0f} kg/m^3, 95% interval [{p['ci95'][0]:.0f}, {p['ci95'][1]:.0f}] "
          f"(measured: 7848); goodness of fit p = {fit['gof']['p_value']:.2f}; "
          f"{fit['simulated_tosses']} tosses in {fit['elapsed_s']:.1f} s")

    need = dicesim.power(dicesim.load_scene(scene), against=dicesim.load_scene(str(REPO / "scenes/fair.toml")),
                         fidelity=args.fidelity, n=2000 if quick else 100000)
    print(f"throws to tell Die 1 from a fair die (chi-square, alpha 0.05, power 0.8): {need['n_exact']}")

    labels = [f["label"] for f in fit["fitted"]]
    observed = [f["observed"] for f in fit["fitted"]]
    n = sum(observed)
    fig, ax = plt.subplots(figsize=(8, 5))
    freq = [k / n for k in observed]
    bars = [wilson(k, n) for k in observed]
    ax.bar(labels, freq, color="#9ecae1", label=f"observed ({n} hand throws)")
    ax.errorbar(labels, freq, yerr=[[f - b[0] for f, b in zip(freq, bars)], [b[1] - f for f, b in zip(freq, bars)]],
                fmt="none", ecolor="black", capsize=4, label="95% Wilson")
    ax.plot(labels, [f["p"] for f in fit["fitted"]], "o", color="#d62728",
            label=f"fitted ({args.fidelity}, steel {p['estimate']:.0f} kg/m³)")
    ax.axhline(1 / 6, color="grey", linestyle=":", linewidth=1)
    ax.set_xlabel("face")
    ax.set_ylabel("P(face)")
    ax.set_title(f"Die 1: steel density {p['estimate']:.0f} [{p['ci95'][0]:.0f}, {p['ci95'][1]:.0f}] kg/m³, "
                 f"chi-square p = {fit['gof']['p_value']:.2f}")
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
