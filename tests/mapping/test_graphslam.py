"""Pose-graph SLAM: ICP, the edge Jacobians, the optimiser, a real log."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from robotlib.logs import read_log
from robotlib.mapping.graphslam import GraphSLAMSettings, graph_slam
from robotlib.mapping.icp import icp, scan_to_points, transform_points
from robotlib.mapping.posegraph import (
    PoseGraph,
    compose,
    edge_errors,
    edge_jacobians,
    optimize,
    prune_loops,
    relative_pose,
)
from robotlib.mapping.relations import read_relations, relation_errors

DATA = Path(__file__).resolve().parent.parent / "data"


def test_importing_mapping_leaves_scipy_sparse_and_spatial_for_later():
    import subprocess
    import sys

    code = (
        "import sys, robotlib.mapping; "
        "print(sorted(m for m in sys.modules if m.startswith('scipy.')))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert "'scipy.sparse" not in out and "'scipy.spatial" not in out, out


@pytest.mark.parametrize("seed", range(3))
def test_edge_jacobians_match_finite_differences(seed):
    rng = np.random.default_rng(seed)
    xi, xj, z = rng.normal(size=(3, 8, 3)) * [2.0, 2.0, 3.0]
    a, b = edge_jacobians(xi, xj, z)
    h = 1e-6
    for k in range(3):
        d = np.zeros(3)
        d[k] = h
        na = (edge_errors(xi + d, xj, z) - edge_errors(xi - d, xj, z)) / (2 * h)
        nb = (edge_errors(xi, xj + d, z) - edge_errors(xi, xj - d, z)) / (2 * h)
        np.testing.assert_allclose(a[:, :, k], na, atol=1e-7)
        np.testing.assert_allclose(b[:, :, k], nb, atol=1e-7)


def test_edge_error_is_zero_on_the_measured_motion():
    xi = np.array([[1.0, -2.0, 0.7]])
    z = np.array([[0.5, 0.2, -0.3]])
    np.testing.assert_allclose(edge_errors(xi, compose(xi, z), z), 0.0, atol=1e-12)
    np.testing.assert_allclose(relative_pose(xi, compose(xi, z)), z, atol=1e-12)


def _room(n=300):
    t = np.linspace(0.0, 1.0, n)
    walls = [
        np.c_[t * 6 - 3, np.full(n, -2.0)],
        np.c_[t * 6 - 3, np.full(n, 2.0)],
        np.c_[np.full(n, -3.0), t * 4 - 2],
        np.c_[np.full(n, 3.0), t * 4 - 2],
        np.c_[t - 0.5, np.full(n, 0.7)],
    ]
    return np.concatenate(walls)


@pytest.mark.parametrize("to_line", [False, True])
def test_icp_recovers_a_known_motion(to_line):
    rng = np.random.default_rng(1)
    room = _room()
    true = np.array([0.3, -0.15, 0.12])
    scan = transform_points(relative_pose(true, np.zeros(3)), room)
    scan += rng.normal(0.0, 0.01, scan.shape)
    r = icp(room, scan, init=(0.0, 0.0, 0.0), point_to_line=to_line)
    assert r.converged and r.inliers > 0.95
    assert np.hypot(*(r.pose[:2] - true[:2])) < 0.01
    assert abs(r.pose[2] - true[2]) < math.radians(0.3)
    assert r.rms < 0.03
    sd = np.sqrt(np.diag(r.covariance))
    assert np.all(np.linalg.eigvalsh(r.covariance) > 0) and np.all(sd < 0.01)


def _corridor(pilaster: bool):
    """Two walls 2 m apart along x, and a 0.3 x 0.2 m pilaster on the left one."""
    walls = [(-20.0, -1.0, 20.0, -1.0), (-20.0, 1.0, 20.0, 1.0)]
    if pilaster:
        walls += [(3.0, 1.0, 3.0, 0.8), (3.0, 0.8, 3.3, 0.8), (3.3, 0.8, 3.3, 1.0)]
    return np.array(walls)


@pytest.mark.parametrize("to_line", [False, True])
def test_icp_information_shows_a_blank_corridor_only_point_to_line(to_line):
    from robotlib.sensing.laser import LaserModel, expected_laser

    model = LaserModel(mount=(0.0, 0.0, 0.0))
    ref, cur = (
        scan_to_points(z, model.angles, model.max_range)
        for z in expected_laser(_corridor(False), [(0.0, 0.0, 0.0), (0.2, 0.0, 0.0)])
    )
    r = icp(ref, cur, init=(0.2, 0.0, 0.0), point_to_line=to_line)
    lam = np.linalg.eigvalsh(r.information[:2, :2])
    if to_line:  # next to nothing says where along the walls the scan lies
        assert lam[0] < 0.01 * lam[1]
    else:  # point to point pins every direction alike, corridor or not
        np.testing.assert_allclose(lam[0], lam[1], rtol=1e-9)
        np.testing.assert_allclose(np.linalg.inv(r.information), r.covariance)


def test_a_keyframe_match_keeps_the_odometry_along_what_icp_barely_pins():
    from robotlib.sensing.laser import LaserModel, expected_laser

    model = LaserModel()
    truth = np.array([[0.0, 0.0, 0.0], [0.25, 0.0, 0.0]])
    odometry = np.array([[0.0, 0.0, 0.0], [0.35, 0.0, 0.0]])  # 0.1 m long
    scans = expected_laser(_corridor(True), truth, model)
    placed = {}
    for ratio in (0.0, 0.1):
        settings = GraphSLAMSettings(match_degenerate=ratio, match_scans=False)
        r = graph_slam(odometry, scans, model.angles, model.max_range, settings,
                       mount=model.mount)  # fmt: skip
        ((_, _, z, info, kind),) = r.graph.edges
        assert kind == "scan" and abs(z[1]) < 0.01 and abs(z[2]) < 0.01
        placed[ratio] = z[0], info
    # whole: a few points of the pilaster's faces move the match along x
    assert abs(placed[0.0][0] - 0.25) < 0.03
    # pinned: along x the edge is the odometry's, with the odometry's weight
    z, info = placed[0.1]
    assert z == pytest.approx(0.35, abs=0.005)
    sigma = GraphSLAMSettings().odometry_sigma[0]
    assert np.linalg.inv(info)[0, 0] == pytest.approx(sigma**2, rel=0.1)
    assert info[1, 1] > 20 * info[0, 0]


def test_icp_rejects_bad_input():
    with pytest.raises(ValueError, match="3 points"):
        icp(np.zeros((2, 2)), np.zeros((5, 2)))
    with pytest.raises(ValueError, match="finite"):
        icp(np.full((5, 2), np.nan), np.zeros((5, 2)))


def _square_graph(rng, loop=True, wrong_loop=False):
    """A robot driving a 4 m square twice with drifting odometry."""
    steps = [np.array([0.5, 0.0, 0.0])] * 7 + [np.array([0.5, 0.0, math.pi / 2])]
    truth = [np.zeros(3)]
    for _ in range(2):
        for s in steps * 4:
            truth.append(compose(truth[-1], s))
    truth = np.array(truth)
    g = PoseGraph()
    g.add_pose(truth[0])
    info = np.diag([1 / 0.05**2, 1 / 0.05**2, 1 / 0.02**2])
    for k in range(1, len(truth)):
        z = relative_pose(truth[k - 1], truth[k]) + rng.normal(0, [0.03, 0.03, 0.02])
        z[2] += 0.01  # a bias: the drift
        g.add_pose(compose(g.poses[-1], z))
        g.add_edge(k - 1, k, z, info, "odometry")
    if loop:
        for k in range(32, len(truth)):  # the second lap sees the first
            z = relative_pose(truth[k - 32], truth[k])
            g.add_edge(k - 32, k, z, info * 4, "loop")
    if wrong_loop:
        g.add_edge(5, 50, np.array([3.0, -2.0, 1.0]), info * 4, "loop")
    return g, truth


def test_optimiser_closes_the_loop():
    g, truth = _square_graph(np.random.default_rng(0))
    before = np.hypot(*(g.poses[:, :2] - truth[:, :2]).T).max()
    res = optimize(g)
    after = np.hypot(*(g.poses[:, :2] - truth[:, :2]).T).max()
    assert res.converged and res.chi2_end < 0.01 * res.chi2_start
    assert before > 1.0 and after < 0.2
    np.testing.assert_array_equal(g.poses[0], truth[0])  # the gauge is held


def test_a_wrong_loop_is_pruned():
    plain, truth = _square_graph(np.random.default_rng(0), wrong_loop=True)
    pruned, _ = _square_graph(np.random.default_rng(0), wrong_loop=True)
    optimize(plain)
    assert prune_loops(pruned) == 1
    assert not any(e[:2] == (5, 50) for e in pruned.edges)

    def worst(g):
        return np.hypot(*(g.poses[:, :2] - truth[:, :2]).T).max()

    assert worst(pruned) < 0.2 < 1.0 < worst(plain)


def test_graph_checks_its_edges():
    g = PoseGraph()
    g.add_pose((0, 0, 0))
    with pytest.raises(ValueError, match="distinct"):
        g.add_edge(0, 0, (0, 0, 0), np.eye(3))
    g.add_pose((1, 0, 0))
    with pytest.raises(ValueError, match="positive definite"):
        g.add_edge(0, 1, (1, 0, 0), -np.eye(3))


def test_relation_errors_vanish_on_the_truth(tmp_path):
    rng = np.random.default_rng(2)
    poses = np.cumsum(rng.normal(0, 0.3, (20, 3)), axis=0)
    times = 100.0 + np.arange(20) * 0.5
    lines = ["# timestamp1 timestamp2 x y z roll pitch yaw"]
    for i, j in [(0, 3), (5, 6), (10, 19)]:
        x, y, yaw = relative_pose(poses[i], poses[j])
        lines.append(f"{times[i]} {times[j]} {x} {y} 0 0 0 {yaw}")
    lines.append(f"{times[0]} 999.0 0 0 0 0 0 0")  # no pose at that time
    (tmp_path / "r.relations").write_text("\n".join(lines) + "\n", encoding="ascii")
    rel = read_relations(tmp_path / "r.relations")
    err = relation_errors(times, poses, rel)
    assert err.unmatched == 1 and len(err.translation) == 3
    np.testing.assert_allclose(err.translation, 0.0, atol=1e-12)
    shifted = poses.copy()
    shifted[19, 0] += 0.1
    assert relation_errors(times, shifted, rel).translation.max() > 0.05


def _intel_head():
    states = [
        s for s in read_log(DATA / "intel_head.clf.bz2").states if "laser" in s.extra
    ]
    scans = np.array([s.extra["laser"] for s in states])
    lo, hi = states[0].extra["laser_angles"]
    angles = np.linspace(lo, hi, scans.shape[1])
    odo = np.array([s.pose for s in states])
    times = np.array([s.time for s in states])
    return odo, scans, angles, times


@pytest.mark.slow
def test_scans_between_keyframes_are_matched_not_dead_reckoned():
    from robotlib.mapping import heading_rms, record_drive

    log = record_drive(
        "loop", [(12.0, 1.5), (19.5, 1.5), (19.5, 8.0)], seed=51, every=2
    )
    m = log.laser_model
    run = [graph_slam(log.odometry, log.laser, m.angles, m.max_range,
                      GraphSLAMSettings(match_scans=on), mount=m.mount)
           for on in (False, True)]  # fmt: skip
    between = np.setdiff1d(np.arange(len(log)), run[1].keyframes)
    dead, matched = (heading_rms(r.poses[between], log.truth[between]) for r in run)
    assert matched < 0.6 * dead
    np.testing.assert_array_equal(run[0].graph.poses, run[1].graph.poses)


@pytest.mark.slow  # ~17 s: 400 scans matched into a pose graph
def test_graph_slam_on_the_head_of_the_intel_log():
    odo, scans, angles, times = _intel_head()
    rel = read_relations(DATA / "intel_head.relations")
    res = graph_slam(odo, scans, angles, 81.0, GraphSLAMSettings())
    assert res.poses.shape == odo.shape and res.failed_matches == 0
    assert len(res.graph.poses) == len(res.keyframes) > 20
    slam = relation_errors(times, res.poses, rel)
    raw = relation_errors(times, odo, rel)
    assert slam.unmatched == 0 and len(slam.translation) == 21
    assert slam.translation.mean() < 0.05
    assert slam.translation.mean() < raw.translation.mean()
