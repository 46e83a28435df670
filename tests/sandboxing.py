"""The grading tests' helpers: the sandbox's presence, and the processes they left.

``.ci/run`` sets ``ROBOTLIB_REQUIRE_SANDBOX=1``: there a missing sandbox is a
failure, so the grading tests can never pass by being skipped.

The tests that look for processes a grading run left behind look only in
their own process tree: the test process is a child subreaper while they run
(`orphans_adopted`), so a process that escapes its parent (``setsid``, a
double fork) is re-parented to the test, not to init, and `procs_with`
searches only below the test. Another user's grading run on the same machine
is never seen, nor the session's own background work (`tests.background`:
a lab grading beside the tests, in a process that adopts its own orphans).
Afterwards the test process stops adopting and reaps the
adopted processes that have ended, so no zombies pile up in the session.

A grading run started as background work (`tests.background`) runs in a
process of its own that adopts in the same way (`run_adopting`): when the
run ends, that process records the command lines of whatever is left below
it, for the tests to look at, and then ends them.
"""

import contextlib
import ctypes
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from robotlib.course import sandbox as sb
from robotlib.course.session import _descendants
from tests import background


def need_sandbox() -> None:
    """Skip (or, in CI, fail) the calling test when bubblewrap cannot run here."""
    why = sb.available()
    if not why:
        return
    if os.environ.get("ROBOTLIB_REQUIRE_SANDBOX") == "1":
        pytest.fail(f"the grading sandbox is required here and does not run: {why}")
    pytest.skip(f"no sandbox here: {why}")


_PR_SET_CHILD_SUBREAPER, _PR_GET_CHILD_SUBREAPER = 36, 37
_libc = ctypes.CDLL(None, use_errno=True)


@contextlib.contextmanager
def orphans_adopted():
    """Within the block, adopt the orphans of every process started below.

    Linux re-parents an orphan to its nearest ancestor marked a child
    subreaper (``prctl(PR_SET_CHILD_SUBREAPER)``), else to init; with this
    process marked, whatever a grading run starts stays in this process's
    tree, where `procs_with` looks. Start the processes inside the block. On
    leaving it the mark is removed and every child that has ended but was
    never waited for (adopted orphans: no ``Popen`` waits for them) is
    reaped.
    """
    if _libc.prctl(_PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_CHILD_SUBREAPER) failed")
    try:
        yield
    finally:
        _libc.prctl(_PR_SET_CHILD_SUBREAPER, 0, 0, 0, 0)
        _reap_ended_children()


def _reap_ended_children() -> None:
    me, theirs = os.getpid(), set(background.pids())  # its Popen waits for those
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", "rb") as f:
                # pid (comm) state ppid ...: comm may hold spaces, so split after it
                state, ppid = f.read().rpartition(b")")[2].split()[:2]
        except (OSError, ValueError):
            continue
        if state == b"Z" and int(ppid) == me and int(entry) not in theirs:
            with contextlib.suppress(ChildProcessError):
                os.waitpid(int(entry), os.WNOHANG)


def _adopting() -> bool:
    flag = ctypes.c_int(0)
    _libc.prctl(_PR_GET_CHILD_SUBREAPER, ctypes.byref(flag), 0, 0, 0)
    return flag.value == 1


def procs_with(needle: bytes, below: int | None = None) -> list[int]:
    """Pids of this test's processes whose command line contains ``needle``.

    The processes below ``below`` (default: this process, which must be
    inside `orphans_adopted`, so that escaped descendants count; the trees of
    the session's background processes are not the test's).
    """
    if below is None:
        if not _adopting():
            raise RuntimeError("start the processes inside orphans_adopted()")
        below = os.getpid()
    others = set()
    for pid in background.pids():
        others |= {pid, *_descendants(pid)}
    out = []
    for entry in map(str, (p for p in _descendants(below) if p not in others)):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/cmdline", "rb") as f:
                    if needle in f.read():
                        out.append(int(entry))
            except OSError:
                pass
    return out


def run_adopting(cmd, report: Path, timeout: float) -> subprocess.CompletedProcess:
    """Run ``cmd`` as background work, in a process that adopts what it leaves.

    That process (this module run as a script) is a child subreaper, so the
    processes ``cmd`` leaves behind (escaped ones too) stay below it; when
    ``cmd`` has ended it writes their command lines (``\\0``-separated
    arguments, as in ``/proc/PID/cmdline``) to ``report`` and ends them. Read
    them with `left_behind`. ``timeout``: in quiet seconds (`tests.contention`).
    """
    wrapper = [sys.executable, "-m", __name__, report, *cmd]
    return background.run(wrapper, timeout, cwd=Path(__file__).parents[1])


def left_behind(report: Path) -> list[bytes]:
    """The command lines `run_adopting` found below it after its command ended."""
    return [c.encode("latin-1") for c in json.loads(report.read_text())]


def _adopt_and_report(report: Path, cmd: list[str]) -> int:
    """Run ``cmd`` adopting its orphans; report, then end, what is left."""
    with orphans_adopted():
        proc = subprocess.Popen(cmd)
        signal.signal(signal.SIGTERM, lambda *_: proc.terminate())
        status = proc.wait()
        left: dict[int, bytes] = {}
        for _ in range(20):  # what is still ending gets 2 s, as in a test after it
            _reap_ended_children()
            left = {}
            for pid in _descendants(os.getpid()):
                with contextlib.suppress(OSError):  # a zombie's command line is empty
                    if cmdline := Path(f"/proc/{pid}/cmdline").read_bytes():
                        left[pid] = cmdline
            if not left:
                break
            time.sleep(0.1)
        report.write_text(json.dumps([c.decode("latin-1") for c in left.values()]))
        for pid in left:
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
        deadline = time.monotonic() + 10
        while _descendants(os.getpid()) and time.monotonic() < deadline:
            _reap_ended_children()
            time.sleep(0.05)
    return status


if __name__ == "__main__":  # run_adopting's own process
    sys.exit(_adopt_and_report(Path(sys.argv[1]), sys.argv[2:]))
