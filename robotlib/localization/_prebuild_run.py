"""What `robotlib.localization._prebuild`'s helper process runs.

The helper builds `MCL.best` on a small room of its own (`_ROOM`) and steps
it (`_run`), which compiles the step's kernels into numba's cache; a forked
helper first compiles what its parent needs besides (`_for_the_parent`).
Its room has no cone table worth building: the table is filled with
made-up ranges (`_fake_table`), the beam model's factors are made up too
(`_fake_norms`), and its admissible area and free test are every point of
the room by the robot's radius (`_room_free`). Imports nothing of robotlib
at import time but `robotlib.localization._prebuild`, and never a layer
above the localization.
"""

import json
import os
import sys
import threading
import time

from ._prebuild import _READY

_ROOM = (
    (0.0, 0.0, 3.0, 0.0),
    (3.0, 0.0, 3.0, 3.0),
    (3.0, 3.0, 0.0, 3.0),
    (0.0, 3.0, 0.0, 0.0),
)
"""The helper's world: a 3 m square room, walls ``x1, y1, x2, y2`` in m."""


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


def _exit_with_parent(fd: int = 0) -> None:
    """End this process when the parent closes the pipe ``fd`` (it ended)."""
    try:
        while os.read(fd, 4096):
            pass
    finally:
        os._exit(0)


def _main() -> None:
    """Run the spawned helper: its options in ``sys.argv[1]`` (JSON), then `_run`."""
    threading.Thread(target=_exit_with_parent, daemon=True).start()
    spec = json.loads(sys.argv[1])
    from . import _prebuild

    if os.path.abspath(_prebuild.__file__) != spec["file"]:  # another robotlib
        os._exit(1)
    _run(spec["options"], sys.stdout.fileno())


def _for_the_parent(world, given: dict) -> None:
    """Compile (and compute) what the parent's `MCL.best` needs besides its step.

    In a fork, first: the cone table's sweep helpers but `_ray_echoes`
    (which the parent compiles meanwhile), the admissible area of the
    parent's own ``world`` (into the tables' disk cache as well, where the
    parent then finds it), a free test of as many points as the first draw
    of particles, and the beam model's factors, all with the argument types
    of the parent's calls: the parent loads these kernels from numba's cache
    instead of compiling them. On a map too large for the sweep, only the
    factors (the parent builds the rest with other kernels).
    """
    import numpy as np

    from . import _kernels
    from ._kernels.tables import compile_sweep_helpers
    from .cones import _sweep_builds, free_space
    from .mcl import BEST
    from .paper import ADMISSIBLE_RADIUS
    from .sensors import BeamParameters

    options = {**BEST, **given}
    if _sweep_builds(world, None, 1):  # the labs' worlds (a large map: none of it)
        # the sweep's helpers but `_ray_echoes`, for the parent's walls' type
        compile_sweep_helpers(np.ascontiguousarray(world.obstacles))
        radius = options.get("admissible_radius", ADMISSIBLE_RADIUS)
        free_space(world, options.get("resolution", 0.05), radius)
        world.is_free(np.zeros((options["n"], 2)), radius)
    q = BeamParameters(**options["beam"])
    _kernels.beam_norms(1.0, q.z_hit, q.z_short, q.sigma_hit, q.lambda_short, 2)


def _run(given: dict, out: int) -> None:
    """Build `MCL.best` (``given`` options) on `_ROOM`, step it; ready on ``out``."""
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
    options = {**BEST, **given}
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
    mcl = MCL.best(world, rng=0, **given)
    z = np.linspace(0.3, 2.5, len(mcl.sensor.sonar.sensors))
    odo = np.array(world.start)
    step = np.array([0.5, 0.0, 0.05])
    for k in range(8):  # until a step resampled: a first step may, or may not
        mcl.step(odo + k * step, odo + (k + 1) * step, z[::-1] if k % 2 else z)
        if mcl.info.resampled:
            break
    os.write(out, f"{_READY} {time.process_time():.3f}\n".encode())
    os._exit(0)
