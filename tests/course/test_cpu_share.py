"""A submission's share of the machine: busy processes, not starting ones; one core.

A notebook that forks busy loops is flagged for its busy processes, but one
that starts a flood of ``sleep`` processes is not: those wait for a CPU to
start, then sleep (Lab 2's ``process_flood`` case was flagged and slowed
down for it on a loaded machine). Where the grader may make control groups
(as root, cgroup v1 or v2), a slot's processes together get one core at
most, and the time the quota holds them back counts as waiting for a CPU,
which no limit charges.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import time

import pytest

from robotlib.course import cpu
from robotlib.course.parallel import slot

BUSY_LOOP = [sys.executable, "-c", "while True:\n    pass"]


def _end(procs):
    for p in procs:
        p.kill()
        p.wait()


def test_sleeping_processes_are_not_busy_and_a_busy_loop_is():
    sleep = shutil.which("sleep")
    code = (
        "import os, sys, time\n"
        f"kids = [os.posix_spawn({sleep!r}, ['sleep', '600'], {{}})\n"
        "        for _ in range(60)]\n"
        "sys.stdout.write('spawned\\n'); sys.stdout.flush()\n"
        "time.sleep(600)\n"
    )
    flood = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE)
    busy = subprocess.Popen(BUSY_LOOP)
    try:
        assert flood.stdout.readline() == b"spawned\n"
        u = cpu.usage(flood.pid)
        for _ in range(8):  # the grader's samples, every 0.25 s
            time.sleep(0.25)
            u = cpu.usage(flood.pid, since=u.since)
            assert u.processes == 61 and u.running == 0, u
        u = cpu.usage(busy.pid)
        deadline = time.monotonic() + 30
        while u.running == 0 and time.monotonic() < deadline:
            time.sleep(0.25)
            u = cpu.usage(busy.pid, since=u.since)
        assert u.running == 1, u
    finally:
        for p in cpu.descendants(flood.pid):
            subprocess.run(["kill", "-9", str(p)], check=False)
        _end([flood, busy])


FOUR_LOOPS = (
    "import os, time\n"
    "for _ in range(4):\n"
    "    if os.fork() == 0:\n        while True:\n            pass\n"
    "time.sleep(600)\n"
)


def _quota(share: cpu.Share, fraction: float) -> None:
    """Give the slot's group ``fraction`` of one core, as a loaded machine would."""
    for g in share.groups:
        if (g / "cpu.max").exists():  # v2
            (g / "cpu.max").write_text(f"{int(fraction * 100_000)} 100000")
        elif (g / "cpu.cfs_quota_us").exists():  # v1
            period = int((g / "cpu.cfs_period_us").read_text())
            (g / "cpu.cfs_quota_us").write_text(str(int(fraction * period)))


def test_busy_loops_are_seen_however_little_cpu_their_slot_gets():
    """Four busy loops in a slot that gets 2 % of a core are seen busy at once.

    That is about a slot's share on two cores at a load of 100. Each loop
    then gets about 5 ms of CPU time a second. Counted by CPU time (a clock
    tick, 10 ms, since first seen running) they were seen busy after 1.5-2 s
    of samples, and could miss a hog whose submission ended sooner. They get
    many short turns on a CPU and never sleep, so more than `cpu.HOGS` are
    busy in two of the grader's first five samples (every 0.25 s).
    """
    if not cpu._controllers():
        pytest.skip("no control groups the grader may make here (not root, none)")
    with slot() as k:
        share = cpu.Share(k, 64)
        if not share.groups:
            pytest.skip("the control groups are not ours to change here")
        tree = subprocess.Popen(share.wrap([sys.executable, "-c", FOUR_LOOPS]))
        try:
            deadline = time.monotonic() + 30
            while len(cpu.descendants(tree.pid)) < 4 and time.monotonic() < deadline:
                time.sleep(0.05)
            _quota(share, 0.02)
            u, busy = cpu.usage(tree.pid), []
            for _ in range(5):
                time.sleep(0.25)
                u = cpu.usage(tree.pid, since=u.since)
                busy.append(u.running)
        finally:
            for p in cpu.descendants(tree.pid):
                subprocess.run(["kill", "-9", str(p)], check=False)
            _end([tree])
            share.close()
        assert sum(b > cpu.HOGS for b in busy) >= 2, busy


def test_a_slot_holds_its_processes_to_one_core_and_the_quota_is_waiting():
    """Three busy loops in a slot's group use one core at most between them;
    the time the quota holds each back shows as waiting for a CPU."""
    if not cpu._controllers():
        pytest.skip("no control groups the grader may make here (not root, none)")
    with slot() as k:
        share = cpu.Share(k, 64)
        if not share.groups:
            pytest.skip("the control groups are not ours to change here")
        procs = [subprocess.Popen(share.wrap(BUSY_LOOP)) for _ in range(3)]
        try:
            time.sleep(0.5)  # each has joined its group
            before = [cpu.usage(p.pid) for p in procs]
            t0 = time.monotonic()
            time.sleep(2.0)
            after = [cpu.usage(p.pid, p.pid) for p in procs]
            wall = time.monotonic() - t0
        finally:
            _end(procs)
            share.close()
        used = sum(a.cpu - b.cpu for a, b in zip(after, before, strict=True))
        assert used <= 1.15 * wall, (used, wall)
        assert all(a.wait > 0.5 for a in after), after  # held back: waiting
        assert not any(g.exists() for g in share.groups)
