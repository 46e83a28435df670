"""The paper's Figs. 2-4 from a localization run's `History`, each on a given ``ax``.

- `plot_trajectories` (Fig. 2): true and estimated trajectories on the map;
- `plot_error` (Fig. 3): position error per step, with the tracking mean;
- `plot_particle_count` (Fig. 4): particles per step.
"""

from __future__ import annotations

import numpy as np

from ..localization.history import History, localized_step

__all__ = ["plot_trajectories", "plot_error", "plot_particle_count"]


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
    ax.plot(t[:, 0], t[:, 1], "-", color="k", label="true")
    ax.plot(e[:, 0], e[:, 1], "o--", ms=3, color="tab:red", label="estimate", **kw)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_aspect("equal")
    ax.legend(loc="best")
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
    ax.plot(a["step"], a["error"], "o-", ms=3, label="error")
    ax.axhline(tolerance, ls=":", color="gray", label=f"{tolerance} m")
    k = localized_step(a["error"], tolerance)
    if k is not None:
        mean = float(np.mean(a["error"][k - 1 :]))
        ax.hlines(mean, k, a["step"][-1], color="tab:green", label=f"mean {mean:.2f} m")
        ax.axvline(k, ls="--", color="tab:green", alpha=0.5)
    ax.set_xlabel("step")
    ax.set_ylabel("position error (m)")
    ax.legend(loc="best")
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
