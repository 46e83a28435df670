"""The exploration figures draw a short run, and the animation plays offline."""

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402

from robotlib import load_world  # noqa: E402
from robotlib.exploration import ExploreSettings, explore_team, find_frontiers  # noqa: E402
from robotlib.plotting.exploration import (  # noqa: E402
    animate_exploration,
    plot_coverage,
    plot_exploration,
    plot_frontiers,
)


@pytest.fixture(scope="module")
def run():
    w = load_world("office")
    s = ExploreSettings(max_time=12.0, snapshot_period=3.0)
    return w, explore_team(w, 2, s, rng=0)


def test_figures_draw_the_run(run):
    w, res = run
    fig, axes = plt.subplots(1, 3)
    plot_exploration(axes[0], res, w)
    assert len(axes[0].lines) >= 2 * res.n_robots  # a path and a start per robot
    plot_coverage(axes[1], [res])
    assert len(axes[1].lines) == 2  # the curve and the 90 % line
    frontiers = find_frontiers(res.map)
    assert frontiers  # 12 s is not enough to explore the office
    plot_frontiers(axes[2], res.map, frontiers)
    plt.close(fig)


def test_animation_is_a_self_contained_player(run):
    w, res = run
    assert len(res.snapshots) >= 4
    fig, ax = plt.subplots()
    page = animate_exploration(fig, ax, res, w)
    assert "<img" in page.data and "cdnjs" not in page.data
    empty = type(res)(**{**res.__dict__, "snapshots": []})
    with pytest.raises(ValueError, match="snapshot"):
        animate_exploration(*plt.subplots(), empty)
