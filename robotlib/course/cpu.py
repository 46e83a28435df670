"""CPU time of a sandbox's processes, and each submission's share of the machine.

Grades must not depend on how busy the machine is. A wall-clock limit does:
the same slow but correct answer passes on a quiet machine and times out
beside a classmate whose notebook forks busy loops. So the grader measures
each sandbox from ``/proc``:

- `usage` gives the CPU time of a process and every process below it
  (children that ended included: their time is in their parent's
  ``cutime``), how long the worker's main thread waited for a CPU while it
  was ready to run (``/proc/PID/schedstat``), how many processes the tree
  has and how many of them are running;
- a student's cell or call is charged ``max(CPU time, wall time - time
  waiting for a CPU)`` (`processes.Clock`): busy work counts by the CPU it
  used, sleeping or blocking counts by the wall clock, and time the machine
  made the student wait counts for nothing. The CPU time is read when the
  time is charged; the wall time only between samples (`Usage.time`), so
  the grader's own delays in relaying a short call are never charged.

A submission's processes share one control group per grading slot where
the machine lets the grader make them (`Share`, cgroup v2 or v1, as root):
one core at most (a CFS quota: time throttled counts as waiting), an equal
``cpu`` weight however many processes it forks, and a ``pids`` limit.
Without control groups the CPU-time limits still hold (a process that forks
CPU hogs spends its own budget faster) and the grader lowers the priority
of a sandbox running more busy processes than `HOGS` (`Share.tame`).

A process is busy when, since a sample first saw it running (or ready to
run), it has been so in every sample, has never slept (no voluntary context
switch, ``/proc/PID/status``), and has either used `BUSY_CPU` of CPU time
or been given a CPU `BUSY_TURNS` times (``/proc/PID/schedstat``). A loaded
machine, or a slot's quota shared by four loops, gives a busy loop little
CPU time but many short turns, so it is seen as soon as on a quiet one;
a process that waits to start and then sleeps (a flood of ``sleep``: about
1 ms of CPU time each) stops being runnable after a turn or two, however
long it waited for it.

Imports only the standard library.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path

__all__ = [
    "BUSY_CPU",
    "BUSY_TURNS",
    "HOGS",
    "Share",
    "Usage",
    "descendants",
    "find_worker",
    "stat",
    "usage",
]

TICK = os.sysconf("SC_CLK_TCK")

HOGS = 2
"""Busy processes a sandbox may have at once before it counts as forking hogs."""

BUSY_CPU = 0.01
"""CPU time a process must use, never sleeping, to count as busy, s."""

BUSY_TURNS = 5
"""Or times it must be given a CPU, never sleeping, to count as busy."""


def stat(pid: int) -> list[bytes] | None:
    """Read ``/proc/PID/stat``: the fields after the command (state, ppid, ...)."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            data = f.read()
    except OSError:
        return None
    return data[data.rindex(b")") + 2 :].split()


def _children(pid: int) -> list[int] | None:
    """Children of ``pid`` from ``/proc/PID/task/*/children``; None if unsupported."""
    try:
        tasks = os.listdir(f"/proc/{pid}/task")
    except OSError:
        return []
    kids: list[int] = []
    for tid in tasks:
        try:
            with open(f"/proc/{pid}/task/{tid}/children", "rb") as f:
                kids += [int(k) for k in f.read().split()]
        except FileNotFoundError:
            if not os.path.exists(f"/proc/{pid}/task/{tid}"):
                continue  # that thread ended meanwhile
            return None  # a kernel without CONFIG_PROC_CHILDREN
        except OSError:
            continue
    return kids


def descendants(pid: int) -> list[int]:
    """Every process below ``pid`` (children first seen, then theirs), from /proc.

    Follows ``/proc/PID/task/*/children`` (a few reads for a sandbox's tree);
    where the kernel lacks them, reads every process's parent instead.
    """
    out, todo = [], [pid]
    while todo:
        kids = _children(todo.pop())
        if kids is None:
            return _descendants_by_scan(pid)
        out += kids
        todo += kids
    return out


def _descendants_by_scan(pid: int) -> list[int]:
    parents: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit() and (fields := stat(int(entry))) is not None:
            parents.setdefault(int(fields[1]), []).append(int(entry))
    out, todo = [], [pid]
    while todo:
        kids = parents.get(todo.pop(), [])
        out += kids
        todo += kids
    return out


@dataclass(frozen=True)
class Usage:
    """One sample of a process tree.

    Attributes
    ----------
    cpu : float
        CPU time of the tree, s (user and system, ended children included).
    wait : float
        Time the worker's main thread waited for a CPU while runnable, s.
    processes : int
        Processes in the tree.
    running : int
        Busy processes of the tree (see the module's text): busy loops, not
        processes waiting to start.
    since : dict
        Process id to its CPU time (s), turns on a CPU and voluntary context
        switches when a sample first saw it running without sleeping since,
        for each process running in every sample since (pass it to the next
        `usage`).
    time : float
        When ``wait`` was read (`time.monotonic`), s.
    """

    cpu: float = 0.0
    wait: float = 0.0
    processes: int = 0
    running: int = 0
    since: dict[int, tuple[float, int, int]] = field(default_factory=dict)
    time: float = 0.0


def _wait(pid: int | str | None) -> float:
    if pid is None:
        return 0.0
    try:
        with open(f"/proc/{pid}/schedstat") as f:
            return int(f.read().split()[1]) * 1e-9
    except (OSError, IndexError, ValueError):
        return 0.0  # no scheduler statistics: wall time counts in full


def _turns(pid: int, own: float) -> tuple[float, int, int]:
    """Return a running process's CPU time (s), turns on a CPU and sleeps so far.

    ``own``: its CPU time from ``stat`` (clock ticks, every thread). Turns
    and sleeps are its main thread's; 0 without scheduler statistics (then
    only the CPU time tells a busy process).
    """
    try:
        with open(f"/proc/{pid}/schedstat") as f:
            ran, _, turns = f.read().split()[:3]
        with open(f"/proc/{pid}/status", "rb") as f:
            slept = next(
                int(line.split()[1])
                for line in f
                if line.startswith(b"voluntary_ctxt_switches:")
            )
    except (OSError, ValueError, StopIteration):
        return own, 0, 0
    return max(own, int(ran) * 1e-9), int(turns), slept


def usage(
    pid: int,
    worker: int | None = None,
    since: dict[int, tuple[float, int, int]] | None = None,
) -> Usage:
    """Sample the tree below (and including) ``pid``; ``worker``: its main process.

    ``since``: the previous sample's `Usage.since` (None: the first sample,
    in which no process is busy yet).
    """
    since = since or {}
    ticks, procs, running, now = 0, 0, 0, {}
    for p in [pid, *descendants(pid)]:
        fields = stat(p)
        if fields is None:
            continue
        procs += 1
        # utime, stime, cutime, cstime: fields 14-17 of stat, 12-15 here
        ticks += sum(int(x) for x in fields[11:15])
        if fields[0] == b"R":
            cur = _turns(p, (int(fields[11]) + int(fields[12])) / TICK)
            first = since.get(p, cur)
            if first[2] != cur[2]:  # it slept since: seen running from now on
                first = cur
            now[p] = first
            running += cur[0] - first[0] >= BUSY_CPU or cur[1] - first[1] >= BUSY_TURNS
    return Usage(ticks / TICK, _wait(worker), procs, running, now, time.monotonic())


def find_worker(pid: int, argv: list[str]) -> int | None:
    """Return ``pid`` or the first process below it whose command starts with ``argv``.

    The sandbox's wrappers (``prlimit``, ``bwrap``, ``setpriv``) carry the
    worker's command line among their own arguments: only the process that
    runs it has it first.
    """
    want = b"\0".join(a.encode() for a in argv) + b"\0"
    for p in [pid, *descendants(pid)]:
        try:
            with open(f"/proc/{p}/cmdline", "rb") as f:
                if f.read().startswith(want):
                    return p
        except OSError:
            continue
    return None


def _controllers() -> list[tuple[Path, str]]:
    """Return (hierarchy, controller) pairs we may create groups in."""
    root = Path("/sys/fs/cgroup")
    if os.geteuid() != 0:
        return []
    if (root / "cgroup.controllers").exists():  # v2
        ctl = (root / "cgroup.controllers").read_text().split()
        return [(root, "v2")] if "cpu" in ctl else []
    return [(root / c, c) for c in ("cpu", "pids") if (root / c / "tasks").exists()]


class Share:
    """A grading slot's control groups: one core at most, equal weight, a pid limit.

    Parameters
    ----------
    slot : int
        The grading slot.
    processes : int
        Most processes (and threads) the slot's sandboxes may hold at once.
    enabled : bool
        False: no control groups (only `tame`).
    """

    def __init__(self, slot: int, processes: int, enabled: bool = True):
        self.groups: list[Path] = []
        for base, kind in _controllers() if enabled else []:
            # beside the machine's other work, not below one shared parent:
            # each slot weighs as much as one ordinary process
            group = base / f"robotlib-grade-slot-{slot}"
            try:
                group.mkdir(exist_ok=True)
                if kind in ("pids", "v2"):
                    (group / "pids.max").write_text(str(processes))
                if kind == "v2":
                    (group / "cpu.max").write_text("100000 100000")  # one core
                if kind == "cpu":
                    (group / "cpu.shares").write_text("1024")
                    period = (group / "cpu.cfs_period_us").read_text().strip()
                    (group / "cpu.cfs_quota_us").write_text(period)  # one core
            except OSError:
                continue  # not ours to change (a container): the CPU limits hold
            self.groups.append(group)

    def wrap(self, cmd: list[str]) -> list[str]:
        """Return ``cmd`` made to start inside the slot's groups."""
        if not self.groups:
            return cmd
        join = " && ".join(f'echo $$ > "{g}/cgroup.procs"' for g in self.groups)
        return ["sh", "-c", f'{join} && exec "$@"', "sh", *cmd]

    @staticmethod
    def tame(pid: int) -> None:
        """Give every process below ``pid`` the lowest priority (nice 19)."""
        for p in [pid, *descendants(pid)]:
            try:
                os.setpriority(os.PRIO_PROCESS, p, 19)
            except OSError:
                pass

    def close(self, settle: float = 2.0) -> None:
        """Remove the groups once empty (another grading run may still use one).

        A killed sandbox's last processes leave their group a moment after
        their parent was reaped: each removal is retried for ``settle`` s.
        """
        deadline = time.monotonic() + settle
        for group in self.groups:
            while True:
                try:
                    group.rmdir()
                    break
                except FileNotFoundError:
                    break
                except OSError:
                    if time.monotonic() > deadline:
                        break
                    time.sleep(0.05)
