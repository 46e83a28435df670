"""How well an exploration went, judged by the true world.

- `reachable_area`: the true free cells a robot can see from where its body
  can go: cells without a wall within one robot radius (plus a cell) of the
  admissible area and joined to it through such cells (not the inside of a
  box) (`robotlib.world.World.free_space`, the piece of free
  space holding ``World.start``).
- `explored_fraction`: the share of those cells the map knows (free or
  occupied, `robotlib.exploration.frontiers.classify`).
- `time_to`: the first time a coverage curve reaches a level.
- `ExplorationResult`: what `robotlib.exploration.explore` and
  `robotlib.exploration.explore_team` return: the map, the coverage curve,
  the F1 of the map against the true walls (`robotlib.mapping.map_score`),
  each robot's path and length, collisions, the times to 90 % and 99 %.

Imports the world, the mapping metrics and the frontier states; never plots.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from ..mapping import MapScore, OccupancyGrid, dilate
from ..p3dx import ROBOT_RADIUS
from ..world import World
from .frontiers import UNKNOWN, classify

__all__ = ["reachable_area", "explored_fraction", "time_to", "ExplorationResult"]


def reachable_area(world: World, resolution: float = 0.1) -> np.ndarray:
    """Return the true free cells a robot can see from where it can drive.

    Parameters
    ----------
    world : World
        The truth.
    resolution : float
        Cell side, m (cells of ``world.occupancy_grid(resolution)``).

    Returns
    -------
    numpy.ndarray of bool, shape (ny, nx)
    """
    admissible = world.free_space(resolution, ROBOT_RADIUS).data
    walls = world.occupancy_grid(resolution).data
    near = dilate(admissible, int(math.ceil(ROBOT_RADIUS / resolution)) + 1)
    labels, _ = ndimage.label(near & ~walls)  # 4-connected: walls part pieces
    keep = np.unique(labels[admissible & (labels > 0)])
    return np.isin(labels, keep)


def explored_fraction(grid, reachable, free_level: float = 0.2) -> float:
    """Share of the ``reachable`` cells (bool (ny, nx)) the map ``grid`` knows."""
    r = np.asarray(reachable, dtype=bool)
    n = int(r.sum())
    if n == 0:
        raise ValueError("no reachable cell")
    known = classify(grid, free_level, free_level) != UNKNOWN
    return float((known & r).sum() / n)


def time_to(times, coverage, level: float) -> float:
    """First time (s) the coverage reaches ``level``; nan if it never does."""
    c = np.asarray(coverage, dtype=float)
    hit = np.flatnonzero(c >= level)
    return float(np.asarray(times, dtype=float)[hit[0]]) if len(hit) else float("nan")


@dataclass(frozen=True, eq=False)
class ExplorationResult:
    """An exploration's record.

    Attributes
    ----------
    map : OccupancyGrid
        The (shared) map at the end.
    times : numpy.ndarray, shape (K,)
        Simulated times of the coverage samples, s.
    coverage : numpy.ndarray, shape (K,)
        Explored fraction of the reachable area at those times.
    paths : list of numpy.ndarray, each (T, 3)
        Each robot's true poses, one per cycle.
    estimates : list of numpy.ndarray, each (T, 3)
        The poses each robot mapped from (the truth, or SLAM's estimate).
    score : MapScore
        The final map against the true walls.
    wall_collisions, robot_collisions : int
        Times a robot touched a wall, or another robot (starts of contact).
    outcome : str
        ``"home"`` (explored and back), ``"explored"`` (no reachable
        frontier left, not every robot home), ``"timeout"``.
    duration : float
        Simulated time at the end, s.
    snapshots : list of tuple
        ``(time, logodds (ny, nx) float16, poses (R, 3), targets (R, 2))``
        every ``ExploreSettings.snapshot_period`` s, for animations.
    targets : list of numpy.ndarray
        Each robot's chosen targets in order, (N, 2) m.
    """

    map: OccupancyGrid
    times: np.ndarray
    coverage: np.ndarray
    paths: list
    estimates: list
    score: MapScore
    wall_collisions: int
    robot_collisions: int
    outcome: str
    duration: float
    snapshots: list = field(default_factory=list)
    targets: list = field(default_factory=list)

    @property
    def n_robots(self) -> int:
        """Team size."""
        return len(self.paths)

    @property
    def collisions(self) -> int:
        """Wall and robot collisions together."""
        return self.wall_collisions + self.robot_collisions

    @property
    def explored(self) -> float:
        """Final explored fraction."""
        return float(self.coverage[-1]) if len(self.coverage) else 0.0

    @property
    def path_lengths(self) -> np.ndarray:
        """Distance each robot drove, m, shape (R,)."""
        return np.array(
            [float(np.hypot(*np.diff(p[:, :2], axis=0).T).sum()) for p in self.paths]
        )

    def time_to(self, level: float) -> float:
        """First simulated time the coverage reached ``level``, s (nan: never)."""
        return time_to(self.times, self.coverage, level)

    def summary(self) -> dict:
        """Return the numbers as a plain dict (JSON-ready)."""
        return {
            "robots": self.n_robots,
            "explored": self.explored,
            "f1": self.score.f1,
            "precision": self.score.precision,
            "recall": self.score.recall,
            "t90_s": self.time_to(0.9),
            "t99_s": self.time_to(0.99),
            "duration_s": self.duration,
            "path_m": [float(v) for v in self.path_lengths],
            "wall_collisions": self.wall_collisions,
            "robot_collisions": self.robot_collisions,
            "outcome": self.outcome,
        }
