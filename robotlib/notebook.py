"""The one call every lab notebook starts with: ``robotlib.notebook.setup()``.

It sets a plotting style, seeds what can be seeded, and compiles (or loads
from numba's cache) the kernels the lab will use, so that later cells show
only teaching code and graded cells do not pay for compilation::

    import robotlib.notebook
    rng = robotlib.notebook.setup(seed=0)
"""

from __future__ import annotations

import os
import random
import time
from collections.abc import Iterable

import numpy as np

__all__ = ["setup", "warm_up", "WARMUPS"]

STYLE = {
    "figure.figsize": (7.0, 3.5),
    "figure.dpi": 80,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "legend.frameon": False,
    "image.cmap": "viridis",
}
"""Matplotlib settings of the labs (small, light figures)."""


def _warm_sim() -> None:
    from .sim import Simulator
    from .world import load_world

    sim = Simulator(load_world("corridor"), seed=0)
    body = sim.add_robot()
    body.command("MOVE", 0.1)
    for _ in range(3):
        sim.step()


def _warm_mcl() -> None:
    from .localization import MCL, BeamSensorModel, KLDResampling, paper
    from .world import load_world

    world = load_world("corridor")
    rng = np.random.default_rng(0)
    p, w = paper.uniform_particles(world, 20, rng)
    z = np.full(8, 2.0)
    zhat = paper.expected(world, p)
    w = paper.innovation_weights(z, zhat)
    idx = paper.resample_indexes(w, rng)
    paper.check_particles(world, p[idx], w, rng)
    paper.estimate(p, w)
    paper.dispersion_index(p, world.size)
    odo = np.asarray(world.start, dtype=float)
    # The exact and fast (fused) paths, small N and the many-particle paths
    # (threads, chunked noise) of the filters the labs and widgets build.
    filters = (
        MCL.paper(world, n=20, rng=0),
        MCL.paper(world, n=20, fast=True, rng=0),
        MCL(
            world, BeamSensorModel(world), resampling=KLDResampling(20, 40), n=20, rng=0
        ),
        MCL.best(world, rng=0, n=10_000),
    )
    for mcl in filters:
        mcl.step(odo, odo + [0.1, 0.0, 0.0], z)


def _warm_avoidance() -> None:
    from .avoidance import (
        VFH,
        Bug2,
        PotentialField,
        WallFollower,
        polar_histogram,
        run_episode,
        smooth_histogram,
    )
    from .world import World

    box = World(segments=[[0, 0, 4, 0], [4, 0, 4, 3], [4, 3, 0, 3], [0, 3, 0, 0]])
    for c in (VFH(), PotentialField(), Bug2(), WallFollower()):
        run_episode(box, c, goal=(3.0, 1.5), start=(1.0, 1.5, 0.0), seed=0, max_time=1)
    smooth_histogram(polar_histogram([[1.0, 0.0]], [1.0], [0.0, 0.0, 0.0]))


def _warm_mapping() -> None:
    from .mapping import record_drive, run_fastslam

    log = record_drive("loop", [(3.0, 1.5)], seed=0, every=2)
    run_fastslam(log, 4, "laser", rng=0)
    run_fastslam(log, 4, "sonar", rng=0)


def _warm_models() -> None:
    from .localization import BeamParameters, BeamSensorModel
    from .sensing import SonarModel, simulate_ranges
    from .world import load_world

    world = load_world("corridor")
    poses = np.tile(np.asarray(world.start, dtype=float), (3, 1))
    simulate_ranges(world, poses, SonarModel(), rng=0)
    simulate_ranges(world, poses, SonarModel(sensors=np.zeros((1, 3))), rng=0)
    z = np.full(8, 2.0)
    BeamSensorModel(world).log_likelihood(poses, z)
    fast = BeamSensorModel(world, fast=True, params=BeamParameters(exponent=0.2))
    fast.log_likelihood(np.tile(poses, (100, 1)), z)


WARMUPS = {
    "sim": _warm_sim,
    "mcl": _warm_mcl,
    "mapping": _warm_mapping,
    "avoidance": _warm_avoidance,
    "models": _warm_models,
}
"""What `warm_up` can compile: a name to a function that runs the kernels once."""


def warm_up(parts: Iterable[str] = ("sim",)) -> dict[str, float]:
    """Run the numba kernels of ``parts`` once (compiling or loading them).

    Parameters
    ----------
    parts : iterable of str
        Keys of `WARMUPS`.

    Returns
    -------
    dict
        Seconds spent on each part.
    """
    spent = {}
    for part in parts:
        if part not in WARMUPS:
            raise ValueError(f"unknown warm-up {part!r}; choose from {sorted(WARMUPS)}")
        t0 = time.perf_counter()
        WARMUPS[part]()
        spent[part] = time.perf_counter() - t0
    return spent


def setup(
    seed: int = 0, warm: Iterable[str] = ("sim",), style: bool = True
) -> np.random.Generator:
    """Prepare a lab notebook: style, seeds, warmed-up kernels.

    Parameters
    ----------
    seed : int
        Seeds Python's `random` and NumPy's legacy global generator (for any
        student code that uses them) and the returned generator.
    warm : iterable of str
        Kernels to compile or load now (keys of `WARMUPS`: ``"sim"``,
        ``"mcl"``, ``"mapping"``, ``"models"``); empty for none.
    style : bool
        Apply the labs' matplotlib style (`STYLE`). The backend is left to
        Jupyter (inline) or to ``MPLBACKEND`` (``Agg`` in CI and grading).

    Returns
    -------
    numpy.random.Generator
        ``numpy.random.default_rng(seed)``, for the notebook's own draws.
    """
    if style:
        import matplotlib as mpl

        if not os.environ.get("DISPLAY") and "MPLBACKEND" not in os.environ:
            try:
                get_ipython()  # type: ignore[name-defined]  # noqa: F821
            except NameError:
                mpl.use("Agg")
        mpl.rcParams.update(STYLE)
    random.seed(seed)
    np.random.seed(seed)  # noqa: NPY002 - only for students' legacy calls
    np.set_printoptions(precision=4, suppress=True)
    warm_up(tuple(warm))
    return np.random.default_rng(seed)
