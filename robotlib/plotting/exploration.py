"""Exploration figures (Lab 7), each on a given ``ax``.

- `plot_frontiers`: a map's frontier regions, their centroids and targets;
- `plot_exploration`: a run's final map, the true walls, each robot's path;
- `plot_coverage`: explored fraction against simulated time, per run;
- `animate_exploration`: the team exploring, from a run's snapshots (an
  HTML player that works offline, `robotlib.plotting.world.animate`).

Draws data only; never computes robotics.
"""

from __future__ import annotations

import numpy as np

from .mapping import plot_logodds
from .style import legend_outside
from .world import animate, plot_robot, plot_world

__all__ = ["plot_frontiers", "plot_exploration", "plot_coverage", "animate_exploration"]

TEAM_COLORS = ("tab:red", "tab:orange", "tab:green", "tab:purple")
"""One colour per robot of a team."""


def plot_frontiers(ax, grid, frontiers, color: str = "tab:cyan"):
    """Draw `Frontier` regions on ``grid``'s cells: cells, centroid (x), target (o)."""
    res, (x0, y0) = grid.resolution, grid.origin
    for k, f in enumerate(frontiers):
        xy = np.column_stack(
            [x0 + (f.cells[:, 1] + 0.5) * res, y0 + (f.cells[:, 0] + 0.5) * res]
        )
        ax.plot(*xy.T, "s", ms=2, color=color, label="frontier" if k == 0 else None)
        ax.plot(*f.centroid, "x", color="k", ms=5)
        ax.plot(*f.target, "o", mfc="none", color="k", ms=5)
    return ax


def plot_exploration(ax, result, world=None, title=None):
    """Draw a run's map, the true walls (optional) and each robot's true path."""
    plot_logodds(ax, result.map)
    if world is not None:
        plot_world(ax, world, color="tab:blue", linewidth=0.5)
    for k, path in enumerate(result.paths):
        c = TEAM_COLORS[k % len(TEAM_COLORS)]
        ax.plot(path[:, 0], path[:, 1], "-", color=c, lw=1, label=f"robot {k + 1}")
        ax.plot(*path[0, :2], "o", color=c, ms=4)
    ax.set_title(
        title
        or f"{result.n_robots} robot(s): {result.explored:.0%} explored, "
        f"F1 {result.score.f1:.2f}"
    )
    legend_outside(ax)
    return ax


def plot_coverage(ax, results, labels=None):
    """Draw the explored fraction against simulated time of each run."""
    for k, r in enumerate(results):
        label = labels[k] if labels is not None else f"{r.n_robots} robot(s)"
        ax.plot(r.times, r.coverage, label=label)
    ax.axhline(0.9, color="grey", lw=0.5, ls="--")
    ax.set_xlabel("simulated time [s]")
    ax.set_ylabel("explored fraction")
    ax.set_ylim(0, 1.02)
    ax.legend(loc="lower right")
    return ax


def animate_exploration(fig, ax, result, world=None, **kw):
    """Animate a run's snapshots (``ExploreSettings.snapshot_period`` > 0).

    Each frame shows the shared map, the robots at their true poses and the
    targets they drive to. Options go to `robotlib.plotting.world.animate`.
    """
    if not result.snapshots:
        raise ValueError("the run kept no snapshots (set snapshot_period > 0)")
    grid = result.map.copy()

    def draw(k):
        ax.clear()
        t, logodds, poses, targets = result.snapshots[k]
        grid.logodds[:] = logodds
        plot_logodds(ax, grid)
        if world is not None:
            plot_world(ax, world, color="tab:blue", linewidth=0.5)
        for j, (pose, target) in enumerate(zip(poses, targets, strict=True)):
            c = TEAM_COLORS[j % len(TEAM_COLORS)]
            plot_robot(ax, pose, color=c)
            if np.all(np.isfinite(target)):
                ax.plot(*target, "*", color=c, ms=9)
        ax.set_title(f"t = {t:.0f} s")

    return animate(fig, draw, len(result.snapshots), **kw)
