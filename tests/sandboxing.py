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
"""

import contextlib
import ctypes
import os

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
