"""The avoidance worlds and their seeded start/goal pairs.

Each avoidance world (``clutter``, ``doorway``, ``utrap``, ``alcoves``) ships
with a sidecar ``worlds/NAME.pairs.json`` (written by
``worlds/make_worlds.py``) naming the regions that starts and goals are drawn
from and the clearance they keep from walls. `start_goal_pairs` draws pairs
from them: the same seed gives the same pairs, and every pair is reachable
(start and goal in one connected piece of the free space at the robot's
radius plus a margin).

Imports: robotlib.world only.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np

from .._random import as_rng
from ..p3dx import ROBOT_RADIUS
from ..world import WORLDS_DIR, World, load_world, wrap_angle

__all__ = ["AVOID_WORLDS", "StartGoal", "start_goal_pairs", "pair_regions"]

AVOID_WORLDS = ("clutter", "doorway", "utrap", "alcoves")
"""The shipped obstacle-avoidance worlds."""

_PASSAGE = 0.05
"""Margin beyond the robot radius for the reachability test, m."""


@dataclass(frozen=True)
class StartGoal:
    """One start pose and goal position.

    Attributes
    ----------
    start : tuple of float
        ``(x, y, theta)``, m and rad.
    goal : tuple of float
        ``(x, y)``, m.
    """

    start: tuple[float, float, float]
    goal: tuple[float, float]


def pair_regions(name: str) -> dict:
    """Return the sidecar of an avoidance world (regions in m, clearance)."""
    path = WORLDS_DIR / f"{name}.pairs.json"
    if not path.exists():
        raise FileNotFoundError(
            f"{path}: no start/goal regions for world {name!r}; "
            f"avoidance worlds: {', '.join(AVOID_WORLDS)}"
        )
    return json.loads(path.read_text(encoding="ascii"))


def start_goal_pairs(
    world: str | World,
    n: int = 20,
    seed: np.random.Generator | int | None = 0,
) -> list[StartGoal]:
    """Draw ``n`` seeded, reachable start/goal pairs in an avoidance world.

    Starts and goals are uniform over their regions (from the world's
    ``.pairs.json``) where the walls are at least ``clearance`` away; the
    start heading points at the goal within +-45 degrees.

    Parameters
    ----------
    world : str or World
        An avoidance world's name (or the World loaded from it).
    n : int
        Number of pairs.
    seed : numpy.random.Generator, int or None
        Randomness; the same seed gives the same pairs.

    Returns
    -------
    list of StartGoal
    """
    w = load_world(world) if isinstance(world, str) else world
    spec = pair_regions(w.name if not isinstance(world, str) else world)
    rng = as_rng(seed)
    free = w.free_space(0.05, ROBOT_RADIUS + _PASSAGE)

    def connected(xy) -> bool:
        i, j = free.cell_of(np.asarray(xy))
        ny, nx = free.shape
        return bool(0 <= i < ny and 0 <= j < nx and free.data[i, j])

    def draw(region) -> np.ndarray:
        x0, y0, x1, y1 = region
        for _ in range(10_000):
            xy = np.array([rng.uniform(x0, x1), rng.uniform(y0, y1)])
            if w.distance_to_walls(xy) >= spec["clearance"] and connected(xy):
                return xy
        raise ValueError(f"no free point in region {region} of {w.name!r}")

    pairs = []
    for _ in range(int(n)):
        s = draw(spec["start_region"])
        g = draw(spec["goal_region"])
        heading = math.atan2(g[1] - s[1], g[0] - s[0])
        heading = wrap_angle(heading + rng.uniform(-math.pi / 4, math.pi / 4))
        pairs.append(
            StartGoal((float(s[0]), float(s[1]), heading), (float(g[0]), float(g[1])))
        )
    return pairs
