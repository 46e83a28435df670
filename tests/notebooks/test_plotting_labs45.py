"""The planning (Lab 4) and mapping (Lab 5) figures and the mapping panel.

The labs draw these in every notebook run (slow tests); here each is drawn
once on small data, so the fast loop exercises them too.
"""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest

from robotlib import load_world
from robotlib.mapping import OccupancyGrid, record_drive
from robotlib.planning import astar, configuration_space, rrt
from robotlib.planning.navigation import Navigation
from robotlib.plotting import mapping as rpm
from robotlib.plotting import planning as rpp
from robotlib.widgets.mapping import MappingPanel, build_map


@pytest.fixture
def ax():
    fig, ax = plt.subplots()
    yield ax
    plt.close(fig)


@pytest.fixture(scope="module")
def office():
    return load_world("office")


@pytest.fixture(scope="module")
def cspace(office):
    return configuration_space(office, resolution=0.1)


def test_cspace_and_search_expansion(ax, office, cspace):
    plan = astar(cspace, (1.5, 7.5), (5.0, 7.5), record=True)
    assert plan.found and len(plan.order) > 0
    rpp.plot_cspace(ax, cspace, world=office)
    blocked = ax.images[-1].get_array()
    assert (~blocked.mask).sum() == cspace.blocked.sum()  # dark cells: the blocked
    rpp.plot_expansion(ax, cspace, plan.order, upto=10)
    shown = ax.images[-1].get_array()
    assert (~shown.mask).sum() == 10  # the first ten cells expanded, coloured
    (line,) = rpp.plot_path(ax, plan.path, "r-")
    np.testing.assert_array_equal(line.get_xydata(), plan.path)


def test_search_animation_ends_on_the_path(cspace):
    plan = astar(cspace, (1.5, 7.5), (5.0, 7.5), record=True)
    fig, ax = plt.subplots()
    page = rpp.animate_search(fig, ax, cspace, plan, frames=2)
    assert "<script" in page.data
    assert ax.get_title() == f"{len(plan.order)} of {len(plan.order)} expanded"


def test_tree_edges_and_path(ax, office):
    tree = rrt(office, (1.5, 7.5), (5.0, 7.5), rng=0)
    assert tree.found
    rpp.plot_tree(ax, tree)
    (edges,) = ax.collections
    assert len(edges.get_segments()) == len(tree.nodes) - 1  # one per child
    np.testing.assert_array_equal(ax.lines[-1].get_xydata(), tree.path)


def test_navigation_record_is_drawn_with_its_outcome(ax, office):
    truth = np.array([[1.5, 7.5, 0.0], [2.0, 7.5, 0.0], [2.5, 7.4, 0.0]])
    nav = Navigation(
        np.arange(3.0) * 0.1, truth, truth + 0.05, truth, np.zeros((3, 2)),
        np.zeros(3, np.int8), np.zeros((3, 8)), np.zeros(3, bool),
        plans=[truth[:, :2]], hits=np.array([[3.0, 7.0]]),
        goal=np.array([2.5, 7.5]), outcome="reached",
    )  # fmt: skip
    rpp.plot_navigation(ax, office, nav)
    labels = [line.get_label() for line in ax.lines]
    for label in ("plans", "marked echoes", "true path", "MCL estimate", "goal"):
        assert label in labels
    assert ax.get_title().startswith("reached in")


def test_logodds_grid_is_clipped_and_placed(ax):
    grid = OccupancyGrid((4, 6), origin=(1.0, 2.0), resolution=0.5)
    grid.logodds[1, 2] = 9.0
    grid.logodds[2, 3] = -9.0
    im = rpm.plot_logodds(ax, grid, limit=4.0)
    assert im.get_extent() == [1.0, 4.0, 2.0, 4.0]
    assert im.get_array().max() == 4.0 and im.get_array().min() == -4.0


def test_map_over_truth_paths_and_ekf(ax, office):
    grid = OccupancyGrid.for_world(office, 0.2)
    grid.logodds[5, 5] = 2.0
    rpm.plot_map_vs_truth(ax, grid, office, title="F1 1.00")
    occupied = ax.images[-1].get_array()
    assert (~occupied.mask).sum() == 1 and ax.get_title() == "F1 1.00"
    path = np.array([[1.0, 1.0, 0.0], [2.0, 1.5, 0.0]])
    rpm.plot_paths(ax, truth=path, odometry=path + 0.1, particles=[path, path])
    labels = [line.get_label() for line in ax.lines]
    assert "true" in labels and "odometry" in labels and "SLAM" not in labels
    mu = np.array([1.0, 1.0, 0.0, 3.0, 4.0, 5.0, 6.0])
    P = np.diag([0.1, 0.2, 0.01, 0.3, 0.3, 0.4, 0.4])
    before = len(ax.lines)
    rpm.plot_ekf(ax, mu, P, landmarks=[[3.0, 4.0], [5.0, 6.0]])
    # landmarks, the pose's ellipse and dot, two landmark ellipses, the estimates
    assert len(ax.lines) - before == 6


def test_fastslam_animation_shows_the_last_snapshot(office):
    grid = OccupancyGrid.for_world(office, 0.2)
    frames = [(grid, np.array([[1.0, 1.0], [1.0 + k, 1.0]])) for k in range(3)]
    fig, ax = plt.subplots()
    page = rpm.animate_fastslam(fig, ax, frames, world=office)
    assert "<script" in page.data
    np.testing.assert_array_equal(ax.lines[-1].get_xdata(), [1.0, 3.0])


@pytest.fixture(scope="module")
def short_log():
    return record_drive("loop", [(12.0, 1.5), (15.0, 1.5)], seed=4, every=2)


def test_build_map_true_poses_map_at_least_as_well_as_odometry(short_log):
    for sensor in ("sonar", "laser"):
        true_map, true_score = build_map(short_log, sensor, "true")
        _, odo_score = build_map(short_log, sensor, "odometry")
        assert true_map.resolution == (0.1 if sensor == "sonar" else 0.05)
        assert true_score.f1 >= odo_score.f1 > 0.0, sensor
    grid, score = build_map(short_log, "laser", "fastslam", n_particles=5)
    assert grid.shape == short_log.world.occupancy_grid(0.05).shape
    assert 0.0 < score.f1 <= 1.0


def test_mapping_panel_redraws_on_every_choice(short_log):
    panel = MappingPanel(short_log)
    assert len(panel.out.outputs) == 1 and panel.score is not None
    assert panel.status.value == f"sonar, true poses: F1 {panel.score.f1:.2f}"
    panel.sensor.value = "laser"
    assert panel.status.value.startswith("laser, true poses: F1")
    shown = panel.out.outputs[0]
    panel.poses.value = "odometry"
    assert panel.status.value.startswith("laser, odometry poses: F1")
    assert panel.out.outputs[0] != shown  # a new figure
    assert "robotlib-stale" not in panel.out._dom_classes  # drawn, not greyed
