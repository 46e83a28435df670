import math

import numpy as np
import pytest

from robotlib.localization import MCL
from robotlib.pioneer.server import SimServer
from robotlib.planning import (
    GOALS,
    Navigation,
    Navigator,
    NavSettings,
    PathFollower,
    PurePursuit,
    StopAndTurn,
    astar,
    configuration_space,
    cross_track,
    navigate,
    office_with_boxes,
    pure_pursuit,
)
from robotlib.planning.navigate import TURN_MARGIN, _spread
from robotlib.robot import robot
from robotlib.sim import OdometryNoise, SimRobot, Simulator
from robotlib.world import compose, load_world


def test_pure_pursuit_law():
    assert pure_pursuit((0, 0, 0), (1, 0), 0.3) == (0.3, 0.0)
    v, w = pure_pursuit((0, 0, 0), (1, 1), 0.3, w_max=10)
    alpha, dist = math.pi / 4, math.sqrt(2)
    assert v == 0.3 and w == pytest.approx(0.3 * 2 * math.sin(alpha) / dist)
    v, w = pure_pursuit((0, 0, 0), (1, -1), 0.3, w_max=10)
    assert w < 0
    assert pure_pursuit((0, 0, math.pi / 2), (0, -1), 0.3, 0.7) == (0.0, 0.7)
    assert pure_pursuit((0, 0, 0), (1, 1), 0.3, w_max=0.1)[1] == 0.1


def test_cross_track():
    path = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0]])
    pts = np.array([[1.0, 0.5], [3.0, 1.0], [-1.0, 0.0], [2.0, 3.0]])
    np.testing.assert_allclose(cross_track(path, pts), [0.5, 1.0, 1.0, 1.0])


@pytest.fixture(scope="module")
def office():
    return load_world("office")


def test_pure_pursuit_tracks_an_astar_path(office):
    cs = configuration_space(office, margin=TURN_MARGIN)
    plan = astar(cs, (1.5, 7.5), (12.5, 3.0))
    r = SimRobot(Simulator(office, seed=0, odometry=OdometryNoise.none()))
    pp = PurePursuit(plan.path, lookahead=0.3, speed=0.3)
    xy = []
    for _ in range(1500):
        v, w = pp.command(r.true_pose())
        if pp.done:
            break
        r.setvel(v)
        r.setrotvel(w)
        r.readsonar()
        assert not r.state.stalled
        xy.append(r.true_pose()[:2])
    assert pp.done
    ct = cross_track(plan.path, np.array(xy))
    assert np.sqrt(np.mean(ct**2)) < 0.05
    assert np.hypot(*(xy[-1] - plan.path[-1])) < 0.15


def test_follower_hands_only_unmapped_obstacles_to_the_avoider():
    f = PathFollower(PurePursuit([[0, 0], [5, 0]]), StopAndTurn())
    open_ = np.full(8, 5.0)
    near = open_.copy()
    near[3:5] = 0.5
    assert f.command(open_, (0, 0, 0), open_) == pytest.approx((0.3, 0.0), abs=0.2)
    assert not f.avoiding
    f.command(near, (0, 0, 0), near + 0.05)  # a mapped wall: keep following
    assert not f.avoiding
    v, w = f.command(near, (0, 0, 0), open_)  # unmapped: the avoider steers
    assert f.avoiding and f.avoider.goal is not None
    f.command(np.full(8, 0.3), (0, 0, 0), np.full(8, 0.3))  # too close anyway
    assert f.avoiding
    for _ in range(f.release_cycles):
        f.command(open_, (0, 0, 0), open_)
    assert not f.avoiding


def test_goal_sets_are_free_and_reachable():
    for name, sets in GOALS.items():
        world = load_world(name)
        cs = configuration_space(world, margin=TURN_MARGIN)
        assert len(sets) >= 2
        for goals in sets.values():
            for g in goals:
                assert astar(cs, world.start, g).found, (name, g)


def test_bad_goal_is_a_clear_error(office):
    r = SimRobot(Simulator(office, seed=0))
    with pytest.raises(ValueError, match="goal .* inside an obstacle"):
        navigate(r, office, (5.0, 3.0))


def test_navigator_takes_checked_settings_and_runs_once(office):
    with pytest.raises(ValueError, match="filter_every"):
        NavSettings(filter_every=0)
    with pytest.raises(ValueError, match="speed"):
        NavSettings(speed=-0.3)
    with pytest.raises(TypeError, match="NavSettings"):
        Navigator(office, (2.5, 3.0), settings={"speed": 0.3})
    mcl = MCL.best(office, rng=0, n=300, init=office.start)
    nav = Navigator(office, (2.5, 3.0), mcl=mcl, settings=NavSettings(speed=0.2))
    r = SimRobot(Simulator(office, seed=0))
    record = nav.run(r, max_time=1.0)
    assert record.outcome == "timeout" and nav.outcome == "timeout"
    assert np.abs(record.command[:, 0]).max() <= 0.2  # (spins in place first)
    with pytest.raises(RuntimeError, match="runs once"):
        nav.run(r)


def run(world_map, world_sim, goal, seed):
    r = SimRobot(Simulator(world_sim, seed=seed))
    return navigate(r, world_map, goal, rng=seed)


@pytest.mark.slow
def test_navigate_past_an_unmapped_box_from_global_localization(office):
    sim_world = office_with_boxes()
    a = run(office, sim_world, (7.5, 5.2), 2)
    assert a.success, (a.outcome, a.final_error)
    assert a.localized_at > 0 and len(a.plans) >= 1 and len(a.hits) > 0
    assert a.duration <= 180 and not a.stalled.any()
    # clearance from every wall and box along the true path
    assert sim_world.distance_to_walls(a.truth[:, :2]).min() > 0.2
    b = run(office, sim_world, (7.5, 5.2), 2)
    for field in ("truth", "estimate", "command", "sonar", "mode"):
        assert np.array_equal(getattr(a, field), getattr(b, field)), field


def test_navigate_in_the_maze():
    maze = load_world("maze")
    nav = run(maze, maze, GOALS["maze"]["corners"][1], 1)
    assert nav.success and nav.duration <= 180


def test_navigate_over_tcp(office):
    start = np.array(office.start)
    # lock-step: the run is the same however slow this client is (a busy machine)
    with SimServer(office, robots=1, port=0, lockstep=True, seed=0) as srv:
        r = robot(srv.addresses[0], lockstep=True)
        try:
            mcl = MCL.best(office, rng=0, n=2000, init=start)  # tracking start
            nav = navigate(
                r, office, (2.5, 3.0), mcl=mcl, settings=NavSettings(min_filter_steps=3)
            )
        finally:
            r.disconnect()
    assert nav.reached, nav.outcome
    assert np.isnan(nav.truth).all()  # a Pioneer reports no true pose
    assert np.hypot(*(nav.estimate[-1, :2] - (2.5, 3.0))) < 0.2


def test_navigator_confirms_the_goal_with_a_second_filter_of_its_own(office):
    own = Navigator(office, (7.5, 5.2), rng=3)
    assert own.second is not None and own.second is not own.mcl
    told = MCL.best(office, rng=0, n=2000, init=np.array(office.start))
    assert Navigator(office, (7.5, 5.2), mcl=told).second is None  # trusted alone
    alone = Navigator(office, (7.5, 5.2), rng=3, settings=NavSettings(confirm=0.0))
    assert alone.second is None
    with pytest.raises(ValueError, match="confirm"):
        NavSettings(confirm=-1.0)


class _Cloud:
    """A stand-in filter: just the particles and weights `Navigator` reads."""

    def __init__(self, particles):
        self.particles = np.asarray(particles, dtype=float)
        self.weights = np.full(len(self.particles), 1.0 / len(self.particles))


def test_navigator_trusts_only_a_belief_settled_over_its_window(office):
    nav = Navigator(office, (2.5, 3.0), mcl=MCL.best(office, rng=0, n=300))
    nav._start_localizing(0.0)
    rng = np.random.default_rng(0)
    here = np.array([2.0, 2.0, 0.3])
    tight = here + rng.normal(0.0, [0.03, 0.03, 0.01], (500, 3))
    nav.mcl = _Cloud(tight)
    odo = np.zeros(3)
    for k in range(nav.settings.window):
        assert not nav._settled()  # not yet a whole window
        step = np.array([0.02 * k, 0.0, 0.0])
        nav._note_belief(compose(here, step), compose(odo, step))
    assert nav._settled()
    # a jump of the estimate that the odometry does not explain
    nav._note_belief(compose(here, [3.0, 0.0, 0.0]), compose(odo, [0.5, 0.0, 0.0]))
    assert not nav._settled()
    # tight by its spread (under 0.15 m), but 6 % of it 0.6 m off: not unimodal
    nav._start_localizing(0.0)
    split = tight.copy()
    split[:30, 0] += 0.6
    nav.mcl = _Cloud(split)
    assert _spread(nav.mcl)[0] < nav.settings.spread
    for _ in range(nav.settings.window):
        nav._note_belief(here, odo)
    assert not nav._settled()


def test_false_reached_is_judged_by_the_truth():
    def record(outcome, end):
        truth = np.array([[0.0, 0.0, 0.0], [*end, 0.0]])
        return Navigation(
            np.arange(2.0), truth, truth, truth, np.zeros((2, 2)),
            np.zeros(2, np.int8), np.zeros((2, 8)), np.zeros(2, bool),
            goal=np.array([5.0, 0.0]), outcome=outcome,
        )  # fmt: skip

    assert record("reached", (2.0, 0.0)).false_reached
    assert not record("reached", (4.7, 0.0)).false_reached
    assert not record("timeout", (2.0, 0.0)).false_reached
