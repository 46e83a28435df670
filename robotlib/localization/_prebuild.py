"""Compiling `MCL.best`'s step on the second core while the filter is built.

On an empty numba cache, building `MCL.best` compiles the cone table's
builder and the admissible area's kernels (seconds), and its first step
then compiles the step's own kernels (as many seconds again); numba
compiles one function at a time in a process. `start` runs the second half
in a helper process at once, on another core, while this process builds
the filter: the helper builds the same filter on a small room of its own
(`_ROOM`) and takes steps with it, which compiles the same kernels for the
same argument types into numba's on-disk cache; `Prebuild.wait` (before the
filter's first step) waits until the helper has taken its first step, and
the step then loads those kernels from the cache instead of compiling them.
While it would wait, this process compiles the step's last kernels itself
(`compile_tail`, from the last on, until the helper is done), so neither
process waits for the other. The numbers are the same either way (the same
compiled code).

The helper's room has no cone table worth building: its table is filled
with made-up ranges (`_fake_table`), the beam model's factors are made up
too (`_fake_norms`), and its admissible area and free test are every point
of the room by the robot's radius (`_room_free`), so the helper compiles
none of their kernels (this process does, while the helper compiles the
step's: about half of the compiling each). The made-up table never reaches
the table cache (``ROBOTLIB_TABLE_CACHE=off`` in the helper).

No helper is started when the step's kernels are cached already, when
numba's cache is off or cannot be found, when there is one core, when the
machine has no core to spare (`BUSY_SPARE`; ``ROBOTLIB_PREBUILD=1`` starts
one anyway), or when ``ROBOTLIB_PREBUILD`` is ``0``/``off``. The helper
ends when it is done or when this process ends (its standard input closes),
whichever comes first.
Imports nothing of robotlib at import time (`start` imports the
localization's kernels; the helper `robotlib.localization.mcl` and
`robotlib.world`), and never a layer above the localization.
"""

from __future__ import annotations

import json
import os
import select
import subprocess
import sys
import threading
import time

__all__ = ["Prebuild", "start"]

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

_ROOM = (
    (0.0, 0.0, 3.0, 0.0),
    (3.0, 0.0, 3.0, 3.0),
    (3.0, 3.0, 0.0, 3.0),
    (0.0, 3.0, 0.0, 0.0),
)
"""The helper's world: a 3 m square room, walls ``x1, y1, x2, y2`` in m."""

_READY = "ready"

started: list[Prebuild] = []
"""Every helper this process started (for benchmarks: their processor time)."""


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
    proc : subprocess.Popen
        The helper, with its standard input and output piped.
    """

    def __init__(self, proc: subprocess.Popen):
        self.proc = proc
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


def start(fast: bool = True, options: dict | None = None) -> Prebuild | None:
    """Start the helper for `MCL.best` (``fast`` and its ``options``), or None.

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
        "from robotlib.localization._prebuild import _main; _main()"
    )
    try:
        proc = subprocess.Popen(
            [sys.executable, "-c", code, spec],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            env=env,
            close_fds=True,
        )
    except OSError:
        return None
    threading.Thread(target=proc.wait, daemon=True).start()  # reaped when it ends
    helper = Prebuild(proc)
    started.append(helper)
    return helper


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


def _fake_table(*args) -> None:
    """Stand-in for the cone table builders: made-up ranges in the last argument."""
    import numpy as np

    table = args[-1]
    table[...] = (np.arange(table.size) * 7919 % 4900 + 100).reshape(table.shape)


def _fake_norms(max_range, z_hit, z_short, sigma, lam_short, n):
    """Stand-in for `beam_norms`: made-up factors, arrays of the same types."""
    import numpy as np

    return np.linspace(0.5, 2.0, n), np.linspace(0.0, 1.0, n)


def _room_free(xy, radius=0.0):
    """Stand-in for the helper's `World.is_free`: inside `_ROOM` by ``radius``."""
    import numpy as np

    xy = np.asarray(xy, dtype=float)
    x, y = xy[..., 0], xy[..., 1]
    return (x > radius) & (x < 3.0 - radius) & (y > radius) & (y < 3.0 - radius)


def _exit_with_parent() -> None:
    """End this process when the parent closes our standard input (it ended)."""
    try:
        sys.stdin.buffer.read()
    finally:
        os._exit(0)


def _main() -> None:
    """Run the helper: build `MCL.best` on `_ROOM` and step it (module docstring)."""
    threading.Thread(target=_exit_with_parent, daemon=True).start()
    spec = json.loads(sys.argv[1])
    if os.path.abspath(__file__) != spec["file"]:  # another robotlib: no use
        os._exit(1)
    import numpy as np

    from ..world import World
    from ..world.grid import Grid
    from . import _kernels
    from .mcl import BEST, MCL
    from .paper import ADMISSIBLE_RADIUS

    for name in (
        "build_cone_table",
        "build_cone_table_indexed",
        "build_cone_table_strips",
    ):
        setattr(_kernels, name, _fake_table)
    _kernels.beam_norms = _fake_norms  # the parent compiles it, after its table
    world = World(np.array(_ROOM), start=(1.5, 1.5, 0.0), name="prebuild")
    object.__setattr__(world, "is_free", _room_free)  # no distance kernels either
    options = {**BEST, **spec["options"]}
    res = float(options.get("resolution", 0.05))
    radius = float(options.get("admissible_radius", ADMISSIBLE_RADIUS))
    x0, y0, x1, y1 = world.bounds
    ny = int(np.ceil((y1 - y0) / res - 1e-9))
    nx = int(np.ceil((x1 - x0) / res - 1e-9))
    free = np.zeros((ny, nx), dtype=bool)
    ys = y0 + (np.arange(ny) + 0.5) * res
    xs = x0 + (np.arange(nx) + 0.5) * res
    free[(ys > radius) & (ys < 3.0 - radius)] = True
    free[:, ~((xs > radius) & (xs < 3.0 - radius))] = False
    free.setflags(write=False)
    world._cache["free", res, radius] = Grid(free, (x0, y0), res)
    mcl = MCL.best(world, rng=0, **spec["options"])
    z = np.linspace(0.3, 2.5, len(mcl.sensor.sonar.sensors))
    odo = np.array(world.start)
    step = np.array([0.5, 0.0, 0.05])
    for k in range(8):  # until a step resampled: a first step may, or may not
        mcl.step(odo + k * step, odo + (k + 1) * step, z[::-1] if k % 2 else z)
        if mcl.info.resampled:
            break
    sys.stdout.write(f"{_READY} {time.process_time():.3f}\n")
    sys.stdout.flush()
    os._exit(0)
