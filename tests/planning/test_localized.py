"""`Localized`: an avoider aimed by MCL on the map, judged by the true pose."""

import math

import numpy as np
import pytest

from robotlib.avoidance import VFH, run_episode, start_goal_pairs
from robotlib.planning import Localized
from robotlib.world import World, load_world


class _Fixed:
    """A stand-in filter whose estimate is given."""

    def __init__(self, estimate):
        self.estimate = np.asarray(estimate, dtype=float)

    def step(self, odo_prev, odo_now, z):
        return self.estimate


@pytest.mark.parametrize(
    ("estimate", "expected"),
    [
        ((1.5, 1.0, 0.0), (4.5, 5.0)),  # truly 0.5 m further along x
        ((1.0, 1.0, math.pi / 2), (5.0, -3.0)),  # truly turned a quarter left
    ],
)
def test_the_goal_is_moved_into_the_odometry_frame(estimate, expected):
    c = Localized(VFH(), load_world("clutter"), goal=(5.0, 5.0), rng=0)
    sonar, pose = np.full(8, 5.0), np.array([1.0, 1.0, 0.0])
    c.command(sonar, pose)  # starts the filter at the first pose
    assert np.allclose(c.inner.goal, (5.0, 5.0))
    c.mcl = _Fixed(estimate)
    c.command(sonar, pose)
    assert np.allclose(c.estimate, estimate)
    assert np.allclose(c.inner.goal, expected)
    assert c.goal.tolist() == [5.0, 5.0]  # the map goal stays


def test_reaches_truly_where_odometry_alone_ends_off():
    world = load_world("clutter")
    pair = start_goal_pairs("clutter", 10, seed=13)[1]
    plain = run_episode(world, VFH(), goal=pair.goal, start=pair.start, seed=9)
    aimed = run_episode(
        world, Localized(VFH(), world, rng=1), goal=pair.goal, start=pair.start,
        seed=9,
    )  # fmt: skip
    assert plain.outcome == aimed.outcome == "reached"
    assert plain.true_error > 1.0  # this seed's odometry drifts
    assert aimed.true_success and aimed.true_error < 0.25
    assert aimed.controller == "VFH+MCL" and aimed.collisions == 0


def test_rejects_what_is_not_a_controller_or_a_world():
    world = load_world("clutter")
    with pytest.raises(TypeError, match="Controller"):
        Localized(object(), world)
    with pytest.raises(TypeError, match="World"):
        Localized(VFH(), "clutter")


def test_tolerance_is_the_wrapped_controllers():
    c = Localized(VFH(), load_world("clutter"))
    c.tolerance = 0.2
    assert c.inner.tolerance == 0.2 == c.tolerance


def test_waypoints_lead_through_the_door_of_a_room():
    walls = [[0, 0, 9, 0], [9, 0, 9, 6], [9, 6, 0, 6], [0, 6, 0, 0]]
    walls += [[4.5, 0, 4.5, 4.8]]  # a partition, the way round it by the top
    world = World(segments=walls, start=(2.0, 1.0, 0.0), name="partition")
    runs = {
        plan: run_episode(
            world, Localized(VFH(), world, rng=2, plan=plan), goal=(7.0, 1.0),
            start=(2.0, 1.0, 0.0), seed=4,
        )
        for plan in (False, True)
    }  # fmt: skip
    e = runs[True]
    assert e.true_success and e.collisions == 0 and e.duration < 40.0
    # VFH alone first follows the partition the wrong way (20-30 m driven)
    assert e.path_length < 0.6 * runs[False].path_length
    assert e.truth[:, 1].max() > 4.8  # it went round the partition's end
