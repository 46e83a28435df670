"""Short explorations judged by the true map: coverage, map quality, no collision."""

import numpy as np
import pytest

from robotlib import load_world
from robotlib.exploration import (
    ExploreSettings,
    explore,
    explore_team,
    frontier_cells,
    reachable_area,
    team_starts,
)
from robotlib.mapping import OccupancyGrid
from robotlib.world import seeded_world


def test_settings_and_starts_refuse_bad_input():
    with pytest.raises(ValueError):
        ExploreSettings(sensor="radar")
    with pytest.raises(ValueError):
        ExploreSettings(strategy="random")
    with pytest.raises(ValueError):
        ExploreSettings(speed=0)
    w = load_world("office")
    with pytest.raises(ValueError):
        team_starts(w, 5)
    starts = team_starts(w, 3)
    assert starts.shape == (3, 3)
    assert np.all(w.is_free(starts[:, :2], 0.35))
    d = np.hypot(*(starts[:, None, :2] - starts[None, :, :2]).transpose(2, 0, 1))
    assert d[~np.eye(3, dtype=bool)].min() > 0.6


def test_reachable_area_is_free_and_holds_the_start():
    w = load_world("office")
    r = reachable_area(w, 0.1)
    g = OccupancyGrid.for_world(w, 0.1)
    assert r.shape == g.shape
    assert not (r & w.occupancy_grid(0.1).data).any()
    i = int((w.start[1] - g.origin[1]) // 0.1)
    j = int((w.start[0] - g.origin[0]) // 0.1)
    assert r[i, j]


def test_the_loop_uses_the_frontiers_and_chooser_it_is_given():
    """Lab 7 plugs a student's functions in: they are called, and checked."""
    w = load_world("office")
    short = ExploreSettings(max_time=12.0)
    calls = []

    def spy(state):
        calls.append(np.shape(state))
        return frontier_cells(state)

    def stay(costs, *rest):  # never a target: the robot looks round, then is done
        return np.full(len(np.atleast_2d(costs)), -1)

    res = explore(w, settings=short, rng=0, frontiers=spy, chooser=stay)
    assert calls and all(c == res.map.shape for c in calls)
    assert res.outcome != "timeout" and res.path_lengths[0] < 0.5
    with pytest.raises(ValueError, match="shape"):
        explore(w, settings=short, rng=0, frontiers=lambda s: np.zeros((3, 3), bool))
    with pytest.raises(ValueError, match="targets for 2 robots"):
        explore_team(w, 2, short, rng=0, chooser=lambda c, *rest: np.array([0]))


@pytest.mark.slow
def test_one_robot_explores_the_office_and_comes_home():
    w = load_world("office")
    res = explore(w, settings=ExploreSettings(max_time=400.0), rng=3)
    assert res.explored >= 0.95
    assert res.score.f1 >= 0.9
    assert res.collisions == 0
    assert res.outcome == "home"
    assert np.hypot(*(res.paths[0][-1, :2] - np.asarray(w.start[:2]))) < 0.6
    assert res.time_to(0.9) < res.duration


@pytest.mark.slow
def test_a_team_of_two_explores_without_touching():
    w = load_world("office")
    res = explore_team(w, 2, ExploreSettings(max_time=200.0, go_home=False), rng=4)
    assert res.explored >= 0.9
    assert res.robot_collisions == 0 and res.wall_collisions == 0
    assert np.all(res.path_lengths > 2.0)  # both robots took part


@pytest.mark.slow
def test_two_robots_each_waiting_for_the_other_do_not_wait_for_ever():
    """Generated office 4: the two robots, heading for doors on either side of
    the corridor, each saw the other ahead and waited (12 % explored at
    400 s); the later one now waits for the earlier one only."""
    w = seeded_world("gen-office", 4)
    res = explore_team(w, 2, ExploreSettings(max_time=150.0, go_home=False), rng=4)
    assert res.explored >= 0.9
    assert res.robot_collisions == 0 and res.wall_collisions == 0


@pytest.mark.slow
def test_a_team_whose_teammate_parked_on_its_way_home_parks_too():
    """The building, three robots: the third parked on the second's start,
    and the second, in sight of it, re-planned home every second for the
    rest of the run (timeout at 1200 s, 99.7 % explored by 110 s)."""
    w = load_world("building")
    res = explore_team(w, 3, ExploreSettings(max_time=400.0), rng=0)
    assert res.outcome == "home"
    assert res.explored >= 0.95
    assert res.collisions == 0
