"""Map quality against the true world, and trajectory error.

A map's occupied cells (log-odds above a threshold) are compared with
`robotlib.world.World.occupancy_grid` at the same resolution, with a
tolerance of one cell:

- precision: the share of mapped occupied cells within one cell of a true
  wall cell;
- recall: the share of the true wall cells the robot explored (within one
  cell of a cell the map has any evidence for) that have a mapped occupied
  cell within one cell;
- F1: their harmonic mean (0 when either is 0);
- mean distance: from the centres of the mapped occupied cells to the true
  walls, m.

Imports only the world and NumPy; never plots.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..world import World
from ..world.geometry import wrap_angle

__all__ = ["MapScore", "map_score", "dilate", "trajectory_rms"]


@dataclass(frozen=True)
class MapScore:
    """How a map compares with the truth (see the module docstring).

    Attributes
    ----------
    precision, recall, f1 : float
        In [0, 1].
    mean_distance : float
        Mean distance from mapped occupied cells to the true walls, m (nan
        when nothing is mapped occupied).
    n_mapped, n_true : int
        Mapped occupied cells; explored true wall cells.
    """

    precision: float
    recall: float
    f1: float
    mean_distance: float
    n_mapped: int
    n_true: int

    def as_dict(self) -> dict:
        """Return the fields as a plain dict."""
        return asdict(self)


def dilate(mask: np.ndarray, cells: int = 1) -> np.ndarray:
    """Grow a boolean mask by ``cells`` in every direction (8-connected)."""
    m = np.asarray(mask, dtype=bool)
    out = m.copy()
    for _ in range(int(cells)):
        grown = out.copy()
        grown[1:, :] |= out[:-1, :]
        grown[:-1, :] |= out[1:, :]
        grown[:, 1:] |= out[:, :-1]
        grown[:, :-1] |= out[:, 1:]
        grown[1:, 1:] |= out[:-1, :-1]
        grown[:-1, :-1] |= out[1:, 1:]
        grown[1:, :-1] |= out[:-1, 1:]
        grown[:-1, 1:] |= out[1:, :-1]
        out = grown
    return out


def map_score(
    logodds,
    world: World,
    resolution: float,
    threshold: float = 0.0,
    tolerance: int = 1,
    explored_only: bool = True,
) -> MapScore:
    """Score a map against ``world`` (see the module docstring).

    Parameters
    ----------
    logodds : numpy.ndarray, shape (ny, nx), or OccupancyGrid
        The map's log-odds (or a bool array of occupied cells, then every
        cell counts as explored), on the cells of
        ``world.occupancy_grid(resolution)``.
    world : World
        The truth.
    resolution : float
        Cell side, m.
    threshold : float
        Cells with log-odds above it count as occupied.
    tolerance : int
        Cells of slack for a match.
    explored_only : bool
        Recall over the explored true walls only (else over all of them).

    Returns
    -------
    MapScore
    """
    L = getattr(logodds, "logodds", logodds)
    L = np.asarray(L)
    truth = world.occupancy_grid(resolution).data
    if L.shape != truth.shape:
        raise ValueError(f"map has shape {L.shape}, the truth {truth.shape}")
    if L.dtype == bool:
        mapped, seen = L, np.ones_like(L)
    else:
        mapped, seen = L > threshold, L != 0
    n_mapped = int(mapped.sum())
    true_walls = truth & dilate(seen, tolerance) if explored_only else truth
    n_true = int(true_walls.sum())
    precision = (
        float((mapped & dilate(truth, tolerance)).sum() / n_mapped) if n_mapped else 0.0
    )
    recall = (
        float((true_walls & dilate(mapped, tolerance)).sum() / n_true)
        if n_true
        else 0.0
    )
    f1 = 2 * precision * recall / (precision + recall) if precision + recall else 0.0
    dist = world.distance_field(resolution).data
    mean_d = float(dist[mapped].mean()) if n_mapped else float("nan")
    return MapScore(precision, recall, f1, mean_d, n_mapped, n_true)


def trajectory_rms(estimate, truth) -> float:
    """Root-mean-square position error of a trajectory (T, 3) against the truth, m."""
    e = np.asarray(estimate, dtype=float)
    t = np.asarray(truth, dtype=float)
    if e.shape != t.shape or e.ndim != 2 or e.shape[1] < 2:
        raise ValueError(f"trajectories differ in shape: {e.shape} vs {t.shape}")
    return float(np.sqrt(np.mean(np.sum((e[:, :2] - t[:, :2]) ** 2, axis=1))))


def heading_rms(estimate, truth) -> float:
    """Root-mean-square heading error (wrapped) of a trajectory, rad."""
    e = np.asarray(estimate, dtype=float)
    t = np.asarray(truth, dtype=float)
    return float(np.sqrt(np.mean(wrap_angle(e[:, 2] - t[:, 2]) ** 2)))
