"""Bounds in quiet seconds (`tests.contention`): the probe and the clock."""

from __future__ import annotations

import os
import subprocess
import sys
import threading

import pytest

from tests import contention


def test_a_stretch_counts_its_wall_time_over_the_contention_measured_in_it(
    monkeypatch,
):
    key = 1_000  # no thread runs at this priority
    monkeypatch.setitem(
        contention._measured, key, [(10.0, 1.0), (20.0, 4.0), (30.0, 2.0)]
    )
    # 5-10 s at 1, 10-20 s at 4, 20-30 s at 2, after the last one at 2
    assert contention._quiet(key, 5.0, 35.0) == pytest.approx(
        5 + 10 / 4 + 10 / 2 + 5 / 2
    )
    assert contention._quiet(key, 12.0, 18.0) == pytest.approx(6 / 4)
    assert contention._quiet(key, 40.0, 50.0) == pytest.approx(10 / 2)


@pytest.mark.skipif(not hasattr(os, "sched_setaffinity"), reason="needs CPU affinity")
def test_a_busy_process_on_the_probe_s_core_makes_the_contention_at_least_1_5():
    """Sharing one core with a busy process, the probe runs about half the time."""
    core = min(os.sched_getaffinity(0))
    busy = subprocess.Popen([sys.executable, "-c", "while True:\n    pass"])
    got = []

    def probe():  # a thread of its own: only it is pinned
        os.sched_setaffinity(0, {core})
        got.append(contention.probe())

    try:
        os.sched_setaffinity(busy.pid, {core})
        thread = threading.Thread(target=probe)
        thread.start()
        thread.join()
    finally:
        busy.kill()
        busy.wait()
    assert got[0] >= 1.5, got


def test_a_process_past_its_quiet_timeout_is_killed_and_says_the_contention():
    proc = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    with pytest.raises(subprocess.TimeoutExpired, match="contention"):
        contention.communicate(proc, timeout=0.5, poll=0.2)
    assert proc.returncode is not None
