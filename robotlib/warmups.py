"""What ``robotlib warmup`` runs: each part's kernels, called once.

`WARMUPS` maps a part's name to a function that runs its kernels once (so
that numba compiles them, or loads them from its cache), or to a list of
``(label, function)`` steps. `robotlib.notebook.warm_up` runs them with a
progress bar; a lab names its parts in ``robotlib.notebook.setup(warm=...)``.
A kernel a lab calls with other argument types, or on a path no part takes,
compiles inside the lab: the notebook tests fail on that
(``ROBOTLIB_COMPILE_LOG``), so a new path gets its step here.

Sits with the notebook set-up (layer 7): imports any layer, inside the
functions, so that importing it stays cheap.
"""

from __future__ import annotations

import os
from collections.abc import Callable

import numpy as np

__all__ = ["WARMUPS"]


def _warm_sim() -> None:
    from .sim import Simulator
    from .world import load_world

    sim = Simulator(load_world("corridor"), seed=0)
    body = sim.add_robot()
    body.command("MOVE", 0.1)
    for _ in range(3):
        sim.step()


def _mcl_inputs():
    from .world import load_world

    world = load_world("corridor")
    odo = np.asarray(world.start, dtype=float)
    return world, odo, odo + [0.1, 0.0, 0.0], np.full(8, 2.0)


def _warm_mcl_pieces() -> None:
    from .localization import paper

    world, *_ = _mcl_inputs()
    rng = np.random.default_rng(0)
    p, w = paper.uniform_particles(world, 20, rng)
    zhat = paper.expected(world, p)
    w = paper.innovation_weights(np.full(8, 2.0), zhat)
    idx = paper.resample_indexes(w, rng)
    paper.check_particles(world, p[idx], w, rng)
    paper.estimate(p, w)
    paper.dispersion_index(p, world.size)
    many, _ = paper.uniform_particles(world, 64, rng)  # the threaded scan (N >= 64)
    paper.admissible(world, paper.predict(many, odo0 := np.zeros(3), odo0, rng=rng))
    paper.expected(world, many)


def _warm_filter(make: Callable) -> Callable[[], None]:
    def warm() -> None:
        world, odo0, odo1, z = _mcl_inputs()
        make(world).step(odo0, odo1, z)

    return warm


def _warm_plan() -> None:
    from .planning import (
        CSpace,
        astar,
        dijkstra,
        inflate,
        rrt,
        wavefront,
        wavefront_field,
    )
    from .world import load_world

    cs = CSpace.from_array(np.zeros((4, 4), dtype=bool))
    inflate(cs.blocked, 1.0)
    for planner in (astar, dijkstra, wavefront):
        planner(cs, (0.5, 0.5), (3.5, 3.5))
    wavefront_field(cs, (3.5, 3.5))
    world = load_world("corridor")
    x, y, _ = world.start
    rrt(world, (x, y), (x + 0.5, y), rng=0)


def _warm_avoidance() -> None:
    from .avoidance import (
        VFH,
        Bug2,
        PotentialField,
        VFHSettings,
        WallFollower,
        choose_direction,
        polar_histogram,
        run_episode,
        smooth_histogram,
    )
    from .world import World

    box = World(segments=[[0, 0, 4, 0], [4, 0, 4, 3], [4, 3, 0, 3], [0, 3, 0, 0]])
    stuck = VFHSettings(patience=0.0, progress=10.0)  # follows the boundary at once
    controllers = (
        VFH(),
        VFH(settings=stuck),
        VFH(histogram=polar_histogram, direction=choose_direction),  # Lab 2's parts
        PotentialField(),
        Bug2(),
        WallFollower(),
    )
    for c in controllers:
        run_episode(box, c, goal=(3.0, 1.5), start=(1.0, 1.5, 0.0), seed=0, max_time=1)
    smooth_histogram(polar_histogram([[1.0, 0.0]], [1.0], [0.0, 0.0, 0.0]))
    _warm_ring_many()


def _warm_mapping() -> None:
    from .mapping import record_drive, run_fastslam
    from .sensing import expected_laser
    from .world import load_world

    log = record_drive("loop", [(3.0, 1.5)], seed=0, every=2)
    run_fastslam(log, 4, "laser", rng=0)
    run_fastslam(log, 4, "sonar", rng=0)
    world = load_world("loop")
    expected_laser(world, np.tile(world.start, (8, 1)))  # the threaded caster (K >= 8)


def _warm_explore() -> None:
    """Two robots exploring a small hall briefly, with the laser and the sonar."""
    from .exploration import ExploreSettings, explore_team
    from .world import generate_world

    world = generate_world("hall", 0)
    for sensor in ("laser", "sonar"):
        explore_team(world, 2, ExploreSettings(sensor=sensor, max_time=4.0), rng=0)


def _warm_ring_many() -> None:
    """Run the sonar ring's threaded kernels (more than 64 poses at once)."""
    from .sensing import SonarModel, expected_ranges, simulate_ranges
    from .world import load_world

    world = load_world("corridor")
    poses = np.tile(np.asarray(world.start, dtype=float), (65, 1))
    simulate_ranges(world, poses, SonarModel(), rng=0)
    expected_ranges(world, poses)


def _warm_large_map() -> None:
    """Measure distances on a map of many walls (through the bucket index)."""
    from .world import World
    from .world.index import INDEX_MIN_SEGMENTS

    x = np.arange(INDEX_MIN_SEGMENTS, dtype=float) * 0.1
    walls = np.column_stack([x, np.zeros_like(x), x + 0.05, np.ones_like(x)])
    world = World(segments=walls)
    world.distance_to_walls(np.zeros((3, 2)))
    world.distance_field(0.5)
    world.free_space(0.5)


def _warm_cone_table() -> None:
    """Build a small cone table, never read from the tables' disk cache.

    A table found on disk (one the same source built before, maybe in
    another clone sharing ``~/.cache``) skips the builder's kernels, which
    would then compile in the first lab that builds a table for another
    world.
    """
    from .localization import ConeTable
    from .world import World

    box = World(segments=[[0, 0, 1, 0], [1, 0, 1, 1], [1, 1, 0, 1], [0, 1, 0, 0]])
    saved = os.environ.get("ROBOTLIB_TABLE_CACHE")
    os.environ["ROBOTLIB_TABLE_CACHE"] = "off"
    try:
        ConeTable(box, resolution=0.25)
    finally:
        if saved is None:
            del os.environ["ROBOTLIB_TABLE_CACHE"]
        else:
            os.environ["ROBOTLIB_TABLE_CACHE"] = saved


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
    fast.log_likelihood(np.tile(poses, (100, 1)), z)  # the table, looked up
    fast.table.lookup(np.tile(poses, (2000, 1)))  # over threads (4,096 poses and up)
    _warm_cone_table()
    _warm_ring_many()


def _warm_landmarks() -> None:
    from .localization.ekf import ekf_predict, landmark_update
    from .mapping.ekfslam import observe_landmarks, world_landmarks
    from .world import load_world

    world = load_world("corridor")
    corners, pose = world_landmarks(world), np.asarray(world.start, dtype=float)
    ids, z = observe_landmarks(corners, pose, walls=world, rng=0)
    mu, P = ekf_predict(pose, np.eye(3) * 0.01, pose, pose + [0.1, 0.0, 0.1])
    landmark_update(mu, P, z, corners[ids], 0.05, 0.03)


def _paper(world):
    from .localization import MCL

    return MCL.paper(world, n=20, rng=0)


def _paper_fast(world):
    from .localization import MCL

    return MCL.paper(world, n=20, fast=True, rng=0)


def _beam_kld(world):
    from .localization import MCL, BeamSensorModel, KLDResampling

    model = BeamSensorModel(world)
    return MCL(world, model, resampling=KLDResampling(20, 40), n=20, rng=0)


def _best(world):
    from .localization import MCL

    return MCL.best(world, rng=0, n=10_000)  # the threaded fused step, KLD


def _beam_fast(world):
    from .localization import MCL, BeamSensorModel

    return MCL(world, BeamSensorModel(world, fast=True), n=20, rng=0)


def _paper_fast_many(world):
    from .localization import MCL

    return MCL.paper(world, n=10_000, fast=True, rng=0)  # the threaded fused step


WARMUPS: dict[str, Callable[[], None] | list[tuple[str, Callable[[], None]]]] = {
    "sim": _warm_sim,
    "mcl": [
        ("the paper's pieces", _warm_mcl_pieces),
        ("MCL.paper", _warm_filter(_paper)),
        ("MCL.paper (fast)", _warm_filter(_paper_fast)),
        ("MCL.paper (fast, threads)", _warm_filter(_paper_fast_many)),
        ("beam + KLD", _warm_filter(_beam_kld)),
        ("beam (fast)", _warm_filter(_beam_fast)),
        ("a cone table's builder", _warm_cone_table),
        ("MCL.best (threads)", _warm_filter(_best)),
        ("a large map", _warm_large_map),
    ],
    "mapping": _warm_mapping,
    "avoidance": _warm_avoidance,
    "models": _warm_models,
    "plan": _warm_plan,
    "explore": _warm_explore,
    "ekf": [  # Lab 1's EKF and its comparison with MCL
        ("landmarks", _warm_landmarks),
        ("MCL.best (threads)", _warm_filter(_best)),
    ],
}
"""What `warm_up` can compile: a name to a function that runs its kernels
once, or to a list of ``(label, function)`` steps (the progress bar counts
steps). Each lab adds its entry and names it in ``setup(warm=...)``."""
