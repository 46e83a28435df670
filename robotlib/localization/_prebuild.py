"""Compiling `MCL.best`'s step on the second core while the filter is built.

On an empty numba cache, building `MCL.best` compiles the cone table's
builder and the admissible area's kernels (seconds), and its first step
then compiles the step's own kernels (as many seconds again); numba
compiles one function at a time in a process. `start` runs the second half
in a helper process at once, on another core, while this process builds
the filter: the helper builds the same filter on a small room of its own
and takes steps with it, which compiles the same kernels for the same
argument types into numba's on-disk cache; `Prebuild.wait` (before the
filter's first step) waits until the helper has taken its first step, and
the step then loads those kernels from the cache instead of compiling them.
While it would wait, this process compiles the step's last kernels itself
(`compile_tail`, from the last on, until the helper is done), so neither
process waits for the other. The numbers are the same either way (the same
compiled code).

What the helper runs is in `robotlib.localization._prebuild_run`. The
made-up cone table of its room never reaches the table cache
(``ROBOTLIB_TABLE_CACHE=off`` in the helper).

The helper is a fork of this process (`_fork`) while numba has no thread
pool yet (`_can_fork`), else a fresh interpreter (`_spawn`). A fork needs
no imports or numba set-up of its own, and it has the filter's world: it
first compiles what this process would compile after its cone table's
largest kernel (`_prebuild_run._for_the_parent`: the table's other helpers, the
admissible area, the beam model's factors), while this process compiles
that kernel and builds its table. A spawned helper compiles the step's
kernels only, and this process the rest.

No helper is started when the step's kernels are cached already, when
numba's cache is off or cannot be found, when there is one core, when the
machine has no core to spare (`BUSY_SPARE`; ``ROBOTLIB_PREBUILD=1`` starts
one anyway), or when ``ROBOTLIB_PREBUILD`` is ``0``/``off``. The helper
ends when it is done or when this process ends (a pipe from it closes),
whichever comes first.
Imports nothing of robotlib at import time (`start` imports the
localization's kernels; the helper `robotlib.localization._prebuild_run`),
and never a layer above the localization.
"""

from __future__ import annotations

import json
import os
import select
import subprocess
import sys
import threading
import time
import warnings

__all__ = ["Prebuild", "forked", "start"]

ENV = "ROBOTLIB_PREBUILD"
"""Environment variable: ``0``/``off`` no helper (the helper sets it), ``1``/``on``
one even on a busy machine, unset/``auto`` one when a core is to spare."""

BUSY_SPARE = 0.5
"""No helper (unless ``ROBOTLIB_PREBUILD=1``) at a load average of ``cores - this``.

On a machine whose cores are all busy the helper only adds its own start
(about 2 s of processor time: its imports, numba's set-up, a few numba
functions both processes compile): measured at load 5 on 2 cores, the first
step came 3 s later with it. With a core to spare it runs beside this
process and the first step comes seconds sooner.
"""

WAIT_SECONDS = 120.0
"""Longest `Prebuild.wait` waits for the helper's first step, s."""

_READY = "ready"

started: list[Prebuild] = []
"""Every helper this process started (for benchmarks: their processor time)."""


def forked() -> bool:
    """Whether a forked helper of this process is at work (`_for_the_parent`)."""
    return any(h.forked and h.proc.poll() is None for h in started)


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def _core_to_spare() -> bool:
    """Whether the machine's load leaves a core idle (`BUSY_SPARE`)."""
    try:
        load = os.getloadavg()[0]
    except OSError:  # pragma: no cover - no load average
        return False
    return load < _cores() - BUSY_SPARE


def _cached(dispatcher) -> bool | None:
    """Whether numba's cache holds an index for ``dispatcher`` (None: no cache)."""
    try:
        cache = dispatcher._cache._cache_file
        path = cache._index_path
    except AttributeError:  # caching off, or numba's layout changed
        return None
    return os.path.exists(path)


class Prebuild:
    """A running helper process (see the module's docstring).

    Parameters
    ----------
    proc : subprocess.Popen or _Forked
        The helper, with its standard input and output piped.
    """

    def __init__(self, proc: subprocess.Popen):
        self.proc = proc
        self.forked = isinstance(proc, _Forked)
        """Whether the helper is a fork of this process (`_for_the_parent`)."""
        self.ready = False
        self.waited = 0.0
        """Seconds `wait` waited (wall)."""
        self.cpu = float("nan")
        """The helper's processor time to its first step, s (once `ready`)."""

    def wait(self, timeout: float = WAIT_SECONDS) -> bool:
        """Wait until the helper has taken its first step; return whether it did.

        Returns at once when it has already, or when it ended without it
        (it failed, or it was killed): the step then compiles what it needs.
        """
        if self.ready:
            return True
        t0 = time.monotonic()
        try:
            self.ready = self._wait(t0 + timeout)
        finally:
            self.waited += time.monotonic() - t0
        return self.ready

    def poll(self) -> bool:
        """Whether the helper has taken its first step, without waiting."""
        return self.wait(0.0)

    _line = b""
    _ended = False

    def _wait(self, end: float) -> bool:
        out = self.proc.stdout
        while not self._line.endswith(b"\n"):
            if self._ended:
                return False
            left = max(0.0, end - time.monotonic())
            if not select.select([out], [], [], left)[0]:
                return False
            chunk = os.read(out.fileno(), 256)
            if not chunk:  # the helper ended
                self._ended = True
                return False
            self._line += chunk
        words = self._line.split()
        if not words or words[0] != _READY.encode():
            return False
        self.cpu = float(words[1]) if len(words) > 1 else float("nan")
        return True


def start(
    fast: bool = True, options: dict | None = None, world=None
) -> Prebuild | None:
    """Start the helper for `MCL.best` (``fast`` and its ``options``), or None.

    ``world`` is the filter's: a forked helper computes `_for_the_parent` on it.

    None when the helper would not help (see the module's docstring) or
    ``options`` cannot be passed to it (only JSON values can). A process
    starts one helper at most: while it runs, a second call returns it (a
    second filter's first step waits for the same kernels), and None after.
    """
    setting = os.environ.get(ENV, "auto").strip().lower()
    if setting in ("0", "off", "no", ""):
        return None
    if not fast or os.name != "posix" or _cores() < 2:
        return None
    if setting not in ("1", "on", "yes") and not _core_to_spare():
        return None
    if started:  # one helper per process: a second filter waits for the same
        return started[0] if started[0].proc.poll() is None else None
    from ._kernels import chunked

    if _cached(chunked.beam_chunk) is not False:
        return None
    try:
        spec = json.dumps({"options": options or {}, "file": os.path.abspath(__file__)})
    except (TypeError, ValueError):
        return None
    proc = _fork(spec, world) if _can_fork() else _spawn(spec)
    if proc is None:
        return None
    if not isinstance(proc, _Forked):  # which reaps its own
        threading.Thread(target=proc.wait, daemon=True).start()  # when it ends
    helper = Prebuild(proc)
    started.append(helper)
    return helper


def _spawn(spec: str) -> subprocess.Popen | None:
    """Start the helper as a fresh interpreter (``spec`` its JSON), or None."""
    env = dict(os.environ, ROBOTLIB_TABLE_CACHE="off")
    env[ENV] = "0"
    import numba

    if numba.config.CACHE_DIR:  # this process's numba cache (read at its import)
        env["NUMBA_CACHE_DIR"] = numba.config.CACHE_DIR
    # the same robotlib as this process's (numba caches by the source's folder)
    package = os.path.dirname(
        os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    )
    code = (
        f"import sys; sys.path.insert(0, {package!r}); "
        "from robotlib.localization._prebuild_run import _main; _main()"
    )
    try:
        return subprocess.Popen(
            [sys.executable, "-c", code, spec],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            env=env,
            close_fds=True,
        )
    except OSError:
        return None


def _can_fork() -> bool:
    """Whether the helper can be a fork of this process (else a fresh interpreter).

    A fork skips the helper's imports and numba's set-up (the parent's are
    copied), about 0.6 s of its processor time. Only from a process with no
    other thread (a script, not a Jupyter kernel, whose threads may hold a
    lock the child would wait on for ever), and not once numba has started
    its thread pool: GNU OpenMP does not survive a fork.
    """
    if not hasattr(os, "fork") or threading.active_count() > 1:
        return False
    try:
        from numba.np.ufunc import parallel
    except ImportError:  # pragma: no cover - numba's layout changed
        return False
    return getattr(parallel, "_is_initialized", True) is False


class _Forked:
    """A forked helper, with what `Prebuild` and its callers use of `subprocess.Popen`.

    Parameters
    ----------
    pid : int
        The helper's process id.
    out : int
        The read end of the pipe the helper writes its ready line to.
    life : int
        The write end of a pipe the helper reads until it closes (when this
        process ends): the helper then ends too.
    """

    def __init__(self, pid: int, out: int, life: int):
        self.pid = pid
        self.stdout = os.fdopen(out, "rb", buffering=0)
        self.stdin = os.fdopen(life, "wb", buffering=0)
        self.returncode = None
        self._done = threading.Event()
        threading.Thread(target=self._reap, daemon=True).start()

    def _reap(self) -> None:
        try:
            status = os.waitpid(self.pid, 0)[1]
            self.returncode = os.waitstatus_to_exitcode(status)
        except ChildProcessError:  # reaped by someone else's os.wait
            self.returncode = -1
        self._done.set()

    def poll(self) -> int | None:
        """Return the exit status, or None while the helper runs."""
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        """Wait for the helper to end; return its exit status."""
        if not self._done.wait(timeout):
            raise subprocess.TimeoutExpired(f"prebuild helper {self.pid}", timeout)
        return self.returncode


def _fork(spec: str, world=None) -> _Forked | None:
    """Start the helper as a fork of this process (``spec`` its JSON), or None.

    Given the parent's ``world``, the helper first computes `_for_the_parent`.
    """
    from numba.core.compiler_lock import global_compiler_lock
    from numba.core.registry import cpu_target

    # numba's set-up, which this process's first compile does anyway: the
    # helper inherits it instead of doing it again
    cpu_target.typing_context.refresh()
    cpu_target.target_context.refresh()
    out_r, out_w = os.pipe()
    life_r, life_w = os.pipe()
    try:
        with global_compiler_lock, warnings.catch_warnings():  # no thread compiles
            warnings.simplefilter("ignore", DeprecationWarning)  # "multi-threaded"
            pid = os.fork()
    except OSError:
        for fd in (out_r, out_w, life_r, life_w):
            os.close(fd)
        return None
    if pid == 0:  # the helper: never returns
        try:
            from ._prebuild_run import _exit_with_parent, _for_the_parent, _run

            os.close(out_r)
            os.close(life_w)
            null = os.open(os.devnull, os.O_RDWR)
            for fd in (0, 1, 2):
                os.dup2(null, fd)
            # not the parent's streams either (a notebook's go to its kernel)
            sys.stdout = sys.stderr = open(os.devnull, "w")  # noqa: SIM115
            os.environ[ENV] = "0"
            started.clear()
            ends = threading.Thread(target=_exit_with_parent, args=(life_r,))
            ends.daemon = True
            ends.start()
            given = json.loads(spec)["options"]
            if world is not None:
                _for_the_parent(world, given)
            os.environ["ROBOTLIB_TABLE_CACHE"] = "off"
            _run(given, out_w)
        finally:
            os._exit(1)
    os.close(out_w)
    os.close(life_r)
    return _Forked(pid, out_r, life_w)


def compile_tail(mcl, helper: Prebuild) -> int:
    """Compile the end of ``mcl``'s first step here while ``helper`` is not done.

    The helper compiles the first step's kernels in the order the step calls
    them; this process, once its filter is built and while it would wait,
    compiles the last of them (gathering the new set, KLD-sampling with its
    cumulative weights, the admissibility check) from the last on, each on a
    few of the filter's own particles, so for the same argument types, and
    stops as soon as the helper has taken its step. The helper then loads
    from numba's cache what this process has compiled, and the two meet in
    the middle instead of one waiting for the other. Draws nothing from the
    filter's generator and changes none of its state. Returns how many
    kernels it compiled (or found compiled).
    """
    import numpy as np

    from ._kernels import outside
    from .kld import kld_resample
    from .policies import KLDResampling, _gather

    p, w = mcl.particles[:4], mcl.weights[:4]
    jobs = []
    policy = mcl.resampling
    if type(policy) is KLDResampling:
        idx = np.zeros(2, dtype=np.int64)
        jobs.append(lambda: _gather(p, idx))
        jobs.append(
            lambda: kld_resample(
                p,
                w,
                mcl.world.bounds,
                np.random.default_rng(0),
                policy.n_min,
                policy.n_max,
                policy.epsilon,
                policy.delta,
                policy.bin_xy,
                policy.bin_theta,
            )  # fmt: skip
        )
    if mcl.check:
        bad = np.empty(len(p), dtype=np.bool_)
        x0, y0 = mcl._adm_origin
        jobs.append(
            lambda: outside(
                p.copy(), mcl._admissible, x0, y0, 1.0 / mcl.resolution, bad
            )  # fmt: skip
        )
    done = 0
    for job in jobs:
        if helper.poll():
            break
        job()
        done += 1
    return done
