"""The seeded building tour (`robotlib.experiments.tours`) and the kidnapping report."""

import importlib
import json

import numpy as np
import pytest

from robotlib.cli import main
from robotlib.experiments.tours import drive_tour, tour_space
from robotlib.localization import History
from robotlib.p3dx import ROBOT_RADIUS
from robotlib.world import World, load_world, seeded_world, write_map

rep = importlib.import_module("robotlib.experiments.reproduce")  # the module

TWO_ROOMS = [
    (0, 0, 8, 0),
    (8, 0, 8, 5),
    (8, 5, 0, 5),
    (0, 5, 0, 0),
    (4, 0, 4, 1.8),  # the dividing wall, a 1.2 m door at y 1.8-3.0
    (4, 3.0, 4, 5),
    (1.5, 3.5, 2.5, 3.5),  # a table in the west room
    (6.0, 1.0, 6.6, 1.0),  # a cabinet in the east room
    (6.0, 1.0, 6.0, 1.4),
]
"""An 8 m x 5 m flat of two rooms and a door, m."""


def two_rooms() -> World:
    return World(TWO_ROOMS, bounds=(-0.1, -0.1, 8.1, 5.1), start=(1.0, 1.0, 0.0))


@pytest.fixture(scope="module")
def office():
    return load_world("office")


@pytest.fixture(scope="module")
def tour(office):
    return drive_tour(office, seed=3, n_steps=40)


def _crosses(a, b, walls) -> np.ndarray:
    """Whether segment a-b (2,) properly crosses each wall (W, 4)."""
    p, q = walls[:, :2], walls[:, 2:]

    def orient(u, v, w):
        return np.sign((v[..., 0] - u[..., 0]) * (w[..., 1] - u[..., 1])
                       - (v[..., 1] - u[..., 1]) * (w[..., 0] - u[..., 0]))  # fmt: skip

    ab = orient(a, b, p) * orient(a, b, q) < 0
    return ab & (orient(p, q, a) * orient(p, q, b) < 0)


def test_tour_is_seeded_bit_for_bit(office, tour):
    again = drive_tour(office, seed=3, n_steps=40)
    for name in ("odometry", "sonar", "truth", "trace"):
        np.testing.assert_array_equal(getattr(tour, name), getattr(again, name))
    other = drive_tour(office, seed=4, n_steps=40)
    assert not np.array_equal(other.truth, tour.truth)


def test_tour_never_touches_or_crosses_a_wall(office, tour):
    trace = tour.trace
    assert len(trace) > 10 * len(tour)  # every 100 ms cycle, not only the steps
    clearance = office.distance_to_walls(trace[:, :2])
    assert clearance.min() > ROBOT_RADIUS  # the disc never touches a wall
    hops = np.hypot(*np.diff(trace[:, :2], axis=0).T)
    assert hops.max() < 0.1  # no jumps between cycles
    walls = np.asarray(office.obstacles)
    for a, b in zip(trace[:-1:5, :2], trace[5::5, :2], strict=False):
        assert not _crosses(a, b, walls).any()


def test_tour_moves_through_the_building_in_half_metre_steps(office, tour):
    assert tour.sonar.shape == (40, 8)
    odo_steps = np.hypot(*np.diff(tour.odometry[:, :2], axis=0).T)
    assert np.all((odo_steps > 0.45) & (odo_steps < 0.65))
    # it leaves the start room: the truth spans several metres both ways
    assert np.ptp(tour.truth[:, 0]) > 3.0 or np.ptp(tour.truth[:, 1]) > 3.0
    # and the sonar sees walls (readings under the 5 m maximum) on most steps
    assert (tour.sonar < 4.99).mean() > 0.5


def test_goals_are_reachable_and_clear():
    world = two_rooms()
    space = tour_space(world)
    assert space is tour_space(world)  # built once per world
    xy = space.cspace.to_metres(space.goals)
    assert world.distance_to_walls(xy).min() >= 0.45 - 1e-9
    assert (xy[:, 0] > 4).any() and (xy[:, 0] < 4).any()  # both rooms
    route = drive_tour(world, seed=0, n_steps=60)
    assert (route.truth[:, 0] > 4.3).any()  # through the door
    assert world.distance_to_walls(route.trace[:, :2]).min() > ROBOT_RADIUS


def test_kidnapping_moves_the_truth_not_the_odometry(office, tour):
    taken = drive_tour(office, seed=3, n_steps=40, kidnap=15)
    assert taken.kidnapped_at == 15 and tour.kidnapped_at is None
    np.testing.assert_array_equal(taken.truth[:15], tour.truth[:15])
    np.testing.assert_array_equal(taken.odometry[:15], tour.odometry[:15])
    jump = np.hypot(*(taken.truth[15, :2] - taken.truth[14, :2]))
    odo = np.hypot(*(taken.odometry[15, :2] - taken.odometry[14, :2]))
    assert odo < 0.7 and jump > odo + 0.5  # moved elsewhere; odometry saw a step
    assert office.distance_to_walls(taken.truth[15:, :2]).min() > ROBOT_RADIUS
    with pytest.raises(ValueError, match="kidnap"):
        drive_tour(office, seed=3, n_steps=10, kidnap=10)


def test_recovery_steps():
    e = np.array([9, 9, 0.1, 0.1, 0.1, 5.0, 0.2, 0.1, 0.1, 0.2, 0.25, 0.1, 3.0])
    assert rep.recovery_steps(e, 1) == 5  # steps 6..10 are the first 5 in a row
    assert rep.recovery_steps(e, 6) == 0
    assert rep.recovery_steps(e, 8) is None  # 3 good steps, then the log ends bad
    assert rep.recovery_steps(e[:5], 2, hold=3) == 0
    assert rep.recovery_steps(e, 1, tolerance=0.15) is None


def _history(errors) -> History:
    h = History()
    for e in errors:
        h.true_pose.append(np.array([e, 0.0, 0.0]))
        h.estimate.append(np.zeros(3))
    return h


def test_kidnap_summary_counts_recoveries():
    quick = [0.1] * 10 + [4.0] * 3 + [0.1] * 20  # recovers 3 steps after 10
    never = [0.1] * 10 + [4.0] * 23
    lost = [3.0] * 10 + [0.2] * 23  # was not localized before; finds it at once
    out = rep.summarize_kidnap([_history(x) for x in (quick, never, lost)], 10)
    assert out["recovery_steps"] == [3, None, 0]
    assert out["localized_at_kidnap_rate"] == pytest.approx(2 / 3)
    assert out["recovered_rate"] == pytest.approx(2 / 3)
    assert out["recovered_rate_localized"] == pytest.approx(1 / 2)
    assert out["recovery_steps_median"] == pytest.approx(1.5)


@pytest.mark.slow
def test_reproduce_kidnap_on_a_world_file(tmp_path, monkeypatch):
    path = tmp_path / "two_rooms.map"
    write_map(two_rooms(), path)
    small = rep.FilterConfig("best", "best", {"n": 2000, "kld": {"n_max": 2000}})
    monkeypatch.setattr(rep, "BEST_CONFIG", small)
    out = tmp_path / "r.json"
    args = ["reproduce", "--world", str(path), "--seeds", "1", "--steps", "20"]
    assert main([*args, "--kidnap", "8", "--json", str(out)]) == 0
    result = json.loads(out.read_text())
    for name in ("paper", "best"):
        kid = result[name]["kidnap"]
        assert kid["kidnap_step"] == 8 and len(kid["recovery_steps"]) == 1
        assert 0 <= result[name]["success_rate_50"] <= 1
    # the report's recovery agrees with a run of the same filter on the same tour
    world = load_world(path)
    taken = drive_tour(world, 0, 20, kidnap=8)
    errors = rep.run_filter(taken, small, 0).error
    assert result["best"]["kidnap"]["recovery_steps"] == [rep.recovery_steps(errors, 8)]
    with pytest.raises(SystemExit):
        main([*args, "--kidnap", "19"])


def test_mcl_panel_kidnap_button(office):
    from robotlib.experiments import drive_route
    from robotlib.widgets import mcl as widgets

    route = drive_route(office, seed=0, n_steps=14)
    panel = widgets.MCLPanel(route, n_steps=14, n=300, lam=0.5)
    assert panel.kidnap.value == 0 and "kidnapped" not in panel.status.value
    first = panel.history.true_pose
    panel.kidnap_button.click()
    assert panel.kidnap.value == 7  # halfway through the run
    taken = panel._route_of(panel.world.value, 7)
    assert taken.kidnapped_at == 7
    np.testing.assert_array_equal(np.array(panel.history.true_pose), taken.truth)
    assert not np.array_equal(np.array(first), taken.truth)
    assert "kidnapped before step 7" in panel.status.value
    assert panel.recovered_after == rep.recovery_steps(panel.history.error, 7)
    panel.kidnap.value = 4  # a step typed in the box
    assert panel._route_of(panel.world.value, 4).kidnapped_at == 4
    assert "kidnapped before step 4" in panel.status.value
    panel.kidnap.value = 0  # off again: the plain route
    np.testing.assert_array_equal(np.array(panel.history.true_pose), route.truth)


def test_reproduce_tours_a_fresh_generated_map_per_seed(tmp_path, monkeypatch):
    small = rep.FilterConfig("best", "best", {"n": 500, "kld": {"n_max": 500}})
    monkeypatch.setattr(rep, "BEST_CONFIG", small)
    seen = []
    real = rep.make_route

    def make_route(world, seed, n_steps, route="auto", kidnap=None):
        seen.append((world, seed, route))
        return real(world, seed, n_steps, route, kidnap)

    monkeypatch.setattr(rep, "make_route", make_route)
    out = tmp_path / "r.json"
    args = ["reproduce", "--world", "gen-hall", "--seeds", "2", "--steps", "4"]
    assert main([*args, "--json", str(out)]) == 0
    (w0, s0, r0), (w1, s1, r1) = seen
    assert (s0, s1) == (0, 1) and r0 == r1 == "tour"  # not the corridor drive
    assert w0 == seeded_world("gen-hall", 0) and w1 != w0
    result = json.loads(out.read_text())
    assert result["world"] == "gen-hall" and result["seeds"] == [0, 1]
