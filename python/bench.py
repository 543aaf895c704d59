#!/usr/bin/env python3
"""The module's two speed targets (reported, never asserted in tests):

1. calling overhead: dicesim.toss(scene, 1) after the scene is loaded (target <= 50 us);
2. a 10^6-toss `paper` run of Die 1 from Python against the CLI (target: within 2%).

    PYTHONPATH=build/python /usr/bin/python3 python/bench.py [--tosses 1000000] [--threads 2] [--repeat 3]

Runs alternate (CLI, Python, CLI, Python, ...) so that both see the same machine load; the CLI's
time is its own `elapsed_s` (the run, not the process start), as is the module's. CPU seconds
(all threads; the CLI's include its start and scene load) are printed too: on a machine shared
with other work they vary far less than wall-clock times.
"""
import argparse
import json
import os
import resource
import statistics
import subprocess
import time
import timeit
from pathlib import Path

import dicesim

REPO = Path(__file__).resolve().parents[1]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="scenes/paper/die1.toml")
    ap.add_argument("--tosses", type=int, default=1_000_000)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--cli", default=str(REPO / "build/apps/dicesim"))
    args = ap.parse_args()
    os.chdir(REPO)
    print("load:", os.getloadavg())

    scene = dicesim.load_scene(args.scene)
    t = timeit.Timer(lambda: dicesim.toss(scene, 1))
    n, _ = t.autorange()
    per_call = [x / n * 1e6 for x in t.repeat(7, n)]
    print(f"toss(scene, 1): best {min(per_call):.1f} us, median {statistics.median(per_call):.1f} us ({n} calls x 7)")
    t = timeit.Timer(lambda: dicesim.toss(scene, 1).to_dict())
    n, _ = t.autorange()
    print(f"toss(scene, 1).to_dict(): best {min(t.repeat(7, n)) / n * 1e6:.1f} us")

    cli, py, cli_cpu, py_cpu = [], [], [], []

    def children_cpu():
        u = resource.getrusage(resource.RUSAGE_CHILDREN)
        return u.ru_utime + u.ru_stime

    for _ in range(args.repeat):
        c0 = children_cpu()
        out = subprocess.run([args.cli, "toss", args.scene, "-n", str(args.tosses), "--threads", str(args.threads),
                              "--json"], capture_output=True, text=True, check=True).stdout
        cli_cpu.append(children_cpu() - c0)
        c = json.loads(out)
        cli.append(c["elapsed_s"])
        t0, p0 = time.perf_counter(), time.process_time()
        r = dicesim.toss(scene, args.tosses, threads=args.threads)
        wall = time.perf_counter() - t0
        py_cpu.append(time.process_time() - p0)
        py.append(r.elapsed_s)
        assert list(r.counts) == [f["count"] for f in c["faces"]], "counts differ from the CLI's"
        print(f"  CLI {c['elapsed_s']:.3f} s ({cli_cpu[-1]:.3f} CPU s)   Python {r.elapsed_s:.3f} s "
              f"({py_cpu[-1]:.3f} CPU s, call {wall:.3f} s)")
    print(f"{args.tosses} tosses, {args.threads} threads: CLI median {statistics.median(cli):.3f} s, "
          f"Python median {statistics.median(py):.3f} s, ratio {statistics.median(py) / statistics.median(cli):.3f}")
    print(f"CPU seconds: CLI median {statistics.median(cli_cpu):.3f}, Python median {statistics.median(py_cpu):.3f}, "
          f"ratio {statistics.median(py_cpu) / statistics.median(cli_cpu):.3f}")
    print("load:", os.getloadavg())


if __name__ == "__main__":
    main()
