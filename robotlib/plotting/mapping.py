"""Mapping and SLAM figures (Lab 5), each on a given ``ax``.

- `plot_logodds`: a log-odds grid (free light, occupied dark, unknown grey);
- `plot_map_vs_truth`: a map's occupied cells over the true walls;
- `plot_paths`: true, odometry and estimated trajectories (and particles');
- `plot_ekf`: EKF-SLAM's pose and landmarks with their 95 % ellipses;
- `animate_fastslam`: a FastSLAM run's best map and paths, step by step.

Draws data only; never computes robotics.
"""

from __future__ import annotations

import numpy as np

from .style import legend_outside
from .world import animate, plot_world

__all__ = [
    "plot_logodds",
    "plot_map_vs_truth",
    "plot_paths",
    "plot_ekf",
    "animate_fastslam",
]


def _extent(grid):
    ny, nx = grid.logodds.shape
    x0, y0 = grid.origin
    return (x0, x0 + nx * grid.resolution, y0, y0 + ny * grid.resolution)


def plot_logodds(ax, grid, limit: float = 4.0, **kw):
    """Draw an `OccupancyGrid`'s log-odds (clipped to +-``limit``)."""
    im = ax.imshow(
        np.clip(grid.logodds, -limit, limit), origin="lower", extent=_extent(grid),
        cmap="gray_r", vmin=-limit, vmax=limit, interpolation="nearest", **kw,
    )  # fmt: skip
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal")
    return im


def plot_map_vs_truth(ax, grid, world, threshold: float = 0.0, title=None):
    """Draw a map's occupied cells (red) over the world's true walls (black)."""
    occ = grid.logodds > threshold
    ax.imshow(
        np.ma.masked_where(~occ, occ), origin="lower", extent=_extent(grid),
        cmap="autumn", interpolation="nearest", alpha=0.8,
    )  # fmt: skip
    plot_world(ax, world, color="k", linewidth=0.8)
    if title:
        ax.set_title(title)
    ax.set_aspect("equal")
    return ax


def plot_paths(ax, truth=None, odometry=None, estimate=None, particles=None):
    """Draw trajectories (T, 3): truth, odometry, an estimate, particles' (N, T, 3)."""
    if particles is not None:
        for p in particles:
            ax.plot(p[:, 0], p[:, 1], "-", color="tab:orange", lw=0.5, alpha=0.4)
    for poses, style, label in (
        (truth, "k-", "true"), (odometry, "--", "odometry"), (estimate, "-", "SLAM"),
    ):  # fmt: skip
        if poses is not None:
            ax.plot(poses[:, 0], poses[:, 1], style, lw=1.2, label=label)
    ax.set_aspect("equal")
    ax.set(xlabel="x [m]", ylabel="y [m]")
    legend_outside(ax)
    return ax


def _ellipse(ax, mean, cov, color, k=2.4477):
    vals, vecs = np.linalg.eigh(np.asarray(cov)[:2, :2])
    t = np.linspace(0, 2 * np.pi, 40)
    pts = vecs @ (k * np.sqrt(np.maximum(vals, 0))[:, None] * [np.cos(t), np.sin(t)])
    ax.plot(mean[0] + pts[0], mean[1] + pts[1], "-", color=color, lw=0.8)


def plot_ekf(ax, mu, P, landmarks=None, world=None):
    """Draw EKF-SLAM's state: pose and landmarks with 95 % ellipses."""
    if world is not None:
        plot_world(ax, world, color="0.6", linewidth=0.8)
    if landmarks is not None:
        lm = np.asarray(landmarks)
        ax.plot(lm[:, 0], lm[:, 1], "k+", ms=5, label="true landmarks")
    _ellipse(ax, mu[:2], P[:2, :2], "tab:blue")
    ax.plot(mu[0], mu[1], "o", color="tab:blue", label="robot")
    for j in range((len(mu) - 3) // 2):
        s = slice(3 + 2 * j, 5 + 2 * j)
        _ellipse(ax, mu[s], P[s, s], "tab:red")
    est = mu[3:].reshape(-1, 2)
    ax.plot(est[:, 0], est[:, 1], ".", color="tab:red", label="estimates")
    ax.set_aspect("equal")
    ax.set(xlabel="x [m]", ylabel="y [m]")
    legend_outside(ax)
    return ax


def animate_fastslam(fig, ax, frames, world=None, **kw):
    """Animate ``frames`` (a list of ``(grid, path)`` snapshots of a run)."""

    def draw(k):
        ax.clear()
        grid, path = frames[k]
        plot_logodds(ax, grid)
        if world is not None:
            plot_world(ax, world, color="tab:blue", linewidth=0.5)
        ax.plot(path[:, 0], path[:, 1], "r-", lw=1)

    return animate(fig, draw, len(frames), **kw)
