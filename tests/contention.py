"""Time bounds in quiet seconds: wall time divided by the machine's contention.

A test's time bound catches a fault: a page that never opens, a panel that
takes a minute to redraw, a warm-up that hangs. Counted in wall seconds, the
same bound also fails correct work on a machine whose two cores are shared
with twenty other busy processes: there each CPU second of the work takes
about ten wall seconds. Counted in CPU seconds of the work, it misses a
hang that sleeps. So a bound here is counted on a `Clock` in quiet seconds:
each stretch of wall time divided by the contention measured during it.

The contention (`factor`) is measured with a fixed probe: a busy loop in the
calling thread (so at its priority, which its processes inherit) runs for
`PROBE` s of CPU time, and the factor is its time runnable (running, plus
waiting in a run queue for a core, from Linux's
``/proc/thread-self/schedstat``) over its time running. On a quiet machine it
is 1; with R busy processes of equal priority on C cores, R / C. Waiting for
Python's GIL does not count (the thread sleeps then), so busy tests in the
same process do not stretch the bounds of work beside them. Without
scheduler statistics (not Linux) the factor is the probe's wall time over
its CPU time, GIL waits included. A measurement serves every clock of the
same priority for `EVERY` s, so bounded waits cost about 0.5 % of a core.

A fault keeps failing: a hang or a 60 s redraw takes its quiet time times
the contention, and is measured so. Contention the faulty work makes itself
(a kernel forking busy loops) stretches its own bound; the grader's CPU-hog
checks are what catch that.
"""

from __future__ import annotations

import os
import subprocess
import threading
import time

PROBE = 0.05
"""CPU time of one contention probe, s (several scheduler slices at any load)."""
EVERY = 10.0
"""How long one measurement of the contention serves, s."""

_SCHEDSTAT = "/proc/thread-self/schedstat"
_lock = threading.Lock()
_measured: dict[int, list[tuple[float, float]]] = {}
"""Priority -> the (time, factor) of each measurement at it, oldest first."""


def _schedstat() -> tuple[float, float] | None:
    """This thread's time running and time waiting for a core, s (None: unknown)."""
    try:
        with open(_SCHEDSTAT) as f:
            run, wait = f.read().split()[:2]
    except (OSError, ValueError):
        return None
    return int(run) * 1e-9, int(wait) * 1e-9


def probe(cpu: float = PROBE) -> float:
    """Measure the contention now: runnable time per running time of a busy loop.

    Parameters
    ----------
    cpu : float
        CPU time the loop runs for, s.

    Returns
    -------
    float
        The factor (at least 1): how many times longer than on a quiet
        machine a CPU-bound piece of work at this thread's priority takes.
    """
    start, t0, c0 = _schedstat(), time.monotonic(), time.thread_time()
    while time.thread_time() - c0 < cpu:
        for _ in range(10_000):
            pass
    end, wall, ran = _schedstat(), time.monotonic() - t0, time.thread_time() - c0
    if start is not None and end is not None and end[0] > start[0]:
        run, wait = end[0] - start[0], end[1] - start[1]
        return max(1.0, (run + wait) / run)
    return max(1.0, wall / ran)


def _priority() -> int:
    if hasattr(os, "getpriority") and hasattr(threading, "get_native_id"):
        return os.getpriority(os.PRIO_PROCESS, threading.get_native_id())
    return 0


def factor() -> float:
    """The contention at this thread's priority, measured at most `EVERY` s ago."""
    key = _priority()
    with _lock:
        log = _measured.setdefault(key, [])
        if log and time.monotonic() - log[-1][0] < EVERY:
            return log[-1][1]
    value = probe()
    with _lock:
        log.append((time.monotonic(), value))
    return value


def _quiet(key: int, start: float, end: float) -> float:
    """Quiet seconds in the wall-clock stretch from ``start`` to ``end``.

    Each measurement at priority ``key`` stands for the time since the one
    before it; the time after the last one, for the last one.
    """
    with _lock:
        log = list(_measured[key])
    quiet, t = 0.0, start
    for when, value in log:
        if when > t:
            quiet += (min(when, end) - t) / value
            t = min(when, end)
    return quiet + max(0.0, end - t) / log[-1][1]


class Clock:
    """Quiet seconds since the clock started: wall time over the contention.

    Each stretch of wall time is divided by the contention measured in it
    (by any clock of the same priority: every `EVERY` s while some clock is
    read; without one, by a probe when `elapsed` is called). A clock starts
    with a measurement at most `EVERY` s old, so a wait that times an answer
    (a redraw) starts with no probe in its first seconds.
    """

    def __init__(self):
        factor()  # measured now if stale: not in the first seconds of the wait
        self.start = time.monotonic()

    def elapsed(self) -> float:
        """Quiet seconds since the start, s (at the calling thread's priority)."""
        factor()
        return _quiet(_priority(), self.start, time.monotonic())

    def wall(self) -> float:
        """Wall seconds since the start, s."""
        return time.monotonic() - self.start

    def __str__(self) -> str:
        wall, quiet = self.wall(), self.elapsed()
        return (
            f"{quiet:.0f} quiet s: {wall:.0f} s of wall time at a mean contention "
            f"of {wall / max(quiet, 1e-9):.1f}"
        )


def communicate(proc: subprocess.Popen, timeout: float, poll: float = 2.0):
    """``proc.communicate()`` within ``timeout`` quiet seconds (`Clock`).

    Past it the process is killed and `subprocess.TimeoutExpired` raised
    (its message says the wall time and the contention).
    """
    clock = Clock()
    while True:
        try:
            return proc.communicate(timeout=poll)
        except subprocess.TimeoutExpired:
            if clock.elapsed() > timeout:
                proc.kill()
                proc.communicate()
                raise subprocess.TimeoutExpired(
                    f"{proc.args} (after {clock})", timeout
                ) from None


def run(cmd, timeout: float, **kwargs) -> subprocess.CompletedProcess:
    """`subprocess.run` with output captured as text, ``timeout`` in quiet seconds."""
    with subprocess.Popen(
        [str(c) for c in cmd],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **kwargs,
    ) as proc:
        try:
            out, err = communicate(proc, timeout)
        except BaseException:
            proc.kill()
            raise
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)
