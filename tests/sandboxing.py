"""The grading tests' helpers: the sandbox's presence, and the processes they left.

``.ci/run`` sets ``ROBOTLIB_REQUIRE_SANDBOX=1``: there a missing sandbox is a
failure, so the grading tests can never pass by being skipped.

The tests that look for processes a grading run left behind look only in
their own process tree: the test process first becomes a child subreaper
(`adopt_orphans`), so a process that escapes its parent (``setsid``, a double
fork) is re-parented to the test, not to init, and `procs_with` searches
only below the test. Another user's grading run on the same machine is
never seen.
"""

import ctypes
import os

import pytest

from robotlib.course import sandbox as sb
from robotlib.course.session import _descendants


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


def adopt_orphans() -> None:
    """Make this process adopt the orphans of every process started below it.

    Linux re-parents an orphan to its nearest ancestor marked a child
    subreaper (``prctl(PR_SET_CHILD_SUBREAPER)``), else to init; with this
    process marked, whatever a grading run starts stays in this process's
    tree, where `procs_with` looks. Call it before starting the processes.
    """
    if _libc.prctl(_PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_CHILD_SUBREAPER) failed")


def _adopting() -> bool:
    flag = ctypes.c_int(0)
    _libc.prctl(_PR_GET_CHILD_SUBREAPER, ctypes.byref(flag), 0, 0, 0)
    return flag.value == 1


def procs_with(needle: bytes, below: int | None = None) -> list[int]:
    """Pids of this test's processes whose command line contains ``needle``.

    The processes below ``below`` (default: this process, which must have
    called `adopt_orphans`, so that its escaped descendants count).
    """
    if below is None:
        if not _adopting():
            raise RuntimeError("call adopt_orphans() before starting the processes")
        below = os.getpid()
    out = []
    for entry in map(str, _descendants(below)):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/cmdline", "rb") as f:
                    if needle in f.read():
                        out.append(int(entry))
            except OSError:
                pass
    return out
