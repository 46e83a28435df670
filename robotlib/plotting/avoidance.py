"""Drawing obstacle avoidance: episodes, VFH's polar histogram, the potential field.

Every function draws plain data (an `robotlib.avoidance.Episode`, a
histogram array, a force field from `robotlib.avoidance.force_field`) on the
``ax`` it is given; `animate_episode` plays an episode back. Nothing here
steers a robot.
"""

from __future__ import annotations

import numpy as np

from ..avoidance.base import sonar_endpoints
from .style import legend_outside
from .world import animate, plot_robot, plot_world

__all__ = [
    "plot_episode",
    "plot_clearance",
    "plot_polar_histogram",
    "plot_force_field",
    "animate_episode",
]


def _world_echoes(sonar, pose) -> np.ndarray:
    """Echo points (K, 2) of one scan at ``pose``, world frame."""
    pts, echo = sonar_endpoints(sonar)
    c, s = np.cos(pose[2]), np.sin(pose[2])
    p = pts[echo]
    return np.column_stack(
        [pose[0] + c * p[:, 0] - s * p[:, 1], pose[1] + s * p[:, 0] + c * p[:, 1]]
    )


def plot_episode(ax, episode, world=None, echoes: bool = True, label=None, at=-1):
    """Draw an episode: the world, the path, the sonar echoes, start and goal.

    The true path is drawn where the episode has one (else the odometry);
    echoes are placed on each sonar's axis from the same poses. The robot
    is drawn at cycle ``at`` (default: the last).
    """
    if world is not None:
        plot_world(ax, world)
    poses = episode.truth if episode.truth is not None else episode.odometry
    if echoes:
        pts = np.concatenate(
            [_world_echoes(s, p) for s, p in zip(episode.sonar, poses, strict=True)]
        )
        ax.plot(*pts.T, ".", color="tab:orange", ms=1.5, alpha=0.4, label="echoes")
    ax.plot(*poses[:, :2].T, "-", color="tab:blue", lw=1.5, label=label or "path")
    ax.plot(*poses[0, :2], "o", color="tab:green", label="start")
    if episode.goal is not None:
        ax.plot(*episode.goal, "*", color="tab:red", ms=12, label="goal")
    plot_robot(ax, poses[at])
    outcome = episode.outcome.replace("_", " ")  # "local minimum"
    ax.set_title(f"{episode.controller}: {outcome}, {episode.duration:.1f} s")
    ax.set_aspect("equal")
    return ax


def plot_clearance(ax, episode):
    """Draw the true clearance (or the smallest sonar reading) over time."""
    if episode.clearance is not None:
        ax.plot(episode.time, episode.clearance, label="clearance (true)")
    ax.plot(episode.time, episode.sonar.min(axis=1), lw=0.8, label="nearest sonar")
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set(xlabel="time [s]", ylabel="distance [m]")
    ax.legend(loc="upper right")
    return ax


def plot_polar_histogram(ax, hist, threshold=None, steer=None, target=None):
    """Draw a polar histogram (robot frame, 0 = ahead) on a polar ``ax``.

    Sectors at or above ``threshold`` are drawn red (blocked), others grey;
    ``steer`` (the chosen direction) and ``target`` (the goal's) as lines.
    """
    h = np.asarray(hist, dtype=float)
    n = len(h)
    centres = -np.pi + (np.arange(n) + 0.5) * 2 * np.pi / n
    colors = "tab:gray"
    if threshold is not None:
        colors = np.where(h >= threshold, "tab:red", "tab:gray")
    ax.bar(centres, h, width=2 * np.pi / n, color=colors, alpha=0.8)
    top = max(h.max(), threshold or 0.0, 1.0)
    if threshold is not None:
        t = np.linspace(-np.pi, np.pi, 200)
        ax.plot(t, np.full_like(t, threshold), "k--", lw=1, label="threshold")
    if target is not None:
        ax.plot([target, target], [0, top], color="tab:green", lw=2, label="goal")
    if steer is not None and np.isfinite(steer):
        ax.plot([steer, steer], [0, top], color="tab:blue", lw=2, label="steer")
    if hasattr(ax, "set_theta_zero_location"):
        ax.set_theta_zero_location("N")
    legend_outside(ax, "right", fontsize="small")  # clear of the angle labels
    return ax


def plot_force_field(ax, field, world=None, goal=None):
    """Draw a force field ``(x, y, fx, fy)`` as unit arrows coloured by strength."""
    x, y, fx, fy = field
    mag = np.hypot(fx, fy)
    with np.errstate(invalid="ignore", divide="ignore"):
        q = ax.quiver(x, y, fx / mag, fy / mag, np.log10(mag), cmap="viridis",
                      scale=30, width=0.003)  # fmt: skip
    if world is not None:
        plot_world(ax, world)
    if goal is not None:
        ax.plot(*goal, "*", color="tab:red", ms=12)
    ax.set_aspect("equal")
    return q


def animate_episode(
    episode, world=None, every: int = 5, max_frames: int = 40, html: bool = True
):
    """Play an episode back: the robot, its path so far and its echoes.

    Parameters
    ----------
    episode : robotlib.avoidance.Episode
    world : robotlib.world.World, optional
    every : int
        Show every ``every``-th cycle.
    max_frames : int
        At most this many frames (thinned evenly).
    html : bool
        Return HTML (for notebooks); False: the ``FuncAnimation``.
    """
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 5))
    poses = episode.truth if episode.truth is not None else episode.odometry

    def draw(k):
        ax.clear()
        if world is not None:
            plot_world(ax, world)
        ax.plot(*poses[: k + 1, :2].T, "-", color="tab:blue")
        pts = _world_echoes(episode.sonar[k], poses[k])
        for p in pts:
            ax.plot(
                [poses[k, 0], p[0]], [poses[k, 1], p[1]], color="tab:orange", lw=0.7
            )
        if episode.goal is not None:
            ax.plot(*episode.goal, "*", color="tab:red", ms=12)
        plot_robot(ax, poses[k])
        ax.set_title(f"t = {episode.time[k]:.1f} s")
        ax.set_aspect("equal")

    frames = range(0, len(poses), max(1, every))
    return animate(fig, draw, frames, max_frames=max_frames, html=html)
