"""The paper's Figs. 2-4 from a localization run's `History`, each on a given ``ax``.

- `plot_trajectories` (Fig. 2): true and estimated trajectories on the map;
- `plot_error` (Fig. 3): position error per step, with the tracking mean;
- `plot_particle_count` (Fig. 4): particles per step;
- `plot_mcl_run`: the three in one figure (Fig. 2 coloured by step);
- `plot_particle_snapshots`: the particle cloud at a few steps.

Imports the localization's `History` (plain data) and the course style;
never runs a filter.
"""

from __future__ import annotations

import numpy as np

from ..localization.history import History, localized_step
from .style import COLORS, legend_outside, map_axes

__all__ = [
    "plot_trajectories",
    "plot_error",
    "plot_particle_count",
    "plot_mcl_run",
    "plot_particle_snapshots",
]


def plot_trajectories(ax, history: History, world=None, **kw):
    """Draw the true and estimated trajectories (the paper's Fig. 2).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Where to draw.
    history : History
        A run.
    world : World, optional
        Drawn underneath with `robotlib.plotting.plot_world`.
    **kw
        Passed to the estimate's ``ax.plot``.

    Returns
    -------
    matplotlib.axes.Axes
    """
    a = history.arrays()
    if world is not None:
        from .world import plot_world

        plot_world(ax, world)
    t, e = a["true_pose"], a["estimate"]
    ax.plot(t[:, 0], t[:, 1], "-", color=COLORS["true"], label="true")
    style = {"color": COLORS["estimate"], "ms": 3, **kw}
    ax.plot(e[:, 0], e[:, 1], "o--", label="estimate", **style)
    map_axes(ax)
    legend_outside(ax)
    return ax


def plot_error(ax, history: History, tolerance: float = 0.5):
    """Draw the position error per step and its mean once localized (Fig. 3).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Where to draw.
    history : History
        A run.
    tolerance : float
        "Localized" threshold, m (drawn as a dotted line).

    Returns
    -------
    matplotlib.axes.Axes
    """
    a = history.arrays()
    ax.plot(a["step"], a["error"], "o-", ms=3, color=COLORS["estimate"], label="error")
    ax.axhline(tolerance, ls=":", color=COLORS["reference"], label=f"{tolerance} m")
    k = localized_step(a["error"], tolerance)
    if k is not None:
        mean = float(np.mean(a["error"][k - 1 :]))
        green = COLORS["path"]
        ax.hlines(mean, k, a["step"][-1], color=green, label=f"mean {mean:.2f} m")
        ax.axvline(k, ls="--", color=green, alpha=0.5)
    ax.set_xlabel("step")
    ax.set_ylabel("position error [m]")
    legend_outside(ax, "top")
    return ax


def plot_particle_count(ax, history: History):
    """Draw the number of particles per step (the paper's Fig. 4).

    Returns
    -------
    matplotlib.axes.Axes
    """
    a = history.arrays()
    ax.step(a["step"], a["n_particles"], where="mid")
    ax.set_xlabel("step")
    ax.set_ylabel("particles")
    ax.set_ylim(0, None)
    return ax


def plot_mcl_run(
    history: History,
    world,
    fig=None,
    tolerance: float = 0.5,
    title: str = "",
    kidnap: int = 0,
):
    """Draw the paper's Figs. 2-4 for one run: trajectories in time, error, particles.

    Fig. 2 shows time: the estimate's points are coloured by step (colour
    bar), and the true path is marked every 10 steps. The map spans the top
    row, or, for a world more than 1.2 times as tall as it is wide (a
    building), the left column beside the other two.

    Parameters
    ----------
    history : History
        The run.
    world : World
        Its map.
    fig : matplotlib.figure.Figure, optional
        Drawn into (cleared first); a new figure (pyplot's) by default.
    tolerance : float
        The "localized" error bound drawn on the error plot, m.
    title : str
        A line above the figure (the settings of the run, say).
    kidnap : int
        The log step the robot was carried before (``true_pose[kidnap]`` is
        in the new place; `robotlib.experiments.drive_tour`'s ``kidnap``), 0
        for none: the true path breaks there instead of joining the two
        places, and a line on the error plot marks it.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from .style import WIDTH
    from .world import plot_world

    if fig is None:
        import matplotlib.pyplot as plt

        fig = plt.figure(figsize=(WIDTH, 5.4))
    fig.clear()
    w, h = world.size
    tall = h > 1.2 * w  # a building: the map beside the plots, not above them
    if tall:
        grid = fig.add_gridspec(
            2, 2, width_ratios=(1, 1.6), wspace=0.45, hspace=0.5, top=0.8
        )
        ax_map = fig.add_subplot(grid[:, 0])
        ax_err = fig.add_subplot(grid[0, 1])
        ax_n = fig.add_subplot(grid[1, 1])
    else:
        grid = fig.add_gridspec(2, 2, height_ratios=(1.1, 1))
        ax_map = fig.add_subplot(grid[0, :])
        ax_err = fig.add_subplot(grid[1, 0])
        ax_n = fig.add_subplot(grid[1, 1])
    a = history.arrays()
    steps, truth, est = a["step"], a["true_pose"], a["estimate"]
    plot_world(ax_map, world, color=COLORS["walls"], linewidth=1)
    cut = [kidnap] if 0 < kidnap < len(truth) else []
    for i, piece in enumerate(np.split(truth, cut)):
        label = "true" if i == 0 else None
        ax_map.plot(piece[:, 0], piece[:, 1], "-", color=COLORS["true"], label=label)
    marks = steps[(steps % 10 == 0) | (steps == 1)]
    for k in marks:
        x, y = truth[k - 1, :2]
        ax_map.annotate(
            str(k), (x, y), xytext=(0, 4), textcoords="offset points",
            fontsize=7, ha="center", color=COLORS["true"],
        )  # fmt: skip
    dots = ax_map.scatter(
        est[:, 0], est[:, 1], c=steps, cmap="viridis", s=12, zorder=3,
        vmin=1, vmax=max(int(steps[-1]) if len(steps) else 1, 2),
        label="estimate (colour: step)",
    )  # fmt: skip
    fig.colorbar(dots, ax=ax_map, label="step", pad=0.01, fraction=0.03)
    if tall:
        legend_outside(ax_map, "top", ncols=1)
        ax_map.set_title("trajectories (Fig. 2)", loc="left", pad=38)
    else:
        legend_outside(ax_map, "top")
        ax_map.set_title("true and estimated trajectory (Fig. 2)", loc="right")
    ax_err.plot(steps, a["error"], color=COLORS["estimate"])
    ax_err.axhline(tolerance, color=COLORS["reference"], ls=":", lw=1)
    for k in cut:  # between the last step in the old place and the first in the new
        ax_err.axvline(k + 0.5, color=COLORS["reference"], lw=0.8)
        ax_err.annotate(
            "kidnapped", (k + 0.5, 1), xycoords=("data", "axes fraction"),
            xytext=(-3, -3), textcoords="offset points", ha="right", va="top",
            fontsize=7,
        )  # fmt: skip
    ax_err.set_xlabel("step")
    ax_err.set_ylabel("position error [m]")
    loc = history.localized_step(tolerance)
    ax_err.set_title(f"error per step (Fig. 3); localized from {loc or '-'}")
    ax_n.plot(steps, a["n_particles"], color=COLORS["odometry"])
    if tall:
        ax_err.set_xlabel("")
    ax_n.set_xlabel("step")
    ax_n.set_ylabel("particles")
    ax_n.set_ylim(0, None)
    ax_n.set_title("particles per step (Fig. 4)")
    if title:
        fig.suptitle(title, fontsize=10, x=0.01, ha="left")
    return fig


def plot_particle_snapshots(
    fig, world, snapshots, title_fmt: str = "step {step}: {n} particles"
):
    """Draw the particle cloud at a few steps, two maps per row.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        Drawn into (cleared first).
    world : World
        The map.
    snapshots : dict
        Step (1-based) to a dict with ``particles`` (N, 3), ``weights``
        (N,), ``truth`` (3,) and ``estimate`` (3,), m and rad (what
        `robotlib.widgets.mcl.run_mcl` keeps with ``snapshot_steps``).
    title_fmt : str
        Each row's title; formatted with ``step`` and ``n`` (particles).

    Returns
    -------
    list of matplotlib.axes.Axes
    """
    from .world import plot_particles, plot_robot, plot_world

    fig.clear()
    steps = sorted(snapshots)
    ncols = 2 if len(steps) > 2 else 1
    nrows = -(-len(steps) // ncols)
    axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
    for ax in axes[len(steps) :]:
        ax.set_axis_off()
    for ax, step in zip(axes, steps, strict=False):
        snap = snapshots[step]
        plot_world(ax, world, linewidth=0.8)
        plot_particles(ax, snap["particles"], snap["weights"], arrows=False)
        t, e = snap["truth"], snap["estimate"]
        plot_robot(ax, t, color=COLORS["robot"], alpha=0.9)
        ring = {"mfc": "none", "mec": COLORS["robot"], "ms": 11, "mew": 1.5}
        ax.plot(t[0], t[1], "o", label="true pose", **ring)
        mark = {"color": COLORS["estimate"], "ms": 9, "mew": 2}
        ax.plot(e[0], e[1], "x", label="estimate", **mark)
        ax.set_title(title_fmt.format(step=step, n=len(snap["particles"])), loc="left")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside upper right", ncols=len(labels))
    return list(axes)
