"""Avoidance: kernels against references, controllers on fixed sonar, the runner."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robotlib.avoidance import (
    AVOID_WORLDS,
    BRAITENBERG,
    VFH,
    Braitenberg,
    Bug2,
    Controller,
    PotentialField,
    StartGoal,
    VFHSettings,
    WallFollower,
    choose_direction,
    polar_histogram,
    potential_force,
    run_episode,
    run_episodes,
    smooth_histogram,
    start_goal_pairs,
)
from robotlib.avoidance import _kernels as kern
from robotlib.p3dx import AXLE_TRACK, SONAR_POSES
from robotlib.sim import SimRobot, Simulator
from robotlib.world import World, load_world
from tests import naive_avoidance as naive

SENSORS = np.ascontiguousarray(SONAR_POSES)
OPEN = np.full(8, 5.0)


# -- kernels against their references ------------------------------------------
@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_histogram_matches_reference(seed):
    rng = np.random.default_rng(seed)
    pts = rng.uniform(-3, 3, (30, 2))
    cert = rng.integers(0, 16, 30).astype(float)
    pose = np.array(
        [rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-np.pi, np.pi)]
    )
    n, window, enlarge = (
        int(rng.choice([36, 72])),
        rng.uniform(1, 3),
        rng.uniform(0, 0.5),
    )
    got = polar_histogram(pts, cert, pose, n, window, enlarge)
    want = naive.histogram_points(pts, cert, pose, n, window, enlarge)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-9)


def test_grid_histogram_is_the_points_histogram_of_its_cells():
    rng = np.random.default_rng(3)
    grid = np.where(rng.random((40, 40)) < 0.05, rng.integers(1, 16, (40, 40)), 0.0)
    x0, y0, res = -2.0, -2.0, 0.1
    pose = np.array([0.13, -0.21, 0.7])
    i, j = np.nonzero(grid)
    pts = np.column_stack([x0 + (j + 0.5) * res, y0 + (i + 0.5) * res])
    out = np.zeros(72)
    kern.histogram_grid(grid, x0, y0, res, pose, 1.8, 0.3, out)
    want = naive.histogram_points(pts, grid[i, j], pose, 72, 1.8, 0.3)
    np.testing.assert_allclose(out, want, rtol=1e-12, atol=1e-9)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(0, 5))
def test_smooth_matches_reference(seed, half):
    h = np.random.default_rng(seed).random(72) * 100
    np.testing.assert_allclose(smooth_histogram(h, half), naive.smooth(h, half))


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_certainty_update_matches_reference(seed):
    rng = np.random.default_rng(seed)
    grid = np.where(rng.random((50, 50)) < 0.3, rng.uniform(0, 15, (50, 50)), 0.0)
    pose = np.array(
        [rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-np.pi, np.pi)]
    )
    ranges = np.where(rng.random(8) < 0.2, 5.0, rng.uniform(0.1, 4.9, 8))
    args = (-2.5, -2.5, 0.1, pose, SENSORS, ranges, 5.0, math.radians(15), 2.5)
    want = naive.certainty_update(grid, *args, 3.0, 1.0, 15.0)
    got = grid.copy()
    kern.certainty_update(got, *args, 3.0, 1.0, 15.0)
    np.testing.assert_allclose(got, want, atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_vfh_plus_choice_matches_reference(seed):
    rng = np.random.default_rng(seed)
    n = 72
    blocked = np.zeros(n, dtype=bool)
    for _ in range(rng.integers(0, 5)):
        a, length = rng.integers(0, n), rng.integers(1, 40)
        blocked[(a + np.arange(length)) % n] = True
    target, previous = rng.uniform(-np.pi, np.pi, 2)
    mu = (5.0, 2.0, 2.0)
    got = kern.plus_direction(blocked, target, previous, 16, *mu)
    want = naive.plus_direction(blocked, target, previous, 16, mu)
    if math.isnan(want):
        assert math.isnan(got)
    else:
        assert got == pytest.approx(want, abs=1e-12)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_potential_force_matches_reference(seed):
    rng = np.random.default_rng(seed)
    ranges = np.where(rng.random(8) < 0.3, 5.0, rng.uniform(0.1, 2.0, 8))
    pose = np.array([*rng.uniform(-1, 1, 2), rng.uniform(-np.pi, np.pi)])
    goal = rng.uniform(-5, 5, 2)
    got = potential_force(ranges, pose, goal, 1.0, 0.5, 1.2)
    c, s = math.cos(pose[2]), math.sin(pose[2])
    d = goal - pose[:2]
    gx, gy = c * d[0] + s * d[1], -s * d[0] + c * d[1]
    want = naive.potential_force(ranges, SENSORS, 5.0, gx, gy, 1.0, 0.5, 1.2)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)


# -- the pieces a student writes, on hand-made inputs --------------------------
def test_histogram_puts_an_obstacle_ahead_in_the_middle_sectors():
    h = polar_histogram([[1.0, 0.0]], [10.0], [0.0, 0.0, 0.0], 72, 2.0, 0.3)
    # 100 * (1 - 1/2), within asin(0.3) = 17.5 deg of straight ahead
    assert h[36] == pytest.approx(50.0) and h[35] == pytest.approx(50.0)
    assert np.count_nonzero(h) == 6 and h[:30].sum() == 0


def test_choose_direction_rules():
    free = np.zeros(72)
    assert choose_direction(free, 1.0, 0.4) == pytest.approx(0.4)
    h = np.zeros(72)
    h[30:42] = 10.0  # blocked from -30 to +30 deg
    left = choose_direction(h, 1.0, math.radians(5), wide=16)
    assert left == pytest.approx(math.radians(30 + 40 + 2.5))  # 8 sectors in
    narrow = np.full(72, 10.0)
    narrow[44:48] = 0.0  # a 4-sector valley from 40 to 60 deg
    assert choose_direction(narrow, 1.0, 0.0) == pytest.approx(math.radians(50))
    assert math.isnan(choose_direction(np.full(72, 10.0), 1.0, 0.0))


def test_braitenberg_vehicles_turn_the_right_way():
    # an obstacle on the left (sonars 1-2 at 0.5 m)
    s = OPEN.copy()
    s[1:3] = 0.5
    turn = {
        k: Braitenberg(k, goal_gain=0).command(s, np.zeros(3))[1] for k in BRAITENBERG
    }
    assert turn["fear"] < 0 and turn["explorer"] < 0  # away
    assert turn["aggression"] > 0 and turn["love"] > 0  # towards
    act = np.clip(1 - s / 1.5, 0, 1)
    left, right = 0.35 + BRAITENBERG["fear"] @ act
    assert turn["fear"] == pytest.approx((right - left) / AXLE_TRACK)


def test_wall_follower_keeps_its_distance():
    wf = WallFollower(side="left", distance=0.6)
    s = OPEN.copy()
    s[0], s[1] = 0.9, 0.9 / math.cos(math.radians(40))  # parallel wall, too far
    assert wf.command(s, np.zeros(3))[1] > 0
    s[0], s[1] = 0.4, 0.4 / math.cos(math.radians(40))  # too near
    assert wf.command(s, np.zeros(3))[1] < 0
    s[3] = 0.3  # blocked ahead: turn away on the spot
    v, w = wf.command(s, np.zeros(3))
    assert v == 0 and w < 0


def test_controller_checks_shapes_and_stops_at_goal():
    c = VFH(goal=(0.1, 0.0))
    assert c.command(OPEN, np.zeros(3)) == (0.0, 0.0) and c.status == "reached"
    c.command(OPEN, np.zeros(3), goal=(3.0, 0.0))
    assert c.status == "ok"
    with pytest.raises(ValueError, match="shape"):
        c.command(np.ones(5), np.zeros(3))


def test_vfh_takes_checked_settings():
    c = VFH(settings=VFHSettings(threshold_high=200, n_sectors=36, max_speed=0.25))
    assert c.threshold_high == 200.0 and isinstance(c.threshold_high, float)
    assert c.histogram.shape == (36,) and c.max_speed == 0.25
    assert c.settings.threshold_low == VFHSettings().threshold_low
    with pytest.raises(ValueError, match="threshold_low"):
        VFHSettings(threshold_low=200.0, threshold_high=100.0)
    with pytest.raises(ValueError, match="fade"):
        VFHSettings(fade=0.0)
    with pytest.raises(TypeError, match="VFHSettings"):
        VFH(settings={"window": 2.0})


def test_vfh_grid_remembers_what_it_saw():
    c = VFH(goal=(5.0, 0.0))
    s = OPEN.copy()
    s[3] = s[4] = 1.0
    for _ in range(math.ceil(c.cmax / c.increment)):  # enough echoes to saturate
        c.command(s, np.zeros(3))
    assert c.grid.max() == c.cmax
    assert c.histogram[34:38].min() > c.threshold_high  # blocked straight ahead
    assert abs(c.steer) > math.radians(10)  # steers round it


# -- episodes ------------------------------------------------------------------
class Constant(Controller):
    """Drive straight at a fixed speed (a do-nothing-clever controller)."""

    name = "constant"

    def __init__(self, v=0.4, **kw):
        self.v = v
        super().__init__(**kw)

    def _command(self, sonar, pose):
        return self.v, 0.0


BOX = World(
    segments=[[0, 0, 6, 0], [6, 0, 6, 4], [6, 4, 0, 4], [0, 4, 0, 0]],
    start=(1.0, 2.0, 0.0),
    name="box",
)


def test_runner_success_timeout_and_collision():
    ok = run_episode(BOX, Constant(), goal=(3.0, 2.0), seed=1, max_time=30)
    assert ok.outcome == "reached" and ok.success and ok.collisions == 0
    assert math.hypot(*(ok.odometry[-1, :2] - [3.0, 2.0])) <= 0.3
    late = run_episode(BOX, Constant(v=0.0), goal=(3.0, 2.0), seed=1, max_time=5)
    assert late.outcome == "timeout" and not late.success
    assert len(late.time) == 51 and late.duration == pytest.approx(5.0)
    crash = run_episode(BOX, Constant(), goal=(3.0, 3.0), seed=1, max_time=30)
    assert crash.outcome == "collision" and crash.collisions == 1
    assert crash.min_clearance < 0.01 and not crash.success
    n = len(crash.time)
    assert crash.odometry.shape == (n, 3) and crash.sonar.shape == (n, 8)
    assert crash.commands.shape == (n, 2) and crash.truth.shape == (n, 3)


def test_seeded_episodes_are_reproducible():
    pair = start_goal_pairs("clutter", 1, seed=5)[0]
    a, b = (
        run_episode(
            "clutter", VFH(), goal=pair.goal, start=pair.start, seed=3, max_time=20
        )
        for _ in range(2)
    )
    np.testing.assert_array_equal(a.truth, b.truth)
    np.testing.assert_array_equal(a.commands, b.commands)


def test_start_goal_pairs_are_seeded_free_and_reachable():
    for name in AVOID_WORLDS:
        world = load_world(name)
        pairs = start_goal_pairs(name, 10, seed=1)
        assert pairs == start_goal_pairs(name, 10, seed=1)
        assert pairs != start_goal_pairs(name, 10, seed=2)
        free = world.free_space(0.05, 0.3)
        for p in pairs:
            for xy in (p.start[:2], p.goal):
                assert world.distance_to_walls(np.array(xy)) >= 0.7
                i, j = free.cell_of(np.array(xy))
                assert free.data[i, j]


@pytest.mark.slow
def test_vfh_reaches_a_goal_in_the_clutter_and_the_field_gets_trapped():
    pairs = start_goal_pairs("clutter", 2, seed=0)
    eps = run_episodes("clutter", VFH(), pairs, seed=0)
    assert any(e.success for e in eps)
    assert all(e.collisions == 0 for e in eps)
    pair = start_goal_pairs("utrap", 1, seed=0)[0]
    pf = run_episode("utrap", PotentialField(), pair.goal, start=pair.start, seed=0)
    assert pf.outcome == "local_minimum"
    assert pf.truth[-1, 0] < 7.0  # stuck on the trap's near side


def test_run_episodes_counts_its_episodes_on_a_bar_it_is_given():
    made = []

    class Bar:
        def __init__(self, total, desc):
            self.total, self.desc, self.n, self.closed = total, desc, 0, False
            made.append(self)

        def update(self, k):
            self.n += k

        def close(self):
            self.closed = True

    box = World(segments=[[0, 0, 4, 0], [4, 0, 4, 3], [4, 3, 0, 3], [0, 3, 0, 0]])
    pairs = [StartGoal((1.0, 1.5, 0.0), (3.0, 1.5))] * 3
    eps = run_episodes(box, VFH(), pairs, max_time=1.0, progress=Bar)
    (bar,) = made
    assert len(eps) == 3 and (bar.total, bar.n, bar.closed) == (3, 3, True)
    assert "VFH" in bar.desc


def test_bug2_follows_a_wall_round_a_box():
    walls = [[0, 0, 10, 0], [10, 0, 10, 5], [10, 5, 0, 5], [0, 5, 0, 0]]
    walls += [[4, 1.5, 5, 1.5], [5, 1.5, 5, 3.5], [5, 3.5, 4, 3.5], [4, 3.5, 4, 1.5]]
    world = World(segments=walls, start=(1.5, 2.5, 0.0), name="one box")
    ep = run_episode(world, Bug2(), goal=(8.0, 2.5), seed=0, max_time=90)
    assert ep.outcome == "reached", ep.outcome
    assert ep.collisions == 0


def test_bug2_leaves_the_boundary_towards_a_goal_on_its_free_side():
    bug = Bug2(goal=(5.0, 0.0))
    blocked = OPEN.copy()
    blocked[2:6] = 0.4  # something close ahead
    # the boundary is on the left: a goal square to the right lies away from it
    assert bug._goal_side_free(blocked, -math.pi / 2)
    assert bug._goal_side_free(OPEN, 0.3)
    assert not bug._goal_side_free(blocked, 0.3)  # ahead-left, and blocked
    assert not bug._goal_side_free(OPEN, 2.5)  # round to the left: unseen


def test_bug2_draws_a_new_m_line_when_its_goal_moves():
    bug = Bug2(goal=(5.0, 0.0))
    bug.command(OPEN, np.array([0.0, 0.0, 0.0]))
    bug.command(OPEN, np.array([1.0, 0.0, 0.0]), goal=(5.1, 0.0))  # jitter: same
    assert bug.start.tolist() == [0.0, 0.0]
    bug.mode = "follow"
    bug.command(OPEN, np.array([2.0, 0.0, 0.0]), goal=(2.0, 4.0))  # the next one
    assert bug.start.tolist() == [2.0, 0.0] == bug.hit_point.tolist()
    assert bug.mode == "follow"  # it leaves the boundary by Bug2's own test
    assert bug._on_m_line(np.array([2.0, 3.0]))  # the line runs up to it
    assert not bug._on_m_line(np.array([3.0, 0.0]))


def test_the_same_controller_drives_a_simrobot():
    sim = Simulator(load_world("clutter"), seed=0)
    pair = start_goal_pairs("clutter", 1, seed=0)[0]
    r = SimRobot(sim, sim.add_robot(pair.start))
    ep = run_episode(r, VFH(), goal=pair.goal, max_time=10)
    assert ep.world == "clutter" and len(ep.time) == 101


def test_fused_vfh_step_is_the_kernels_one_by_one():
    rng = np.random.default_rng(8)
    grid = np.where(rng.random((60, 60)) < 0.1, rng.uniform(0, 15, (60, 60)), 0.0)
    pose = np.array([0.2, -0.3, 0.9])
    ranges = rng.uniform(0.3, 5.0, 8)
    common = (-3.0, -3.0, 0.1, pose, SENSORS, ranges, 5.0, math.radians(15), 2.5)
    blocked0 = rng.random(72) < 0.3
    g1, b1, raw1, h1 = grid.copy(), blocked0.copy(), np.zeros(72), np.zeros(72)
    kern.fade(g1, -3.0, -3.0, 0.1, pose[0], pose[1], 5.0, 0.97)
    kern.certainty_update(g1, *common, 3.0, 1.0, 15.0)
    kern.histogram_grid(g1, -3.0, -3.0, 0.1, pose, 1.8, 0.3, raw1)
    kern.smooth(raw1, 2, h1)
    kern.hysteresis(h1, 75.0, 150.0, b1)
    want = kern.plus_direction(b1, 0.4, -0.2, 16, 5.0, 2.0, 2.0)
    g2, b2, raw2, h2 = grid.copy(), blocked0.copy(), np.zeros(72), np.zeros(72)
    got = kern.vfh_step(g2, *common, 3.0, 1.0, 15.0, 0.97, 1.8, 0.3, 2, raw2, h2,
                        75.0, 150.0, b2, 0.4, -0.2, 16, 5.0, 2.0, 2.0)  # fmt: skip
    assert got == want
    np.testing.assert_array_equal(g1, g2)
    np.testing.assert_array_equal(h1, h2)
    np.testing.assert_array_equal(b1, b2)


def test_vfh_sonar_brake_acts_on_one_echo():
    # a fresh grid has no certainty yet: only the brake sees the wall 0.3 m ahead
    sonar = np.full(8, 5.0)
    sonar[3:5] = 0.3
    pose, goal = np.zeros(3), np.array([5.0, 0.0])
    braked = VFH(goal)
    braked.reset()
    v, _ = braked.command(sonar, pose)
    sx, sy, sa = SONAR_POSES[3]
    x, y = sx + 0.3 * math.cos(sa), sy + 0.3 * math.sin(sa)  # the echo on the axis
    free = x - math.sqrt(0.28**2 - y**2) - 0.05  # the disc (+3 cm) stops 5 cm short
    assert 0.0 < v <= math.sqrt(2 * 0.25 * free) + 1e-9
    blind = VFH(goal, VFHSettings(brake=0.0))
    blind.reset()
    assert blind.command(sonar, pose)[0] > v + 0.1
    # an echo beside the path does not brake
    side = np.full(8, 5.0)
    side[[0, 7]] = 0.2
    braked.reset()
    blind.reset()
    assert braked.command(side, pose)[0] == pytest.approx(blind.command(side, pose)[0])


@pytest.mark.parametrize("direction", [None, choose_direction])
def test_vfh_boxed_in_steers_into_the_thinnest_valley(direction):
    dense = np.full(72, 5000.0)
    dense[30:42] = 200.0  # blocked (threshold 150), but the thinnest: ahead
    boxed = VFH((5.0, 0.0), histogram=lambda p, c, pose: dense, direction=direction)
    boxed.reset()
    v, _ = boxed.command(np.full(8, 5.0), np.zeros(3))
    assert abs(boxed.steer) < math.radians(30) and v > 0
    # nothing thinner anywhere (all above 8 x 150): it turns in place
    walled = VFH(
        (5.0, 0.0), histogram=lambda p, c, pose: np.full(72, 5000.0),
        direction=direction,
    )  # fmt: skip
    walled.reset()
    v, w = walled.command(np.full(8, 5.0), np.zeros(3))
    assert math.isnan(walled.steer) and v == 0 and w != 0
