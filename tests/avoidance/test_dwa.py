"""The dynamic window: its roll-out kernel, its safety, its episodes."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from robotlib.avoidance import (
    DWA,
    DWASettings,
    choose_velocity,
    dynamic_window,
    evaluate_window,
    run_episode,
    run_episodes,
    start_goal_pairs,
)
from robotlib.avoidance import _kernels as kern
from robotlib.avoidance.dwa import open_directions
from robotlib.avoidance.dwa_grid import ObstacleGrid, navigation
from robotlib.world import World
from tests import naive_avoidance as naive


def _cloud(rng, n=40):
    r = rng.uniform(0.1, 3.0, n)
    a = rng.uniform(-math.pi, math.pi, n)
    return np.column_stack([r * np.cos(a), r * np.sin(a)])


@pytest.mark.parametrize("seed", range(4))
def test_rollout_kernel_matches_reference(seed):
    rng = np.random.default_rng(seed)
    pts = _cloud(rng)
    vs = np.linspace(0.0, 0.5, 6)
    ws = np.linspace(-1.0, 1.0, 9)
    goal = rng.uniform(-4, 4, 2)
    out = [np.empty((6, 9)) for _ in range(4)]
    kern.dwa_evaluate(pts, vs, ws, 25, 0.1, 0.3, 0.3, goal, *out)
    ref = naive.dwa_evaluate(pts, vs, ws, 25, 0.1, 0.3, 0.3, goal)
    for got, want in zip(out, ref, strict=True):
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)


def _touches(points, v, w, distance, radius):
    """Whether the disc, driven ``distance`` m along the arc, approaches a point."""
    if v <= 0.0:
        return False
    t = np.linspace(0.0, distance / v, 200)
    if abs(w) > 1e-9:
        x, y = v / w * np.sin(w * t), v / w * (1 - np.cos(w * t))
    else:
        x, y = v * t, 0 * t
    d = np.hypot(points[:, 0] - x[:, None], points[:, 1] - y[:, None]) - radius
    d0 = np.hypot(points[:, 0], points[:, 1]) - radius
    return bool(((d <= 0) & (d < d0 - 1e-3)).any())


@pytest.mark.parametrize("seed", range(20))
def test_never_commands_a_velocity_that_hits_a_seen_obstacle_within_braking(seed):
    rng = np.random.default_rng(seed)
    s = DWASettings(step=0.02)  # fine steps: the contact found to 1 cm at 0.5 m/s
    pts = _cloud(rng, 60)
    v0, w0 = rng.uniform(0, 0.5), rng.uniform(-1, 1)
    vs, ws = dynamic_window(v0, w0, s)
    goal = rng.uniform(-4, 4, 2)
    free, heading, togo, gap = evaluate_window(pts, vs, ws, goal, s)
    v, w, score = choose_velocity(vs, ws, free, heading, togo, gap, np.hypot(*goal), s)
    braking = v * s.latency + v**2 / (2 * s.accel)
    # shrink the disc by what one roll-out step can skip past
    assert not _touches(pts, v, w, braking, s.radius - 0.5 * s.max_speed * s.step)
    if np.isfinite(score).any():
        i, j = np.unravel_index(np.argmax(score), score.shape)
        assert (vs[i], ws[j]) == (v, w)
    else:
        assert (v, w) == (0.0, 0.0)


def test_window_respects_the_accelerations_and_limits():
    s = DWASettings()
    vs, ws = dynamic_window(0.2, 0.1, s)
    assert vs.min() == pytest.approx(0.2 - s.accel * s.window_time)
    assert vs.max() == pytest.approx(0.2 + s.accel * s.window_time)
    assert np.abs(ws - 0.1).max() <= s.rot_accel * s.window_time + 1e-12
    assert 0.0 in ws
    vs, ws = dynamic_window(0.0, s.max_turn, s)
    assert vs.min() == 0.0 and ws.max() == s.max_turn
    vs, _ = dynamic_window(0.9, 0.0, s)  # above the limit: brakes towards it
    assert vs.max() <= s.max_speed


def test_nothing_admissible_means_stop():
    s = DWASettings()
    wall = np.column_stack([np.full(30, 0.32), np.linspace(-1.5, 1.5, 30)])
    wall = np.concatenate([wall, wall * [-1, 1], wall[:, ::-1], -wall[:, ::-1]])
    vs, ws = dynamic_window(0.5, 0.0, s)  # too fast to stop inside the box
    free, heading, togo, gap = evaluate_window(wall, vs, ws, (3.0, 0.0), s)
    v, w, score = choose_velocity(vs, ws, free, heading, togo, gap, 3.0, s)
    assert (v, w) == (0.0, 0.0) and np.isneginf(score).all()


def test_side_clearance_prefers_the_arc_away_from_a_wall_ahead_on_the_left():
    s = DWASettings()
    wall = np.column_stack([np.linspace(0.5, 3.0, 26), np.full(26, 0.45)])  # left
    vs, ws = np.array([0.3]), np.array([-0.3, 0.0, 0.3])
    free, heading, togo, gap = evaluate_window(wall, vs, ws, (3.0, 0.0), s)
    assert gap[0, 1] == pytest.approx(0.15, abs=0.01)  # straight on: 0.45 - 0.3
    assert gap[0, 0] > gap[0, 1] > gap[0, 2]  # right, ahead, left
    # with the goal straight ahead, only the side clearance tells the arcs
    # apart among equally fast ones that turn as much
    _, w, _ = choose_velocity(vs, ws[[0, 2]], free[:, [0, 2]], heading[:, [0, 2]],
                              togo[:, [0, 2]], gap[:, [0, 2]], 3.0, s)  # fmt: skip
    assert w == -0.3


def test_open_directions_sees_a_wall_ahead():
    wall = np.column_stack([np.full(41, 1.0), np.linspace(-2, 2, 41)])
    angles, free = open_directions(wall, 0.3, n=8)
    ahead = np.argmin(np.abs(angles - math.pi / 8))
    assert free[ahead] < 1.0
    assert np.isinf(free[np.abs(angles) > math.pi / 2]).all()


def test_settings_are_checked():
    with pytest.raises(ValueError, match="horizon"):
        DWASettings(horizon=0.0)
    with pytest.raises(ValueError, match="weights"):
        DWASettings(heading_weight=-1.0)
    with pytest.raises(TypeError):
        DWA(settings={"horizon": 2.0})
    s = dataclasses.replace(DWASettings(), n_v=3)
    assert isinstance(s.n_v, int) and DWA(settings=s).settings.n_v == 3
    with pytest.raises(ValueError, match="goal"):
        evaluate_window(np.zeros((1, 2)), [0.1], [0.0], (1.0, 2.0, 3.0), s)


def test_dwa_drives_round_a_box_without_touching_it():
    walls = [[0, 0, 10, 0], [10, 0, 10, 5], [10, 5, 0, 5], [0, 5, 0, 0]]
    walls += [[4, 2.0, 5, 2.0], [5, 2.0, 5, 3.0], [5, 3.0, 4, 3.0], [4, 3.0, 4, 2.0]]
    world = World(segments=walls, start=(1.5, 2.5, 0.0), name="one box")
    ep = run_episode(world, DWA(), goal=(8.0, 2.5), seed=0, max_time=60)
    assert ep.outcome == "reached", ep.outcome
    assert ep.collisions == 0 and ep.min_clearance > 0.02


def test_navigation_function_leads_round_a_u_trap():
    res = 0.1
    occ = np.zeros((60, 80), dtype=bool)  # 8 m x 6 m, rows are y
    occ[15, 30:50] = occ[45, 30:50] = True  # the U's arms, open to the west
    occ[15:46, 50] = True  # its back wall
    goal = (30, 70)  # row, column: east of the U
    dist = navigation(occ, res, goal, block=0.25, margin=0.5)
    assert dist[goal] == 0.0
    # from inside the U the way out is round an arm, not through the wall
    inside = dist[30, 45]
    assert inside > 2 * 2.0 + 2.0  # out of the mouth and round: > 6 m
    # an empty grid gives the 8-connected path length
    free = navigation(np.zeros((20, 20), bool), res, (0, 0), 0.25, 0.5)
    assert free[0, 10] == pytest.approx(1.0) and free[10, 10] == pytest.approx(
        10 * math.sqrt(2) * res
    )


def test_carrot_follows_the_descent_round_an_arm():
    grid = ObstacleGrid(resolution=0.1, extent=10.0)
    grid.origin = np.array([0.0, 0.0])
    grid.certainty[15, 30:50] = grid.certainty[45, 30:50] = 5.0
    grid.certainty[15:46, 50] = 5.0
    pose = np.array([4.5, 3.05, 0.0])  # inside the U, facing its back wall
    goal = np.array([7.0, 3.05])
    grid.plan(pose, goal, block=0.25, margin=0.5, border=3.0)
    carrot, togo = grid.carrot(pose, goal, 1.5)
    assert carrot[0] < pose[0]  # back out towards the mouth
    assert togo > 6.0
    near, _ = grid.carrot(goal + [0.3, 0.0], goal, 1.5)
    np.testing.assert_allclose(near, goal)  # the goal itself once within reach


def _true_outcomes(world, n):
    pairs = start_goal_pairs(world, n, seed=0)
    return run_episodes(world, DWA(), pairs, 120.0, seed=0)


@pytest.mark.slow
def test_dwa_goes_through_the_doorway():
    eps = _true_outcomes("doorway", 4)
    assert all(e.collisions == 0 for e in eps)
    through = 0
    for e in eps:  # the true path crosses the wall at x = 6 m within the door
        k = np.nonzero(np.diff(np.sign(e.truth[:, 0] - 6.0)))[0]
        through += bool(len(k)) and all(3.2 < e.truth[i, 1] < 4.0 for i in k)
    assert through >= 3, through
    assert sum(e.true_success for e in eps) >= 2


@pytest.mark.slow
def test_dwa_gets_out_of_the_u_trap():
    pairs = start_goal_pairs("utrap", 4, seed=0)
    eps = run_episodes("utrap", DWA(), pairs, 120.0, seed=0)
    assert all(e.collisions == 0 and e.outcome == "reached" for e in eps)
    for e, p in zip(eps, pairs, strict=True):
        # truly out of the U (mouth west, back wall at x = 7 m) and round it:
        # east of the back wall and near the goal; the odometry's drift over
        # these 15-20 m paths (up to ~1 m) keeps the true 0.5 m verdict for
        # some of them (the bench counts it)
        assert e.truth[-1, 0] > 7.5
        assert math.dist(e.truth[-1, :2], p.goal) < 1.5


def test_dwa_without_a_goal_says_so():
    with pytest.raises(ValueError, match="needs a goal"):
        DWA().command(np.full(8, 5.0), np.zeros(3))
