"""A team of robots exploring together: start poses known to all, one map.

`team_starts` puts 1-4 robots side by side and behind one another around
``World.start`` (their poses relative to each other known, as when a team
is unloaded in one place); `explore_team` runs them in one simulator with
`robotlib.exploration.Exploration`: one shared map, the coordinated
frontier choice (a robot's utility is discounted near the frontiers its
teammates already chose and near where they stand), only the first robot
looking round before the start, a robot stopping for a teammate ahead and
re-planning around it when it waits too long. Imports the loop; never plots.
"""

from __future__ import annotations

import math

import numpy as np

from ..p3dx import ROBOT_RADIUS
from ..world import World
from .explore import Exploration
from .metrics import ExplorationResult
from .settings import ExploreSettings

__all__ = ["team_starts", "explore_team"]

_OFFSETS = [
    (0, 0),
    (1, 0),
    (-1, 0),
    (2, 0),
    (-2, 0),
    (3, 0),
    (0, 1),
    (0, -1),
    (1, 1),
    (1, -1),
]


def team_starts(world: World, n: int, spacing: float = 0.9) -> np.ndarray:
    """Start poses for ``n`` robots around ``world.start``, all facing its way.

    Offsets of ``spacing`` (m) along and across the start heading are tried in
    a fixed order (in a file ahead and behind, then beside); the first ``n``
    where a robot is clear of the walls by 0.2 m and of the others are kept.

    Returns
    -------
    numpy.ndarray, shape (n, 3)

    Raises
    ------
    ValueError
        If ``n`` is not in 1-4, or fewer than ``n`` places are free.
    """
    if not 1 <= n <= 4:
        raise ValueError(f"a team has 1 to 4 robots, got {n}")
    x, y, th = world.start
    c, s = math.cos(th), math.sin(th)
    out: list[tuple] = []
    for a, b in _OFFSETS:
        p = (x + spacing * (a * c - b * s), y + spacing * (a * s + b * c), th)
        if not world.is_free(np.array(p[:2]), ROBOT_RADIUS + 0.2):
            continue
        if all(
            math.hypot(p[0] - q[0], p[1] - q[1]) > 2 * ROBOT_RADIUS + 0.1 for q in out
        ):
            out.append(p)
        if len(out) == n:
            return np.array(out)
    raise ValueError(f"only {len(out)} free start places near {world.start}")


def explore_team(
    world: World,
    n_robots: int = 2,
    settings: ExploreSettings | None = None,
    rng: np.random.Generator | int | None = None,
    starts=None,
    frontiers=None,
    chooser=None,
) -> ExplorationResult:
    """Explore ``world`` with a team of ``n_robots`` sharing one map.

    Parameters
    ----------
    world : World
        The truth.
    n_robots : int
        Team size, 1-4.
    settings : ExploreSettings, optional
        The knobs (``strategy`` ``"coordinated"`` by default).
    rng : numpy.random.Generator, int or None
        Seeds the simulator and SLAM.
    starts : array_like, shape (n_robots, 3), optional
        Start poses (default `team_starts`).
    frontiers, chooser : callable, optional
        Replace the library's `frontier_cells` and `choose` (see
        `Exploration`).

    Returns
    -------
    ExplorationResult
    """
    starts = team_starts(world, n_robots) if starts is None else np.asarray(starts)
    if len(starts) != n_robots:
        raise ValueError(f"need {n_robots} start poses, got {len(starts)}")
    return Exploration(world, starts, settings, rng, frontiers, chooser).run()
