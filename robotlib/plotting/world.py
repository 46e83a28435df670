"""Matplotlib drawing for robotlib: every function draws on the ``ax`` it is given.

Nothing here computes robotics: the functions draw worlds, robots, sonar
cones, trajectories, particles and grids from plain arrays (metres and
radians), and `animate` turns a per-frame drawing function into an animation
that shows in JupyterLab and runs headless.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.animation import FuncAnimation
from matplotlib.collections import LineCollection, PatchCollection
from matplotlib.patches import Polygon, Wedge

from ..p3dx import (
    ROBOT_LENGTH_FRONT,
    ROBOT_LENGTH_REAR,
    ROBOT_WIDTH,
    SONAR_CONE,
    SONAR_MAX_RANGE,
    SONAR_POSES,
)
from ..world import Grid, World
from .style import COLORS, map_axes

__all__ = [
    "plot_world",
    "plot_robot",
    "plot_sonar",
    "plot_trajectory",
    "plot_particles",
    "plot_grid",
    "animate",
]


_label_axes = map_axes


def plot_world(
    ax, world: World, color: str = COLORS["walls"], linewidth: float = 1.5, **kw
):
    """Draw a world's walls (and point obstacles), set equal axes in metres.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Where to draw.
    world : World
        The world.
    color : str
        Wall colour.
    linewidth : float
        Wall width, points.
    **kw
        Passed to `matplotlib.collections.LineCollection`.

    Returns
    -------
    matplotlib.collections.LineCollection
        The walls.
    """
    walls = LineCollection(
        world.segments.reshape(-1, 2, 2), colors=color, linewidths=linewidth, **kw
    )
    ax.add_collection(walls)
    if len(world.points):
        ax.plot(world.points[:, 0], world.points[:, 1], ",", color=color)
    xmin, ymin, xmax, ymax = world.bounds
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    _label_axes(ax)
    return walls


def robot_outline(pose) -> np.ndarray:
    """Return the Pioneer 3-DX's rectangular outline at ``pose``, (4, 2), m."""
    x, y, th = (float(v) for v in pose)
    hw = ROBOT_WIDTH / 2
    body = np.array(
        [
            [ROBOT_LENGTH_FRONT, hw],
            [-ROBOT_LENGTH_REAR, hw],
            [-ROBOT_LENGTH_REAR, -hw],
            [ROBOT_LENGTH_FRONT, -hw],
        ]
    )
    c, s = math.cos(th), math.sin(th)
    return body @ np.array([[c, s], [-s, c]]) + [x, y]


def plot_robot(ax, pose, color: str = COLORS["robot"], alpha: float = 0.6, label=None):
    """Draw the robot's footprint at ``pose`` with a line showing its heading.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Where to draw.
    pose : array_like, shape (3,)
        ``(x, y, theta)``, m and rad.
    color : str
        Fill colour.
    alpha : float
        Fill opacity.
    label : str, optional
        Legend label.

    Returns
    -------
    matplotlib.patches.Polygon
        The footprint.
    """
    x, y, th = (float(v) for v in pose)
    patch = Polygon(robot_outline(pose), closed=True, fc=color, ec="k", alpha=alpha)
    patch.set_label(label)
    ax.add_patch(patch)
    ax.plot([x, x + 0.35 * math.cos(th)], [y, y + 0.35 * math.sin(th)], "k-", lw=1.5)
    return patch


def plot_sonar(
    ax,
    pose,
    ranges,
    sensors=SONAR_POSES,
    cone: float = SONAR_CONE,
    max_range: float = SONAR_MAX_RANGE,
    color: str = COLORS["sonar"],
):
    """Draw each sonar's cone out to its reading.

    Readings at ``max_range`` (no echo) are drawn faint.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Where to draw.
    pose : array_like, shape (3,)
        Robot pose, m and rad.
    ranges : array_like, shape (S,)
        Readings, m.
    sensors : array_like, shape (S, 3)
        Sonar poses in the robot frame (default: the Pioneer's front ring).
    cone : float
        Full cone angle, rad.
    max_range : float
        The no-echo range, m.
    color : str
        Cone colour.

    Returns
    -------
    matplotlib.collections.PatchCollection
        The cones.
    """
    x, y, th = (float(v) for v in pose)
    c, s = math.cos(th), math.sin(th)
    wedges, alphas = [], []
    for (sx, sy, sth), r in zip(np.asarray(sensors), np.asarray(ranges), strict=True):
        cx, cy = x + c * sx - s * sy, y + s * sx + c * sy
        mid = math.degrees(th + sth)
        half = math.degrees(cone) / 2
        wedges.append(Wedge((cx, cy), float(r), mid - half, mid + half))
        alphas.append(0.08 if r >= max_range else 0.35)
    cones = PatchCollection(wedges, fc=color, ec=color, lw=0.5)
    cones.set_alpha(None)
    rgba = np.array([plt.matplotlib.colors.to_rgba(color, a) for a in alphas])
    cones.set_facecolor(rgba)
    ax.add_collection(cones)
    return cones


def plot_trajectory(ax, poses, label=None, **kw):
    """Draw a trajectory through the ``(x, y)`` of ``poses`` (shape (T, 2+)), m."""
    p = np.asarray(poses, dtype=float)
    (line,) = ax.plot(p[:, 0], p[:, 1], label=label, **kw)
    return line


def plot_particles(
    ax, particles, weights=None, color=COLORS["particles"], arrows=None, **kw
):
    """Draw a particle cloud.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Where to draw.
    particles : array_like, shape (N, 3)
        Particle poses, m and rad.
    weights : array_like, shape (N,), optional
        Weights; marker areas scale with them.
    color : str
        Marker colour.
    arrows : bool, optional
        Draw headings as arrows; default: when there are at most 500
        particles.
    **kw
        Passed to ``ax.scatter``.

    Returns
    -------
    matplotlib.collections.PathCollection
        The markers.
    """
    p = np.asarray(particles, dtype=float)
    sizes = 4.0
    if weights is not None:
        w = np.asarray(weights, dtype=float)
        sizes = 2.0 + 30.0 * w / max(w.max(), 1e-300)
    dots = ax.scatter(p[:, 0], p[:, 1], s=sizes, c=color, lw=0, **kw)
    if arrows if arrows is not None else len(p) <= 500:
        ax.quiver(
            p[:, 0],
            p[:, 1],
            np.cos(p[:, 2]),
            np.sin(p[:, 2]),
            color=color,
            angles="xy",
            scale_units="xy",
            scale=8.0,
            width=0.002,
        )
    return dots


def plot_grid(ax, grid: Grid, cmap: str = "gray_r", **kw):
    """Show a `Grid` (occupancy, distance field, map) in world coordinates."""
    image = ax.imshow(
        np.asarray(grid.data, dtype=float),
        origin="lower",
        extent=grid.extent,
        cmap=cmap,
        interpolation="nearest",
        **kw,
    )
    _label_axes(ax)
    return image


def animate(
    fig,
    draw: Callable[[int], object],
    frames: int | Sequence,
    interval: float = 100.0,
    max_frames: int = 150,
    html: bool = True,
    progress: Callable | None = None,
):
    """Animate a figure by calling ``draw(frame)`` for each frame.

    Shows in JupyterLab and runs headless: by default it returns the
    animation as self-contained HTML (``to_jshtml``) and closes ``fig``, so
    the notebook shows only the player.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure ``draw`` updates.
    draw : callable
        ``draw(frame)`` redraws the figure for one frame (e.g. clears the axes
        and plots the state at that step).
    frames : int or sequence
        Number of frames, or the frame values to pass to ``draw``.
    interval : float
        Delay between frames, ms.
    max_frames : int
        At most this many frames are rendered; longer sequences are thinned
        evenly (first and last kept).
    html : bool
        Return ``IPython.display.HTML``; False returns the
        `matplotlib.animation.FuncAnimation`.
    progress : callable, optional
        A progress bar to show while the frames are drawn for the HTML,
        made as ``progress(total=n, desc=...)`` (``robotlib.notebook.progress``
        in a notebook); it counts the frames.

    Returns
    -------
    IPython.display.HTML or matplotlib.animation.FuncAnimation
    """
    values = list(range(frames)) if isinstance(frames, int) else list(frames)
    if len(values) > max_frames:
        keep = np.unique(
            np.linspace(0, len(values) - 1, max_frames).round().astype(int)
        )
        values = [values[i] for i in keep]
    bar = None
    if html and progress is not None:
        bar = progress(total=len(values), desc="drawing the frames")

    def frame(value):
        if bar is not None and bar.n < bar.total:
            bar.update()
        return draw(value)

    anim = FuncAnimation(fig, frame, frames=values, interval=interval, blit=False)
    if not html:
        return anim
    from IPython.display import HTML

    draw(values[0])  # the layout, once, with what a frame draws (titles, labels):
    fig.canvas.draw()  # every frame keeps it (and does not jump)
    fig.set_layout_engine("none")
    fig.canvas.draw_idle = _no_redraw  # saving a frame draws it: once, not twice
    page = HTML(offline_player(anim.to_jshtml(default_mode="once")))
    plt.close(fig)
    if bar is not None:
        bar.update(bar.total - bar.n)  # (saving also draws a frame first)
        bar.close()
    return page


def _no_redraw(*args, **kwargs) -> None:
    return None


_GLYPHS = {  # shapes every font with Geometric Shapes has (DejaVu, Liberation...)
    "fa-minus": "&minus;",
    "fa-fast-backward": "|&#x25C0;&#x25C0;",
    "fa-step-backward": "|&#x25C0;",
    "fa-play fa-flip-horizontal": "&#x25C0;",
    "fa-pause": "&#x25AE;&#x25AE;",
    "fa-play": "&#x25B6;",
    "fa-step-forward": "&#x25B6;|",
    "fa-fast-forward": "&#x25B6;&#x25B6;|",
    "fa-plus": "+",
}
_START = (  # the ";" ends the last frame's line, which has none (else it is called)
    ";(function start(tries) {\n"
    "        /* JupyterLab may insert the output after this script ran */\n"
    "        if (!document.getElementById(img_id)) {\n"
    "            if (tries < 2400) setTimeout(start, 250, tries + 1);\n"
    "            return;\n"
    "        }\n"
    "        \\1\n"
    "    })(0);"
)


def offline_player(page: str) -> str:
    """Make matplotlib's jshtml player work offline and show before its script.

    The player draws its first frame from a script that looks its image up
    in the page, and its buttons' icons come from a stylesheet on a CDN.
    JupyterLab can run an output's script before the output is in the page
    (a cell out of view during Run All), which left the image blank until the
    cell was clicked; offline, the icons were blank. Here the first frame is
    the image's own source, the script waits until the image is in the page,
    and the buttons show plain characters (no stylesheet is fetched).

    Parameters
    ----------
    page : str
        ``FuncAnimation.to_jshtml()``'s output.

    Returns
    -------
    str
        The same player, self-contained.
    """
    import re

    page = re.sub(r"<link rel=\"stylesheet\"\s+href=\"https?://[^\"]*\">\s*", "", page)
    page = re.sub(
        r'<i class="fa ([^"]*)"></i>',
        lambda m: _GLYPHS.get(m.group(1), m.group(1)),
        page,
    )
    first = re.search(r'frames\[0\] = "([^"]*)"', page)
    if first is not None:
        src = first.group(1).replace("\\\n", "")
        page = re.sub(r'(<img id="_anim_img\w+")', rf'\1 src="{src}"', page, count=1)
    return re.sub(
        r"setTimeout\(function\(\) \{\s*(.*?)\s*\}, 0\);",
        _START,
        page,
        count=1,
        flags=re.S,
    )
