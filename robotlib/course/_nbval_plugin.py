"""A pytest plugin, loaded next to nbval by the grader, that records each cell.

Loaded with ``-p robotlib.course._nbval_plugin``; does nothing unless
``--robotlib-results`` is given. It

- reads a per-run secret key from a file descriptor the grader passes
  (``--robotlib-key-fd``) before any kernel starts, and closes it;
- writes one JSON line per notebook cell to the results file, each signed
  with that key (HMAC-SHA256), so a submission cannot forge its results;
- checks, outside the kernel, that each graded check cell printed its
  per-run token (``check_token``) as it ended: a check whose error was
  swallowed, or a cell blanked by an input transformer, fails;
- collects the ``CHECK ...`` lines each check prints, which the grader
  compares with the reference run of the solution;
- removes the graded notebook once collected (``--robotlib-delete-notebook``),
  so the running code cannot read it;
- makes nbval start its kernels on unix sockets (no port races) and notice a
  dead kernel within a second instead of at the cell timeout.
"""

from __future__ import annotations

import hashlib
import hmac
import json
import os
import tempfile
import time

import pytest

META_KEY = "robotlib"
TOKEN_PREFIX = "ROBOTLIB-CHECK-"


def check_token(key: bytes, grade_id: str) -> str:
    """Return the token a check cell prints last, for this run's ``key``."""
    digest = hmac.new(key, f"token:{grade_id}".encode(), hashlib.sha256).hexdigest()
    return TOKEN_PREFIX + digest[:24]


def sign(key: bytes, record: dict) -> str:
    """Return the HMAC of a results record (without its ``mac`` field)."""
    body = json.dumps(record, sort_keys=True, separators=(",", ":"))
    return hmac.new(key, body.encode(), hashlib.sha256).hexdigest()


class _State:
    key: bytes = b""
    out = None
    delete = False


def pytest_addoption(parser):
    """Add the grader's options."""
    group = parser.getgroup("robotlib", "robotlib grader")
    group.addoption("--robotlib-results", default=None, help="JSON-lines results file")
    group.addoption(
        "--robotlib-key-fd", type=int, default=None, help="fd holding the key"
    )
    group.addoption(
        "--robotlib-delete-notebook",
        action="store_true",
        help="remove the notebook once collected",
    )


def _write(record: dict) -> None:
    if _State.out is None:
        return
    record = dict(record)
    record["mac"] = sign(_State.key, record)
    _State.out.write(json.dumps(record, sort_keys=True) + "\n")
    _State.out.flush()
    os.fsync(_State.out.fileno())


def pytest_configure(config):
    """Read the key, open the results file, patch nbval's kernel handling."""
    path = config.getoption("robotlib_results")
    if not path:
        return
    fd = config.getoption("robotlib_key_fd")
    if fd is not None:
        chunks = []
        while chunk := os.read(fd, 4096):
            chunks.append(chunk)
        os.close(fd)
        _State.key = bytes.fromhex(b"".join(chunks).decode().strip())
    _State.out = open(path, "a", encoding="utf-8")  # noqa: SIM115
    _State.delete = config.getoption("robotlib_delete_notebook")
    _patch_nbval()
    _write({"event": "start", "pid": os.getpid()})


OUTPUT_TIMEOUT = 3.0
"""Seconds nbval waits for a cell's outputs (and for an interrupted kernel)."""


def pytest_collection_finish(session):
    """Record the collected cells, then remove the notebook files."""
    if _State.out is None:
        return
    cells = []
    paths = set()
    for i, item in enumerate(session.items):
        cell = getattr(item, "cell", None)
        if cell is None:
            continue
        meta = cell.get("metadata", {}).get(META_KEY) or {}
        cells.append({"n": i, "id": cell.get("id"), "grade_id": meta.get("grade_id")})
        item.output_timeout = OUTPUT_TIMEOUT
        paths.add(str(item.path))
    _write({"event": "collected", "cells": cells})
    if _State.delete:
        for p in paths:
            try:
                os.remove(p)
            except OSError:
                pass


def _error_text(item) -> str | None:
    for out in getattr(item, "test_outputs", None) or []:
        if out.get("output_type") == "error":
            text = f"{out.get('ename', 'Error')}: {out.get('evalue', '')}"
            return text.strip().rstrip(":")
    return None


def _stdout(item) -> list[str]:
    text = "".join(
        out.get("text", "")
        for out in getattr(item, "test_outputs", None) or []
        if out.get("output_type") == "stream" and out.get("name") == "stdout"
    )
    return [line.rstrip() for line in text.splitlines()]


def _classify(item, excinfo) -> tuple[str, str]:
    if excinfo is None:
        return "passed", ""
    exc = excinfo.value
    if isinstance(exc, pytest.skip.Exception):
        return "skipped", "skipped"
    msg = str(exc)
    kernel = getattr(item.parent, "kernel", None)
    if getattr(kernel, "_robotlib_died", False) and not getattr(
        kernel, "_robotlib_reported", False
    ):
        kernel._robotlib_reported = True
        return "died", "the kernel died while running this cell (crash or exit)"
    if "Kernel dead on test start" in msg:
        return "dead", "not run: the kernel had died in an earlier cell"
    if "Timeout of" in msg or "Timed out waiting" in msg:
        timeout = item.config.getoption("nbval_cell_timeout")
        return "timeout", f"timed out after {timeout:g} s"
    return "failed", _error_text(item) or msg.strip().splitlines()[0][:200]


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """Record each cell's raw outcome (before xfail bookkeeping)."""
    outcome = yield
    if _State.out is None or getattr(item, "cell", None) is None:
        return
    if call.when == "setup" and call.excinfo is None:
        return
    if call.when == "teardown":
        return
    cell = item.cell
    meta = cell.get("metadata", {}).get(META_KEY) or {}
    gid = meta.get("grade_id")
    if call.when == "setup":
        status, reason = "error", "the kernel did not start"
        if isinstance(call.excinfo.value, pytest.skip.Exception):
            status, reason = "skipped", "skipped"
    else:
        status, reason = _classify(item, call.excinfo)
    lines = _stdout(item) if call.when == "call" else []
    record = {
        "event": "cell",
        "n": getattr(item, "cell_num", -1),
        "id": cell.get("id"),
        "grade_id": gid,
        "status": status,
        "reason": reason[:300],
        "seconds": round(call.duration, 3),
    }
    if gid is not None:
        token = check_token(_State.key, gid)
        record["token"] = token in lines
        record["check_lines"] = [ln for ln in lines if ln.startswith("CHECK ")][:50]
        if status == "passed" and not record["token"]:
            record["status"] = "failed"
            record["reason"] = "the check did not run to its end (an error was hidden?)"
    _write(record)
    del outcome


def pytest_sessionfinish(session, exitstatus):
    """Record the end of the run."""
    _write({"event": "done", "exitstatus": int(exitstatus)})
    if _State.out is not None:
        _State.out.close()
        _State.out = None


def _patch_nbval() -> None:
    """Unix-socket kernels; a dead kernel noticed within a second."""
    from queue import Empty

    from nbval import kernel as nbk

    if getattr(nbk, "_robotlib_patched", False):
        return
    nbk._robotlib_patched = True
    base = nbk.KernelManager

    class IPCKernelManager(base):
        def __init__(self, **kwargs):
            kwargs.setdefault("transport", "ipc")
            kwargs.setdefault("ip", os.path.join(tempfile.gettempdir(), "k"))
            super().__init__(**kwargs)

    nbk.KernelManager = IPCKernelManager
    await_reply = nbk.RunningKernel.await_reply
    get_message = nbk.RunningKernel.get_message

    def patched_await_reply(self, msg_id, timeout=None):
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            step = 0.5
            if deadline is not None:
                step = max(0.0, min(step, deadline - time.monotonic()))
            try:
                return await_reply(self, msg_id, timeout=step)
            except Empty:
                if not self.is_alive():
                    self._robotlib_died = True
                    raise
                if deadline is not None and time.monotonic() >= deadline:
                    raise

    def patched_get_message(self, stream, timeout=None):
        if getattr(self, "_robotlib_died", False):
            raise Empty
        return get_message(self, stream, timeout=timeout)

    nbk.RunningKernel.await_reply = patched_await_reply
    nbk.RunningKernel.get_message = patched_get_message
