"""Grade one submission: two sandboxed processes, the grader relaying between them.

The student process (their cells) and the check process (the instructor's
checks) never share memory, files or a PID namespace; every message goes
through `run_submission`, which also keeps the time:

- a student cell (at start-up) running longer than the cell limit is
  killed and the process restarted without it;
- a call into the student's code running longer than the cell limit is
  killed: the check fails ("timed out"), the student process is restarted
  for the next checks; a student process that dies (``os._exit``, a crash,
  memory) fails the call in flight and is restarted, a few times at most;
- a check running longer than the cell limit on its own is killed and the
  check process restarted from the next check;
- the submission's total time (start-ups, restarts and checks) is bounded:
  what has not run by then fails with that reason.

Killing a sandbox's first process ends every process in it (PID namespace);
without the sandbox every process carrying the job's id is killed.
Imports `sandbox`, `worker` (the wire format) and `plan`.
"""

from __future__ import annotations

import os
import queue
import secrets
import shutil
import signal
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

from . import sandbox as sb
from .plan import LabPlan
from .worker import recv, send

__all__ = ["Options", "Outcome", "run_submission", "JOB_ENV", "kill_job"]

JOB_ENV = "ROBOTLIB_GRADE_JOB"
"""Environment variable carrying the job id of every process of a grading job."""


@dataclass
class Options:
    """How to run each submission (see ``robotlib grade --help``)."""

    cell_timeout: float = 60.0
    timeout: float = 600.0
    restarts: int = 3
    keep: bool = False
    workroot: Path | None = None
    sandbox: bool = True
    limits: sb.Limits = field(default_factory=sb.Limits)
    numba_cache: Path | None = None  # warmed cache, copied into each scratch
    mpl_cache: Path | None = None  # matplotlib's font list, copied likewise
    warm: bool = False  # this run may write the shared cache (the reference)
    stop: object = None  # a threading.Event: set to end every running submission


@dataclass
class Outcome:
    """What the processes reported for one submission."""

    checks: dict[str, dict] = field(default_factory=dict)
    cells: dict[str, dict] = field(default_factory=dict)
    tripwires: list[tuple[str, str | None, str]] = field(default_factory=list)
    status: str = "ok"
    restarts: int = 0
    log: str = ""


def _job_pids(job: str) -> list[int]:
    tag = f"{JOB_ENV}={job}".encode()
    pids = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit() or int(entry) == os.getpid():
            continue
        try:
            with open(f"/proc/{entry}/environ", "rb") as f:
                if tag in f.read().split(b"\0"):
                    pids.append(int(entry))
        except OSError:
            continue
    return pids


def _stat(pid: int) -> list[bytes] | None:
    """Read ``/proc/PID/stat``: the fields after the command (state, ppid, ...)."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            stat = f.read()
    except OSError:
        return None
    return stat[stat.rindex(b")") + 2 :].split()


def _descendants(pid: int) -> list[int]:
    """Every process below ``pid`` (children first seen, then theirs), from /proc."""
    parents: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit() and (fields := _stat(int(entry))) is not None:
            parents.setdefault(int(fields[1]), []).append(int(entry))
    out, todo = [], [pid]
    while todo:
        kids = parents.get(todo.pop(), [])
        out += kids
        todo += kids
    return out


def _kill_tree(pid: int, settle: float = 1.0) -> None:
    """Kill ``pid`` and every process below it, one stopped snapshot of the tree.

    bubblewrap's child (the sandbox's pid 1) waits for its parent during
    set-up before it asks to die with it: killed in that window, the parent
    would leave it waiting for ever. So the parent is stopped first (it can
    then start no child), the tree is read once it has stopped, and all of
    it is killed.
    """
    try:
        os.kill(pid, signal.SIGSTOP)
    except ProcessLookupError:
        return
    deadline = time.monotonic() + settle
    while time.monotonic() < deadline:
        fields = _stat(pid)
        if fields is None or fields[0] in (b"T", b"t", b"Z", b"X"):
            break
        time.sleep(0.002)
    for p in [pid, *_descendants(pid)]:
        try:
            os.kill(p, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass


def kill_job(job: str, rounds: int = 10) -> int:
    """End every process whose environment carries ``JOB_ENV=job``, one by one."""
    killed = 0
    for _ in range(rounds):
        pids = _job_pids(job)
        if not pids:
            break
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
                killed += 1
            except (ProcessLookupError, PermissionError):
                pass
        time.sleep(0.05)
    return killed


def _env(job: str, sandbox: bool) -> dict[str, str]:
    s = sb.SCRATCH
    home = f"{s}/home"
    venv_bin = str(Path(sys.executable).parent)
    return {
        JOB_ENV: job,
        "PATH": f"{venv_bin}:/usr/local/bin:/usr/bin:/bin",
        "LANG": "C.UTF-8",
        "HOME": home,
        "XDG_CACHE_HOME": f"{home}/.cache",
        "XDG_CONFIG_HOME": f"{home}/.config",
        "IPYTHONDIR": f"{home}/.ipython",
        "MPLCONFIGDIR": f"{home}/.matplotlib",
        "MPLBACKEND": "Agg",
        "TMPDIR": "/tmp" if sandbox else f"{s}/tmp",
        "NUMBA_CACHE_DIR": f"{s}/numba",
        # cone tables are rebuilt in each process: none is written into the
        # class cache that every submission's copy starts from
        "ROBOTLIB_TABLE_CACHE": "off",
        "NUMBA_NUM_THREADS": "1",
        "OMP_NUM_THREADS": "1",
        "OPENBLAS_NUM_THREADS": "1",
        "MKL_NUM_THREADS": "1",
        "PYTHONDONTWRITEBYTECODE": "1",
        "PYTHONNOUSERSITE": "1",
    }


class _Proc:
    """One sandboxed worker, its pipes and a thread reading its frames."""

    def __init__(self, role, spec, scratch, opts, uid, events, gen, log):
        self.role, self.gen, self.job = role, gen, secrets.token_hex(8)
        scratch.mkdir(parents=True, exist_ok=True)
        for sub in ("home/.ipython", "home/.matplotlib", "tmp"):
            (scratch / sub).mkdir(parents=True, exist_ok=True)
        if opts.mpl_cache is not None and opts.mpl_cache.is_dir():
            for f in opts.mpl_cache.glob("fontlist*.json"):
                shutil.copy(f, scratch / "home" / ".matplotlib" / f.name)
        cache = scratch / "numba"
        if opts.numba_cache is not None and not opts.numba_cache.is_dir():
            opts = Options(**{**vars(opts), "numba_cache": None})  # another machine
        if opts.numba_cache is not None and not cache.exists():
            if opts.warm:
                cache.symlink_to(opts.numba_cache)  # the trusted reference run
            else:
                shutil.copytree(opts.numba_cache, cache, symlinks=False)
        # the class's cache was warmed before the reference run: skip the
        # set-up cell's warm-ups (numba loads each kernel from it when used)
        spec = {**spec, "skip_warm_up": cache.exists()}
        cache.mkdir(exist_ok=True)
        if uid is not None:
            for root, dirs, files in os.walk(scratch):
                for n in (root, *(os.path.join(root, d) for d in dirs)):
                    os.chown(n, uid, uid, follow_symlinks=False)
                for n in files:
                    os.chown(os.path.join(root, n), uid, uid, follow_symlinks=False)
            if opts.warm and opts.numba_cache is not None:
                for root, _, files in os.walk(opts.numba_cache):
                    os.chown(root, uid, uid)
                    for n in files:
                        os.chown(os.path.join(root, n), uid, uid)
        r_in, w_in = os.pipe()
        r_out, w_out = os.pipe()
        argv = [sys.executable, "-m", "robotlib.course.worker", role, str(r_in)]
        argv.append(str(w_out))
        extra = []
        if opts.warm and opts.numba_cache is not None and opts.sandbox:
            extra = [str(opts.numba_cache)]
        cmd, env = sb.command(
            argv, scratch, _env(self.job, opts.sandbox), opts.limits, uid, opts.sandbox
        )
        if extra:  # the shared cache, writable, at the link's target
            i = cmd.index("--clearenv")
            cmd[i:i] = ["--bind", extra[0], f"{sb.SCRATCH}/numba"]
            (scratch / "numba").unlink()
            (scratch / "numba").mkdir()
            if uid is not None:
                os.chown(scratch / "numba", uid, uid)
        self.fin, self.fout = r_out, w_in
        self.sandbox = opts.sandbox
        self.alive = True
        try:
            self.popen = subprocess.Popen(
                cmd,
                env=env,
                stdin=subprocess.DEVNULL,
                stdout=log,
                stderr=log,
                pass_fds=(r_in, w_out),
                start_new_session=True,
            )
        except OSError as exc:  # no process (out of pids, ...): reported as its end
            self.popen = None
            log.write(f"could not start the {role} process: {exc}\n".encode())
        os.close(r_in)
        os.close(w_out)
        if self.popen is not None:
            try:
                send(self.fout, spec)
            except OSError:
                pass  # it died at start: its reader sees the end of its pipe
        threading.Thread(target=self._read, args=(events,), daemon=True).start()

    def _read(self, events: queue.Queue) -> None:
        while True:
            try:
                header, payload = recv(self.fin)
            except (EOFError, ValueError, OSError, UnicodeDecodeError):
                events.put((self.role, self.gen, {"op": "eof"}, b""))
                return
            events.put((self.role, self.gen, header, payload))

    def post(self, header: dict, payload: bytes = b"") -> bool:
        try:
            send(self.fout, header, payload)
            return True
        except OSError:
            return False

    def kill(self) -> None:
        if not self.alive:
            return
        self.alive = False
        if self.popen is not None:
            _kill_tree(self.popen.pid)
            try:
                self.popen.wait(timeout=10)
            except subprocess.TimeoutExpired:
                pass
        if not self.sandbox:
            kill_job(self.job)
        for fd in (self.fin, self.fout):
            try:
                os.close(fd)
            except OSError:
                pass


def run_submission(
    plan: LabPlan, cells: list[dict], opts: Options, slot: int = 0
) -> Outcome:
    """Run ``cells`` (the student's) against ``plan``'s checks.

    Never raises for anything the submission does.
    """
    out = Outcome()
    t_end = time.monotonic() + opts.timeout
    root = Path(__import__("tempfile").mkdtemp(prefix="rg-", dir=opts.workroot))
    os.chmod(root, 0o711)
    events: queue.Queue = queue.Queue()
    uid = sb.sandbox_uid(2 * slot) if opts.sandbox else None
    cuid = sb.sandbox_uid(2 * slot + 1) if opts.sandbox else None
    if opts.warm:  # the solution's two processes both write the shared cache
        cuid = uid
    logf = open(root / "log.txt", "wb")  # noqa: SIM115
    skip: set[str] = set()
    gen = {"student": 0, "check": 0}
    procs: dict[str, _Proc | None] = {"student": None, "check": None}
    st = {"ready": False, "cell": None, "pending": None, "queued": None}
    ck = {"cur": None, "t0": 0.0, "index": 0, "done": False, "restarts": 0}
    gids = [c["gid"] for c in plan.check_specs]

    def start_student():
        gen["student"] += 1
        spec = {
            "setup": plan.setup,
            "cells": [c for c in cells if c["id"] not in skip],
            "writes": plan.writes,
            "owner": plan.owner,
        }
        scratch = root / f"student{gen['student']}"
        procs["student"] = _Proc(
            "student", spec, scratch, opts, uid, events, gen["student"], logf
        )
        st.update(ready=False, cell=None)

    def start_check(index: int):
        gen["check"] += 1
        spec = {
            "setup": plan.setup,
            "defs": plan.defs,
            "checks": plan.check_specs,
            "names": plan.names,
            "start": index,
        }
        scratch = root / f"check{gen['check']}"
        procs["check"] = _Proc(
            "check", spec, scratch, opts, cuid, events, gen["check"], logf
        )
        ck.update(cur=None, t0=time.monotonic(), index=index)

    def fail_call(error: str):
        if st["pending"] is not None:
            procs["check"].post({"op": "result", "ok": False, "error": error})
            st["pending"] = None

    def student_died(why: str):
        if procs["student"] is None:
            return  # given up already: a late event of the last process
        procs["student"].kill()
        out.restarts += 1
        if st["cell"] is not None:
            cid = st["cell"][0]
            skip.add(cid)
            out.cells.setdefault(cid, {"status": "error", "error": why})
        fail_call(why)
        if out.restarts <= opts.restarts:
            start_student()
        else:
            procs["student"] = None
            st.update(ready=False, cell=None)
            if st["queued"] is not None:
                st["queued"] = None
                procs["check"].post(
                    {
                        "op": "result",
                        "ok": False,
                        "error": "not run: your code "
                        "kept hanging or crashing the process",
                    }  # fmt: skip
                )

    def forward(item):
        header, payload, _ = item
        st["pending"] = (header, payload, time.monotonic())
        if not procs["student"].post(header, payload):
            student_died("the process of your code had ended")

    try:
        start_student()
        start_check(0)
        while not ck["done"]:
            now = time.monotonic()
            if opts.stop is not None and opts.stop.is_set():
                out.status = "interrupted"
                break
            if now > t_end:
                out.status = "timed out"
                for gid in gids:
                    out.checks.setdefault(
                        gid,
                        {
                            "status": "failed",
                            "error": "not run: the submission's "
                            f"time limit ({opts.timeout:g} s) ran out",
                        },  # fmt: skip
                    )
                break
            if st["cell"] is not None and now - st["cell"][1] > opts.cell_timeout:
                student_died(f"timed out after {opts.cell_timeout:g} s")
                continue
            if st["pending"] is not None and now - st["pending"][2] > opts.cell_timeout:
                student_died(f"timed out after {opts.cell_timeout:g} s")
                continue
            busy = st["pending"] is not None or st["queued"] is not None
            limit = opts.cell_timeout * (3 if ck["cur"] is None else 1)
            if not busy and now - ck["t0"] > limit:
                gid = ck["cur"] or gids[min(ck["index"], len(gids) - 1)]
                out.checks.setdefault(
                    gid,
                    {
                        "status": "failed",
                        "error": f"timed out after {opts.cell_timeout:g} s",
                    },  # fmt: skip
                )
                procs["check"].kill()
                nxt = gids.index(gid) + 1 if gid in gids else len(gids)
                if nxt >= len(gids):
                    break
                start_check(nxt)
                continue
            try:
                role, g, header, payload = events.get(timeout=0.2)
            except queue.Empty:
                continue
            if g != gen[role] or procs[role] is None:
                continue  # from a process already replaced or given up
            op = header.get("op")
            if role == "student":
                if op == "cell":
                    if header.get("status") == "start":
                        st["cell"] = (str(header.get("id")), time.monotonic())
                    else:
                        cid = str(header.get("id"))
                        out.cells.setdefault(cid, header)
                        st["cell"] = None
                elif op == "ready":
                    st.update(ready=True, cell=None)
                    if st["queued"] is not None:
                        item, st["queued"] = st["queued"], None
                        forward(item)
                        ck["t0"] = time.monotonic()
                elif op == "tripwire":
                    hit = (
                        str(header.get("function")),
                        header.get("exercise"),
                        str(header.get("via") or ""),
                    )
                    if hit not in out.tripwires:
                        out.tripwires.append(hit)
                elif op == "result" and st["pending"] is not None:
                    st["pending"] = None
                    procs["check"].post(
                        {
                            "op": "result",
                            "ok": bool(header.get("ok")),
                            "error": str(header.get("error", ""))[:3000],
                        },  # fmt: skip
                        payload,
                    )
                elif op == "eof":
                    student_died("your code ended or crashed the process")
            else:
                if op == "ready":
                    ck["t0"] = time.monotonic()
                elif op == "begin":
                    ck["cur"], ck["t0"] = header.get("gid"), time.monotonic()
                elif op == "end":
                    out.checks.setdefault(str(header.get("gid")), header)
                    ck["cur"], ck["t0"] = None, time.monotonic()
                elif op in ("call", "get"):
                    item = (header, payload, time.monotonic())
                    if procs["student"] is None:
                        procs["check"].post(
                            {
                                "op": "result",
                                "ok": False,
                                "error": "not run: your "
                                "code kept hanging or crashing the process",
                            }  # fmt: skip
                        )
                    elif st["ready"]:
                        forward(item)
                    else:
                        st["queued"] = item
                elif op == "done":
                    ck["done"] = True
                elif op == "eof":
                    gid = ck["cur"]
                    procs["check"].kill()
                    if gid is None and not out.checks:
                        out.status = "set-up failed"
                        break
                    if gid is not None:
                        out.checks.setdefault(
                            gid,
                            {
                                "status": "failed",
                                "error": "the check's process ended (out of memory?)",
                            },  # fmt: skip
                        )
                    done = [g2 for g2 in gids if g2 in out.checks]
                    nxt = max(gids.index(g2) for g2 in done) + 1 if done else 0
                    ck["restarts"] += 1
                    if nxt >= len(gids) or ck["restarts"] > opts.restarts:
                        break
                    start_check(nxt)
    finally:
        for p in procs.values():
            if p is not None:
                p.kill()
        logf.close()
        try:
            out.log = (root / "log.txt").read_text(errors="replace")[-3000:]
        except OSError:
            pass
        if not opts.keep:
            shutil.rmtree(root, ignore_errors=True)
    for gid in gids:
        out.checks.setdefault(gid, {"status": "failed", "error": "not run"})
    return out
