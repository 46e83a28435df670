"""Slow subprocess work done beside the tests, on a core they leave idle.

Most tests run in the one pytest process, on one core; a few slow ones
mostly wait for a long subprocess (the documentation build, a cold compile
in a fresh venv). A test module with a ``background_work(folder)`` function
gets it called in a thread as soon as the session's tests are collected
(if any of its tests were selected; `selected` lists them), with a
temporary folder of its own; it and the processes it starts run at a lower
priority (`NICER`, or the module's ``BACKGROUND_NICER``), so they take
mostly CPU time the tests leave over. The module's tests run last, and get
what ``background_work`` returned (or raised) from `result`. Processes
started with `run` (or given to `adopt`) are asked to end (SIGTERM, then
SIGKILL) if the session ends before them; the tests that look for leftover
processes skip their trees (`pids`).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
import threading
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path

from tests import contention

HOOK = "background_work"
NICER = 5
"""Nice levels below the tests: a core the tests leave idle goes to the background
work, a busy one mostly to the tests (weight 1 to 3), and on a loaded machine the
background work still moves."""

_pool: ThreadPoolExecutor | None = None
_jobs: dict[str, Future] = {}
_selected: dict[str, list] = {}
_folders: list[Path] = []
_procs: list[subprocess.Popen] = []
_pids: list[int] = []
_lock = threading.Lock()
ENDED = threading.Event()
"""Set when the session ends: long background work stops at it."""


def run(cmd, timeout: float, **kwargs) -> subprocess.CompletedProcess:
    """`subprocess.run`, output captured as text, ended with the session.

    ``timeout``: in quiet seconds (`tests.contention`), so that a loaded
    machine does not end slow work that is not stuck.
    """
    with _lock:
        if ENDED.is_set():
            raise RuntimeError("the test session has ended")
        proc = subprocess.Popen(
            [str(c) for c in cmd],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            **kwargs,
        )
        _procs.append(proc)

    out, err = contention.communicate(proc, timeout)
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


def adopt(proc: subprocess.Popen | int) -> None:
    """Count a process the work started itself as the background's (`pids`).

    A ``Popen`` is also ended with the session (`end`); a bare pid (a process
    a library started) only counts while it runs.
    """
    with _lock:
        (_procs if isinstance(proc, subprocess.Popen) else _pids).append(proc)


def _lower(work, folder: Path, nicer: int):
    """Run ``work(folder)`` ``nicer`` levels nicer (its processes inherit it)."""
    if nicer and hasattr(os, "setpriority") and hasattr(threading, "get_native_id"):
        tid = threading.get_native_id()
        nice = os.getpriority(os.PRIO_PROCESS, tid)
        os.setpriority(os.PRIO_PROCESS, tid, min(19, nice + nicer))
    return work(folder)


def start(modules: dict) -> None:
    """Start each module's ``background_work`` (once per module).

    ``modules``: module -> its selected test items.
    """
    global _pool
    for module, items in modules.items():
        if module.__name__ in _jobs:
            continue
        if _pool is None:  # a thread each: they mostly wait for their processes
            _pool = ThreadPoolExecutor(
                max_workers=max(8, len(modules)), thread_name_prefix="background"
            )
        _selected[module.__name__] = list(items)
        folder = Path(tempfile.mkdtemp(prefix="robotlib-bg-"))
        _folders.append(folder)
        nicer = getattr(module, "BACKGROUND_NICER", NICER)
        work = getattr(module, HOOK)
        _jobs[module.__name__] = _pool.submit(_lower, work, folder, nicer)


def selected(module: str) -> list:
    """The test items of ``module`` selected in this session (-k, -m, node ids)."""
    return _selected.get(module, [])


def pids() -> list[int]:
    """Process ids of the background processes not yet waited for (their trees too).

    An ended one counts until its own ``Popen`` has reaped it: nobody else may.
    """
    with _lock:
        mine = [proc.pid for proc in _procs if proc.returncode is None]
        return mine + [pid for pid in _pids if os.path.exists(f"/proc/{pid}")]


def result(module: str, timeout: float = 1800.0):
    """What ``background_work`` of ``module`` returned (its exception re-raised).

    ``timeout``: how long to wait for it, in quiet seconds (`tests.contention`).
    """
    if module not in _jobs:
        raise LookupError(f"no background work was started for {module}")
    clock = contention.Clock()
    while True:
        try:
            return _jobs[module].result(timeout=2.0)
        except TimeoutError:
            if clock.elapsed() > timeout:
                raise TimeoutError(f"{module}'s background work: {clock}") from None


def end(grace: float = 10.0) -> None:
    """End what still runs (SIGTERM, SIGKILL after ``grace`` s), wait, clean up."""
    with _lock:
        ENDED.set()
        running = [proc for proc in _procs if proc.poll() is None]
    for proc in running:
        proc.terminate()  # a grading ends its sandboxes on SIGTERM
    for proc in running:
        try:
            proc.wait(timeout=grace)
        except subprocess.TimeoutExpired:
            proc.kill()
    if _pool is not None:
        _pool.shutdown(wait=True, cancel_futures=True)
    for folder in _folders:
        shutil.rmtree(folder, ignore_errors=True)
