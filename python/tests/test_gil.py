"""The GIL is released while tossing: two Python threads toss in parallel on two cores.

Run alone (CTest RUN_SERIAL). Two concurrent runs against one run at the same moment: with the GIL
held they would take twice as long (ratio 2), released about as long (ratio 1). That needs two
free cores; the overlap of the two runs in time needs none.
"""
import os
import threading
import time

import pytest


def need_two_cores():
    if (os.cpu_count() or 1) < 2:
        if os.environ.get("CI") == "true":
            pytest.fail("the GIL test needs two cores under CI=true")
        pytest.skip("one core")


def cpu_busy():
    """(busy, total) jiffies of the whole machine, from /proc/stat."""
    with open("/proc/stat") as f:
        v = [int(x) for x in f.readline().split()[1:]]
    idle = v[3] + v[4]  # idle + iowait
    return sum(v) - idle, sum(v)


def timed(f):
    """Wall time of f(), and how many cores other processes kept busy meanwhile."""
    b0, t0_all = cpu_busy()
    c0, t0 = time.process_time(), time.perf_counter()
    f()
    wall, mine = time.perf_counter() - t0, time.process_time() - c0
    b1, t1_all = cpu_busy()
    cores = os.cpu_count() or 1
    busy_cores = cores * (b1 - b0) / max(1, t1_all - t0_all)
    return wall, max(0.0, busy_cores - mine / wall)


def test_tosses_in_two_threads_overlap(dicesim, die1):
    """The proof that holds on a busy machine too: two runs, each timed inside the module, fit into
    a wall-clock window much shorter than their sum, so they ran at the same time. With the GIL
    held during a run they could only run one after the other (window >= sum)."""
    n = 100000
    elapsed = []

    def run():
        elapsed.append(dicesim.toss(die1, n, threads=1).elapsed_s)

    ts = [threading.Thread(target=run) for _ in range(2)]
    t0 = time.perf_counter()
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    window = time.perf_counter() - t0
    assert window < 0.75 * sum(elapsed), (window, elapsed)


def test_two_threads_toss_in_parallel(dicesim, die1):
    """Two concurrent runs take about the time of one, when two cores are free for them. Judged
    only when other processes left the cores free during the measurement (as on CI, where this
    test runs alone); on a busy machine the ratio is printed, not judged."""
    need_two_cores()
    # about 0.4 s of tossing on one thread on this machine, whatever its speed
    rate = 20000 / timed(lambda: dicesim.toss(die1, 20000, threads=1))[0]
    n = max(20000, int(0.4 * rate))
    best, quiet = None, False
    for _ in range(3):  # the best of three: other processes may take a core for a while
        one, others_one = timed(lambda: dicesim.toss(die1, n, threads=1))
        results = []

        def run():
            results.append(dicesim.toss(die1, n, threads=1).counts.tolist())

        def two():
            ts = [threading.Thread(target=run) for _ in range(2)]
            for t in ts:
                t.start()
            for t in ts:
                t.join()

        both, others_two = timed(two)
        assert results[0] == results[1]
        ratio = both / one
        print(f"one run {one:.3f} s, two concurrent {both:.3f} s: ratio {ratio:.2f}; "
              f"other processes kept {others_one:.2f} / {others_two:.2f} cores busy")
        if others_one < 0.3 and others_two < 0.3:
            quiet = True
            best = ratio if best is None else min(best, ratio)
            if best < 1.5:
                break
    if not quiet:
        # A busy machine says nothing about the GIL (speed is not a unit test's verdict); the
        # overlap test above proves the release at any load.
        return
    assert best < 1.5, f"two concurrent runs took {best:.2f}x one run (GIL held: 2x)"


def test_python_runs_while_tossing(dicesim, die1):
    """A long toss in a thread leaves the interpreter to this one: it runs in the middle of the toss
    (a GIL held during the toss would stop it from the toss's start to its end)."""
    span = []
    done = threading.Event()

    def toss():
        dicesim.toss(die1, 3000, threads=1)  # warm
        t0 = time.perf_counter()
        dicesim.toss(die1, 200000, threads=1)
        span.extend([t0, time.perf_counter()])
        done.set()

    samples = []
    t = threading.Thread(target=toss)
    t.start()
    while not done.is_set():
        samples.append(time.perf_counter())
        for _ in range(100):
            pass
    t.join()
    t0, t1 = span
    middle = [s for s in samples if t0 + 0.25 * (t1 - t0) < s < t1 - 0.25 * (t1 - t0)]
    assert len(middle) > 100, f"{len(middle)} samples in the middle half of a {t1 - t0:.3f} s toss"
