"""Drawing for navigation: configuration spaces, searches, trees, runs.

Every function draws on the ``ax`` it is given, from plain data: a
`robotlib.planning.CSpace` (inflated grid, cost map), a search's expansion
order (`Plan.order`, or any ``(E, 2)`` cells), an RRT `Tree`, a
`Navigation` record. `animate_search` animates a search's flood. Nothing
here plans.
"""

from __future__ import annotations

import numpy as np
from matplotlib.collections import LineCollection

from ..world import World
from .world import _label_axes, animate, plot_world

__all__ = [
    "plot_cspace",
    "plot_expansion",
    "animate_search",
    "plot_path",
    "plot_tree",
    "plot_navigation",
]


def plot_cspace(ax, cs, cost: bool = True, world: World | None = None):
    """Show the blocked cells (dark) and, if ``cost``, the cost map (colour)."""
    if cost and cs.cost.max() > 0:
        c = np.ma.masked_where(cs.blocked | (cs.cost == 0), cs.cost)
        ax.imshow(
            c, origin="lower", extent=cs.extent, cmap="Oranges", alpha=0.7,
            interpolation="nearest",
        )  # fmt: skip
    ax.imshow(
        np.ma.masked_where(~cs.blocked, cs.blocked.astype(float)),
        origin="lower", extent=cs.extent, cmap="Greys", vmin=0, vmax=1.5,
        interpolation="nearest",
    )  # fmt: skip
    if world is not None:
        plot_world(ax, world, linewidth=1.0)
    ax.set_aspect("equal")
    _label_axes(ax)
    return ax


def plot_expansion(ax, cs, order, upto: int | None = None, cmap: str = "viridis"):
    """Colour the cells ``order`` (E, 2) by when they were expanded."""
    order = np.asarray(order, dtype=np.int64).reshape(-1, 2)
    upto = len(order) if upto is None else min(int(upto), len(order))
    img = np.full(cs.shape, np.nan)
    if upto:
        img[order[:upto, 0], order[:upto, 1]] = np.arange(upto)
    ax.imshow(
        np.ma.masked_invalid(img), origin="lower", extent=cs.extent, cmap=cmap,
        vmin=0, vmax=max(len(order), 1), interpolation="nearest",
    )  # fmt: skip
    _label_axes(ax)
    return ax


def plot_path(ax, path, style: str = "-", label=None, **kw):
    """Draw a path (K, 2), m."""
    p = np.asarray(path, dtype=float).reshape(-1, 2)
    return ax.plot(p[:, 0], p[:, 1], style, label=label, **kw)


def animate_search(fig, ax, cs, plan, frames: int = 40, world: World | None = None):
    """Animate the expansion order of ``plan`` over ``cs``, then its path.

    ``plan`` is a `Plan` planned with ``record=True``; returns what
    `robotlib.plotting.animate` does.
    """
    n = len(plan.order)
    stops = np.unique(np.linspace(0, n, frames).round().astype(int))

    def draw(k):
        ax.clear()
        plot_cspace(ax, cs, cost=False, world=world)
        plot_expansion(ax, cs, plan.order, upto=k)
        if k == n and plan.found:
            plot_path(ax, plan.path, "r-", lw=2)
        ax.set_title(f"{k} of {n} expanded")

    return animate(fig, draw, list(stops))


def plot_tree(ax, tree, color: str = "tab:blue", path_color: str = "r"):
    """Draw an RRT `Tree`'s edges and its path."""
    nodes, parents = tree.nodes, tree.parents
    kids = np.flatnonzero(parents >= 0)
    segs = np.stack([nodes[parents[kids]], nodes[kids]], axis=1)
    ax.add_collection(LineCollection(segs, colors=color, linewidths=0.5, alpha=0.6))
    ax.plot(nodes[0, 0], nodes[0, 1], "go", ms=6)
    if tree.found:
        plot_path(ax, tree.path, "-", color=path_color, lw=2)
    ax.set_aspect("equal")
    _label_axes(ax)
    return ax


def plot_navigation(ax, world: World, nav, map_world: World | None = None):
    """Draw a `Navigation` run.

    The world, the plans, the true and estimated paths, the marked echoes
    and the goal.
    """
    plot_world(ax, world, color="0.5", linewidth=1.0)
    if map_world is not None:
        plot_world(ax, map_world, linewidth=1.5)
    for k, path in enumerate(nav.plans):
        label = "plans" if k == 0 else None
        plot_path(ax, path, ":", color="tab:green", lw=1, label=label)
    if len(nav.hits):
        ax.plot(*nav.hits.T, "x", color="tab:orange", ms=3, label="marked echoes")
    if np.isfinite(nav.truth).all():
        ax.plot(*nav.truth[:, :2].T, "k-", lw=1.5, label="true path")
    ax.plot(*nav.estimate[:, :2].T, "--", color="tab:red", lw=1, label="MCL estimate")
    ax.plot(*nav.goal, "r*", ms=14, label="goal")
    ax.set_aspect("equal")
    ax.set_title(f"{nav.outcome} in {nav.duration:.0f} s")
    _label_axes(ax)
    return ax
