"""The course's one figure style: sizes, colours, map axes, legends off the map.

Every lab figure follows it: figures as wide as the notebook (`WIDTH`),
colour-blind-safe colours (Okabe and Ito's palette, `PALETTE`, named by role
in `COLORS`), maps with equal axes labelled in metres, legends outside the
axes so that they never cover a wall. `use` applies `STYLE` to matplotlib
(``robotlib.notebook.setup`` calls it); the helpers work on any ``ax``.

Imports matplotlib only; nothing of robotlib.
"""

from __future__ import annotations

import matplotlib as mpl
from cycler import cycler

__all__ = [
    "PALETTE",
    "COLORS",
    "WIDTH",
    "DPI",
    "STYLE",
    "use",
    "map_figsize",
    "map_axes",
    "legend_outside",
]

PALETTE = (
    "#0072B2",  # blue
    "#E69F00",  # orange
    "#009E73",  # bluish green
    "#D55E00",  # vermillion
    "#CC79A7",  # reddish purple
    "#56B4E9",  # sky blue
    "#F0E442",  # yellow
    "#000000",  # black
)
"""Okabe and Ito's colour-blind-safe palette, in the order lines get them."""

COLORS = {
    "true": "#000000",
    "estimate": "#D55E00",
    "odometry": "#0072B2",
    "robot": "#0072B2",
    "sonar": "#E69F00",
    "particles": "#CC79A7",
    "walls": "#333333",
    "path": "#009E73",
    "goal": "#009E73",
    "reference": "#7F7F7F",
}
"""Colours by role, from `PALETTE` (plus grey for reference lines)."""

WIDTH = 9.0
"""Figure width, inches: at `DPI`, about the width of JupyterLab's output area
on a laptop screen (900 px), so figures are shown at their own size."""

DPI = 100
"""Figure resolution, dots per inch."""

STYLE = {
    "figure.figsize": (WIDTH, 3.6),
    "figure.dpi": DPI,
    "savefig.dpi": DPI,
    "figure.constrained_layout.use": True,
    "font.size": 10,
    "axes.titlesize": 10,
    "axes.labelsize": 10,
    "legend.fontsize": 9,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "axes.prop_cycle": cycler(color=list(PALETTE)),
    "legend.frameon": False,
    "image.cmap": "viridis",
}
"""Matplotlib settings of the course (`use` applies them)."""


def use() -> None:
    """Apply `STYLE` to matplotlib's settings (``rcParams``)."""
    mpl.rcParams.update(STYLE)


def map_figsize(
    bounds, ncols: int = 1, width: float = WIDTH, min_height=1.8, max_height=6.0
):
    """Return a figure size whose ``ncols`` equal-axes maps fill the width.

    Parameters
    ----------
    bounds : array_like
        ``(xmin, ymin, xmax, ymax)`` of the map, m (a `World`'s ``bounds``).
    ncols : int
        Maps side by side.
    width : float
        Figure width, inches.
    min_height, max_height : float
        Limits of the height, inches (a 29 m by 3 m corridor still gets room
        for its labels; a square map does not grow past the screen).

    Returns
    -------
    tuple of float
        ``(width, height)``, inches.
    """
    xmin, ymin, xmax, ymax = (float(v) for v in bounds)
    aspect = (ymax - ymin) / max(xmax - xmin, 1e-9)
    height = width / max(int(ncols), 1) * aspect + 0.8  # + labels and title
    return (float(width), float(min(max(height, min_height), max_height)))


def map_axes(ax) -> None:
    """Give ``ax`` a map's axes: equal scales, x and y labelled in metres."""
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")


def legend_outside(ax, where: str = "auto", **kw):
    """Draw ``ax``'s legend outside the axes, where it covers no data.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes with labelled artists.
    where : {"auto", "right", "top"}
        ``"right"``: beside the axes; ``"top"``: in a row above them (under
        the title); ``"auto"``: above wide axes (a corridor map), beside the
        others.
    **kw
        Passed to ``ax.legend``.

    Returns
    -------
    matplotlib.legend.Legend or None
        None when nothing is labelled.
    """
    handles, labels = ax.get_legend_handles_labels()
    if not handles:
        return None
    if where == "auto":
        x0, x1 = ax.get_xlim()
        y0, y1 = ax.get_ylim()
        wide = ax.get_aspect() == 1.0 and abs(x1 - x0) > 2.5 * abs(y1 - y0)
        where = "top" if wide else "right"
    if where == "top":
        opts = {
            "loc": "lower left",
            "bbox_to_anchor": (0.0, 1.0),
            "ncols": min(len(handles), 4),
            "borderaxespad": 0.2,
        }
    elif where == "right":
        opts = {"loc": "upper left", "bbox_to_anchor": (1.01, 1.0), "borderaxespad": 0}
    else:
        raise ValueError(f"where must be 'auto', 'right' or 'top', got {where!r}")
    opts.update(kw)
    return ax.legend(handles, labels, **opts)
