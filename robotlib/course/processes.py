"""The processes of a grading job: start one sandboxed worker, time it, end it.

- `Options`: how each submission runs (limits in charged time, see `cpu`).
- `Proc`: one sandboxed worker (student or check process), its pipes, a
  thread reading its frames (each event carries when its frame arrived),
  its CPU time (`Proc.sample`).
- `Clock`: the time charged to one cell, call or check: CPU time, or (the
  student's code) wall time not spent waiting for a CPU.
- `kill_job`: end every process carrying a job's id (without the sandbox).

Imports `cpu`, `sandbox` and `worker` (the wire format).
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

from . import cpu
from . import sandbox as sb
from .worker import recv, send

__all__ = ["Clock", "JOB_ENV", "Options", "Proc", "kill_job"]

JOB_ENV = "ROBOTLIB_GRADE_JOB"
"""Environment variable carrying the job id of every process of a grading job."""


@dataclass
class Options:
    """How to run each submission (see ``robotlib grade --help``)."""

    cell_timeout: float = 60.0  # charged time (`cpu`) per student cell, call, check
    slower: float = 20.0  # a check's limit: this times the solution's, if more
    timeout: float = 600.0  # CPU time of the whole submission
    backstop: float = 30.0  # wall limit, in multiples of the above: overloaded
    restarts: int = 3
    keep: bool = False
    workroot: Path | None = None
    sandbox: bool = True
    limits: sb.Limits = field(default_factory=sb.Limits)
    numba_cache: Path | None = None  # warmed cache, copied into each scratch
    mpl_cache: Path | None = None  # matplotlib's font list, copied likewise
    warm: bool = False  # this run may write the shared cache (the reference)
    stop: object = None  # a threading.Event: set to end every running submission


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
        fields = cpu.stat(pid)
        if fields is None or fields[0] in (b"T", b"t", b"Z", b"X"):
            break
        time.sleep(0.002)
    for p in [pid, *cpu.descendants(pid)]:
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


@dataclass
class Clock:
    """Time charged to one cell, call or check (see `cpu`).

    A check process runs the instructor's code, which waits only for the
    grader (relaying a call into the student's code): it is charged its CPU
    time alone. The student's code may also sleep or block (``blocking``):
    it is charged the larger of its CPU time and the wall time between the
    grader's samples less the time its main thread waited for a CPU in
    them. That wall time ends at the last sample, never at the moment the
    grader reads a reply: on a busy machine the grader itself reads late,
    and a check making thousands of short calls (Lab 2's potential field,
    once per control step) would be charged those delays. A call shorter
    than the sampling period is so charged its CPU time; a hang is charged
    in full, one sample late at most.
    """

    proc: Proc
    wall: float
    cpu: float
    wait: float
    sampled: float  # when the start's sample was taken
    blocking: bool = True
    paused: float = 0.0  # wall time spent in the other process (a check's calls)

    @classmethod
    def start(cls, proc: Proc, blocking: bool = True) -> Clock:
        """Start a clock on ``proc`` now (``blocking``: the student's code)."""
        u = proc.sample()
        return cls(proc, time.monotonic(), u.cpu, u.wait, u.time, blocking)

    def elapsed(self, now: float) -> float:
        """Return the wall time since the start, pauses excluded, s."""
        return now - self.wall - self.paused

    def charged(self, fresh: bool = False) -> float:
        """Return the time charged so far, s.

        From the last sample (`Proc.sample`); ``fresh``: the CPU time read
        now (a call or check that has just ended).
        """
        last = self.proc.last
        used = (self.proc.sample() if fresh else last).cpu - self.cpu
        if not self.blocking:
            return used
        awake = last.time - self.sampled - (last.wait - self.wait)
        return max(used, awake)


class Proc:
    """One sandboxed worker, its pipes and a thread reading its frames."""

    def __init__(self, role, spec, scratch, opts, uid, events, gen, log, share):
        self.role, self.gen, self.job = role, gen, secrets.token_hex(8)
        self.started = time.monotonic()
        self.worker: int | None = None
        self.last = cpu.Usage()
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
        self.scratch, self.base = scratch, sb.scratch_bytes(scratch)
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
        self.argv = argv[:3]  # how the worker is told from its wrappers
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
                share.wrap(cmd),
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
        """Queue each frame with when it arrived: ``(role, gen, header, data, t)``."""
        while True:
            try:
                header, payload = recv(self.fin)
            except (EOFError, ValueError, OSError, UnicodeDecodeError):
                events.put((self.role, self.gen, {"op": "eof"}, b"", time.monotonic()))
                return
            events.put((self.role, self.gen, header, payload, time.monotonic()))

    def post(self, header: dict, payload: bytes = b"") -> bool:
        """Send a frame; False if the process has gone."""
        try:
            send(self.fout, header, payload)
            return True
        except OSError:
            return False

    def sample(self) -> cpu.Usage:
        """Sample the process tree's CPU time (kept in ``last`` once it ended)."""
        if self.popen is None or not self.alive:
            return self.last
        if self.worker is None:
            self.worker = cpu.find_worker(self.popen.pid, self.argv)
        u = cpu.usage(self.popen.pid, self.worker, self.last.since)
        # a child ending between two reads can hide its time for one sample
        cpu_s, wait = max(u.cpu, self.last.cpu), max(u.wait, self.last.wait)
        self.last = cpu.Usage(cpu_s, wait, u.processes, u.running, u.since, u.time)
        return self.last

    def kill(self) -> None:
        """End the process and everything it started (its last CPU sample kept)."""
        if not self.alive:
            return
        self.sample()
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
