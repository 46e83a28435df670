"""Laser FastSLAM's GMapping proposal: kernels against NumPy, the draw, a corridor."""

import math
from dataclasses import replace

import numpy as np
import pytest

from robotlib.mapping import FastSLAMSettings, record_drive, run_fastslam
from robotlib.mapping import _kernels_proposal as kern
from robotlib.mapping.proposal import (
    gaussian_draw,
    motion_log_prior,
    proposal_offsets,
    scan_normals,
    to_map_frame,
)
from robotlib.world import World
from tests import naive_mapping as naive

SHAPE, ORIGIN, RES = (30, 40), (-0.5, -0.25), 0.1
FIELD = (0.0, 0.08, 0.1)  # occupied above log-odds 0, sigma 0.08 m, p_rand 0.1


def _maps_and_points(n=3, seed=5):
    rng = np.random.default_rng(seed)
    Ls = rng.normal(-1.0, 2.0, (n, *SHAPE)).astype(np.float32)
    pts = np.column_stack([rng.uniform(-1.5, 1.5, 17), rng.uniform(-1.5, 1.5, 17)])
    pts[3] = (40.0, 0.0)  # off the grid from every pose below
    t = rng.uniform(-3, 3, 17)
    nrm = np.column_stack([np.cos(t), np.sin(t)])
    nrm[[2, 5, 11]] = 0.0  # no normal: whole distances
    poses = np.column_stack(
        [rng.uniform(1, 2.5, n), rng.uniform(1, 2, n), rng.uniform(-3, 3, n)]
    )
    return Ls, pts, nrm, poses


def _ends(pts, nrm):
    return tuple(np.ascontiguousarray(v) for v in (*pts.T, *nrm.T))


def test_field_loglik_kernel_matches_the_reference():
    Ls, pts, nrm, poses = _maps_and_points()
    cands = to_map_frame(poses, proposal_offsets((0.07, 0.03, 0.05)))
    out = np.empty(cands.shape[:2])
    kern.field_loglik_many(Ls, *ORIGIN, RES, cands, *_ends(pts, nrm), *FIELD, out)
    for n in range(len(Ls)):
        for k in (0, 7, 22, 44):
            want = naive.field_score(Ls[n], ORIGIN, RES, cands[n, k], pts, nrm, *FIELD)
            assert out[n, k] == pytest.approx(want, rel=1e-12, abs=1e-12)


def test_fit_pose_kernel_matches_the_reference():
    Ls, pts, nrm, poses = _maps_and_points()
    sig = np.array([0.05, 0.04, 0.03])
    out = np.empty_like(poses)
    kern.fit_pose_many(
        Ls, *ORIGIN, RES, poses, *_ends(pts, nrm), *FIELD, 0.5, sig, 0.04, 0.02, 3, out
    )
    for n in range(len(Ls)):
        want = naive.fit_pose(
            Ls[n], ORIGIN, RES, poses[n], pts, nrm, FIELD, 0.5, sig, (0.04, 0.02), 3
        )
        np.testing.assert_allclose(out[n], want, rtol=0, atol=1e-12)
    assert not np.allclose(out, poses)  # it moved


def test_motion_log_prior_matches_the_kernels_and_the_reference():
    rng = np.random.default_rng(2)
    pred = np.column_stack([rng.uniform(0, 3, (4, 2)), rng.uniform(-3, 3, 4)])
    poses = pred[:, None, :] + rng.normal(0, 0.1, (4, 6, 3))
    sig = np.array([0.02, 0.01, 0.03])
    got = motion_log_prior(poses, pred, sig)
    for n in range(4):
        for k in range(6):
            want = naive.motion_log_prior(poses[n, k], pred[n], sig)
            assert got[n, k] == pytest.approx(want, rel=1e-12)
            assert kern.log_prior(*poses[n, k], *pred[n], *sig) == pytest.approx(
                want, rel=1e-12
            )


def test_scan_normals_match_the_reference_and_face_a_wall():
    rng = np.random.default_rng(4)
    angles = np.linspace(-math.pi / 2, math.pi / 2, 31)
    z = 1.0 / np.maximum(np.cos(angles), 0.2)  # a wall 1 m ahead, clipped
    z[[6, 20]] = 8.0  # no return
    z[13] += 0.3  # a bump: no normal there
    z += rng.normal(0, 0.002, 31)
    mount = np.array([0.02, 0.01, 0.0])
    pts, nrm = scan_normals(mount, angles, z, 8.0, step=1, bend=0.03)
    want_pts, want_nrm = naive.scan_normals(mount, angles, z, 8.0, 0.03)
    np.testing.assert_allclose(pts, want_pts, atol=1e-12)
    np.testing.assert_allclose(nrm, want_nrm, atol=1e-12)
    flat = np.abs(angles) < 1.3  # on the wall, off the clipped ends
    ok = z < 8.0
    facing = np.abs(nrm[:, 0])[(flat & ok)[ok]]
    assert (facing[facing > 0] > 0.99).all()  # normal along x, either sign
    assert (nrm[(np.arange(31) == 13)[ok]] == 0).all()
    kept, _ = scan_normals(mount, angles, z, 8.0, step=3)
    np.testing.assert_allclose(kept, want_pts[(np.arange(31) % 3 == 0)[ok]])


def test_to_map_frame_moves_along_and_across_the_heading():
    out = to_map_frame(np.array([[1.0, 2.0, math.pi / 2]]), np.array([[0.5, 0.2, 0.1]]))
    np.testing.assert_allclose(out[0, 0], [0.8, 2.5, math.pi / 2 + 0.1], atol=1e-12)


def test_gaussian_draw_recovers_a_gaussians_moments_and_normaliser():
    spacing = np.array([0.02, 0.01, 0.01])
    offsets = proposal_offsets(spacing, (21, 21, 21))
    mean, sd = np.array([0.01, -0.005, 0.004]), np.array([0.03, 0.012, 0.02])
    log_tau = -0.5 * (((offsets - mean) / sd) ** 2).sum(axis=1)[None, :] + 3.0
    n = 4000
    fits = np.tile([2.0, 1.0, 0.3], (n, 1))
    normals = np.random.default_rng(0).standard_normal((n, 3))
    draws, log_eta = gaussian_draw(
        fits, offsets, np.repeat(log_tau, n, axis=0), np.full(3, 1e-9), normals
    )
    # the normaliser: the sum of the points' tau
    np.testing.assert_allclose(log_eta, np.log(np.exp(log_tau).sum()), rtol=1e-12)
    d = draws - fits
    c, s = math.cos(0.3), math.sin(0.3)
    local = np.column_stack(
        [c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1], d[:, 2]]
    )
    np.testing.assert_allclose(local.mean(axis=0), mean, atol=3 * sd.max() / 60)
    np.testing.assert_allclose(local.std(axis=0), sd, rtol=0.06)


def test_gaussian_draw_keeps_the_floor_when_one_point_takes_all():
    offsets = proposal_offsets((0.01, 0.01, 0.01))
    log_tau = np.full((2, len(offsets)), -1e6)
    log_tau[:, len(offsets) // 2] = 0.0  # the centre only
    fits = np.zeros((2, 3))
    floor = np.array([0.002, 0.001, 0.003])
    pose, _ = gaussian_draw(fits, offsets, log_tau, floor, np.ones((2, 3)))
    np.testing.assert_allclose(pose, np.tile(floor, (2, 1)), atol=1e-9)


@pytest.mark.slow
def test_blank_corridor_gaussian_proposal_keeps_the_odometrys_increment():
    # 20 m down a blank corridor whose far wall stays out of the laser's 8 m:
    # the scan pins the heading and the across position only, the proposal's
    # draw follows the odometry along it
    w, h = 40.0, 2.5
    walls = [(0, 0, w, 0), (w, 0, w, h), (w, h, 0, h), (0, h, 0, 0)]
    world = World(walls, start=(1.0, 1.25, 0.0), name="blank corridor")
    log = record_drive(world, [(21.0, 1.25)], seed=1, every=2)
    settings = replace(FastSLAMSettings(), proposal="gaussian")
    r = run_fastslam(log, 20, rng=1, settings=settings)
    along = r.path[-1, 0] - log.truth[-1, 0]
    along_odometry = log.odometry[-1, 0] - log.truth[-1, 0]
    assert abs(along - along_odometry) < 0.25
    across = np.abs(r.path[:, 1] - log.truth[:, 1]).max()
    assert across < 0.05
    assert r.score.f1 > 0.9
