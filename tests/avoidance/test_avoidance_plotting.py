"""Avoidance drawings: what they draw from an episode, a histogram, a force field."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Polygon  # noqa: E402

from robotlib.avoidance import VFH, force_field, run_episode  # noqa: E402
from robotlib.plotting.avoidance import (  # noqa: E402
    animate_episode,
    plot_clearance,
    plot_episode,
    plot_force_field,
    plot_polar_histogram,
)
from robotlib.world import World  # noqa: E402

BOX = World(
    segments=[[0, 0, 6, 0], [6, 0, 6, 4], [6, 4, 0, 4], [0, 4, 0, 0], [3, 1, 3, 3]],
    start=(1.0, 2.0, 0.0),
    name="box",
)


def test_episode_drawings():
    ep = run_episode(BOX, VFH(), goal=(5.0, 2.0), seed=0, max_time=8)
    fig, (a, b) = plt.subplots(1, 2)
    plot_episode(a, ep, BOX)
    path = [ln for ln in a.lines if ln.get_label() == "path"][0]
    np.testing.assert_allclose(path.get_xydata(), ep.truth[:, :2])
    plot_clearance(b, ep)
    np.testing.assert_allclose(b.lines[0].get_ydata(), ep.clearance)
    page = animate_episode(ep, BOX, every=20, max_frames=2)
    assert "<img" in page.data or "frames" in page.data
    plt.close("all")


def test_episode_draws_the_robot_at_the_cycle_asked():
    ep = run_episode(BOX, VFH(), goal=(5.0, 2.0), seed=0, max_time=4)
    k = len(ep.time) // 3
    fig, ax = plt.subplots()
    plot_episode(ax, ep, BOX, echoes=False, at=k)
    (robot,) = [p for p in ax.patches if isinstance(p, Polygon)]
    centre = robot.get_xy()[:-1].mean(axis=0)
    assert np.hypot(*(centre - ep.truth[k, :2])) < 0.2
    assert np.hypot(*(centre - ep.truth[-1, :2])) > 0.3
    plt.close(fig)


def test_polar_histogram_marks_blocked_sectors():
    h = np.zeros(72)
    h[30:40] = 10.0
    fig = plt.figure()
    ax = fig.add_subplot(projection="polar")
    plot_polar_histogram(ax, h, threshold=5.0, steer=1.0, target=0.0)
    red = [p for p in ax.patches if p.get_facecolor()[0] > 0.8]
    assert len(red) == 10 and len(ax.patches) == 72
    plt.close(fig)


def test_force_field_points_to_the_goal_in_the_open():
    x, y, fx, fy = force_field(BOX, (5.0, 2.0), resolution=0.5)
    assert x.shape == fx.shape
    inside = (x > 0) & (x < 6) & (y < 0.2)
    assert inside.any() and np.isnan(fx[inside]).all()  # too near the wall to fit
    i, j = np.unravel_index(np.nanargmin(np.hypot(x - 4.75, y - 1.75)), x.shape)
    assert fx[i, j] > 0 and fy[i, j] > 0  # towards (5, 2), nothing near
    fig, ax = plt.subplots()
    plot_force_field(ax, (x, y, fx, fy), BOX, (5.0, 2.0))
    plt.close(fig)


def test_force_field_leaves_out_the_points_outside_the_outer_walls():
    from robotlib.world import load_world

    utrap = load_world("utrap")  # its bounds leave a margin around the outer walls
    x, y, fx, fy = force_field(utrap, (8.5, 3.5), resolution=0.5)
    walls = np.asarray(utrap.segments)
    x0, x1 = walls[:, [0, 2]].min(), walls[:, [0, 2]].max()
    y0, y1 = walls[:, [1, 3]].min(), walls[:, [1, 3]].max()
    outside = (x < x0) | (x > x1) | (y < y0) | (y > y1)
    assert outside.sum() > 20  # the margin's points: a robot fits there
    assert np.isnan(fx[outside]).all() and np.isnan(fy[outside]).all()
    assert np.isfinite(fx[~outside]).sum() > 200  # the inside still has its arrows
