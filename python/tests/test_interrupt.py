"""Ctrl-C (SIGINT -> KeyboardInterrupt) stops a long run promptly and leaves no thread behind."""
import os
import signal
import subprocess
import sys
import threading
import time

import pytest

from conftest import DIE1, SOURCE_DIR

PROMPT_S = 2.0  # from the signal to the exception; the module polls every 20 ms


def interrupt_after(delay):
    """Sends SIGINT to this process after `delay` s; returns a list that receives the send time."""
    sent = []

    def fire():
        sent.append(time.monotonic())
        os.kill(os.getpid(), signal.SIGINT)

    threading.Timer(delay, fire).start()
    return sent


@pytest.mark.parametrize("call", ["toss", "target", "sweep", "stepped", "impulse-sweep"])
def test_sigint_stops_a_long_run(dicesim, die1, call):
    threads_before = threading.active_count()
    sent = interrupt_after(0.3)
    t0 = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        if call == "toss":
            dicesim.toss(die1, 10**9, threads=2)
        elif call == "target":
            dicesim.toss(die1, 10**9, target_halfwidth=1e-6, threads=2)
        elif call == "sweep":
            dicesim.sweep(die1, "throw.height.mean", [0.5, 1.0], 10**9, threads=2)
        elif call == "stepped":  # milliseconds per toss: run_tosses alone would stop after minutes
            dicesim.toss(die1, 10**6, threads=2, fidelity="stepped")
        else:
            dicesim.sweep(die1, "throw.height.mean", [0.5, 1.0], 10**6, threads=2, fidelity="impulse")
    stopped = time.monotonic()
    assert sent, "the run ended before the signal"
    assert stopped - sent[0] < PROMPT_S
    assert stopped - t0 < 0.3 + PROMPT_S
    # the tossing threads have stopped: another run gives the usual counts
    assert list(dicesim.toss(die1, 2000, seed=3).counts) == list(dicesim.toss(die1, 2000, seed=3, threads=1).counts)
    assert threading.active_count() == threads_before


def test_ctrl_c_in_a_script_exits_promptly():
    """A script tossing forever, interrupted from outside: a KeyboardInterrupt traceback, and the
    interpreter ends by SIGINT (what Python does when KeyboardInterrupt is not caught)."""
    code = ("import dicesim, sys\n"
            f"s = dicesim.load_scene({DIE1!r})\n"
            "print('tossing', flush=True)\n"
            "dicesim.toss(s, 10**9, threads=2)\n")
    p = subprocess.Popen([sys.executable, "-c", code], cwd=SOURCE_DIR, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "tossing"
    time.sleep(0.3)
    sent = time.monotonic()
    p.send_signal(signal.SIGINT)
    try:
        _, err = p.communicate(timeout=10)
    finally:
        p.kill()
    assert time.monotonic() - sent < PROMPT_S + 1.0  # interpreter shutdown included
    assert p.returncode == -signal.SIGINT and "KeyboardInterrupt" in err, (p.returncode, err)
