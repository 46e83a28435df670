"""Laser FastSLAM along a blank corridor: the fit's curvature, the constrained fit."""

import math
from dataclasses import replace

import numpy as np

from robotlib.mapping import FastSLAMSettings, record_drive, run_fastslam
from robotlib.mapping import _kernels_match as kern
from robotlib.mapping.fastslam import constrained_fit
from robotlib.world import World
from tests import naive_mapping as naive


def test_fit_curvature_kernel_matches_the_reference():
    rng = np.random.default_rng(3)
    shape, origin, res = (40, 60), (-0.5, -0.5), 0.1
    n = 3
    Ls = np.maximum(rng.normal(0, 2, (n, *shape)), 0).astype(np.float32)
    poses = np.column_stack(
        [rng.uniform(1, 4, n), rng.uniform(1, 2.5, n), rng.uniform(-3, 3, n)]
    )
    mount = np.array([0.16, 0.01, 0.02])
    angles = np.linspace(-math.pi / 2, math.pi / 2, 19)
    z = rng.uniform(0.2, 2.0, 19)
    z[[1, 7]] = 4.0  # no return
    out = np.empty((n, 3))
    kern.fit_curvature_many(Ls, *origin, res, poses, mount, angles, z, 4.0, res, out)
    for k in range(n):
        want = naive.fit_curvature(
            Ls[k], origin, res, poses[k], mount, angles, z, 4.0, res
        )
        np.testing.assert_allclose(out[k], want, rtol=1e-9, atol=1e-6)


def test_fit_curvature_is_small_along_a_wall_and_large_across_it():
    res = 0.05
    L = np.zeros((1, 40, 200), dtype=np.float32)
    L[0, 30, :] = 6.0  # a wall along x at y = 1.525 (cell centres)
    angles = np.radians(np.linspace(20, 160, 15))  # all beams meet the wall
    pose = np.array([[5.0, 0.5, 0.0]])
    z = (1.525 - 0.5) / np.sin(angles)
    out = np.empty((1, 3))
    kern.fit_curvature_many(
        L, 0.0, 0.0, res, pose, np.zeros(3), angles, z, 8.0, res, out
    )
    cxx, cxy, cyy = out[0]
    assert cyy > 100 * abs(cxx) and cyy > 0
    assert abs(cxy) < 0.01 * cyy


def test_constrained_fit_keeps_only_the_pinned_directions():
    poses = np.zeros((3, 3))
    fits = np.array([[0.1, 0.02, 0.01], [0.1, 0.02, 0.01], [0.1, 0.1, 0.0]])
    curv = np.array(
        [
            [10.0, 0.0, 1000.0],  # y pinned, x free: keep dy only
            [1000.0, 0.0, 1000.0],  # both pinned: the fit
            [500.0, 500.0, 500.0],  # pinned along (1, 1)/sqrt 2, free across it
        ]
    )
    out = constrained_fit(poses, fits, curv, 0.2)
    np.testing.assert_allclose(out[0], [0.0, 0.02, 0.01])
    np.testing.assert_allclose(out[1], fits[1])
    np.testing.assert_allclose(out[2], [0.1, 0.1, 0.0], atol=1e-12)
    flat = constrained_fit(poses, fits, np.zeros((3, 3)), 0.2)  # nothing pinned
    np.testing.assert_allclose(flat[:, :2], 0.0)
    np.testing.assert_allclose(flat[:, 2], fits[:, 2])


def _blank_corridor() -> World:
    """A closed corridor 40 m x 2.5 m, nothing on its walls."""
    w, h = 40.0, 2.5
    walls = [(0, 0, w, 0), (w, 0, w, h), (w, h, 0, h), (0, h, 0, 0)]
    return World(walls, start=(1.0, 1.25, 0.0), name="blank corridor")


def test_blank_corridor_fit_no_longer_drags_the_pose_back():
    # 20 m down a blank corridor whose far wall stays out of the laser's
    # 8 m: the walls pin the heading and the across position only
    world = _blank_corridor()
    log = record_drive(world, [(21.0, 1.25)], seed=1, every=2)
    assert log.truth[-1, 0] > 20.5
    whole = run_fastslam(log, 20, rng=1)
    pinned = run_fastslam(
        log, 20, rng=1, settings=replace(FastSLAMSettings(), match_degenerate=0.2)
    )
    along_whole = whole.path[-1, 0] - log.truth[-1, 0]
    along_pinned = pinned.path[-1, 0] - log.truth[-1, 0]
    along_odometry = log.odometry[-1, 0] - log.truth[-1, 0]
    # the whole fit pulls the pose back towards the cells seen most often
    # (about 8.6 m behind after 20 m)
    assert along_whole < -3.0
    # the constrained fit keeps the odometry's increment along the corridor
    # (0.32 m behind, the odometry 0.31 m)
    assert abs(along_pinned - along_odometry) < 0.25
    assert pinned.rms < 0.5 * whole.rms
