"""Frontiers on an occupancy grid: free cells next to unknown ones, in regions.

A cell of a log-odds map is *free* below ``-free_level``, *occupied* above
``occupied_level`` and *unknown* in between (0, no evidence, is unknown).
A frontier cell is a free cell with an unknown cell among its four
neighbours (Yamauchi, 1997); cells off the grid are not unknown. Frontier
cells are grouped into regions of 8-connected cells; each `Frontier` knows
its cells, its size and its centroid, and names a target cell: the region's
cell nearest its centroid (a robot sent there stands on the frontier even
when the region is curved).

Everything is vectorised NumPy (shifted arrays, `scipy.ndimage.label`);
`tests/exploration/naive_frontiers.py` holds the plain loops the tests hold
it to. Imports nothing of robotlib's but the mapping grid's type; never
plots.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

__all__ = [
    "FREE",
    "UNKNOWN",
    "OCCUPIED",
    "Frontier",
    "classify",
    "frontier_cells",
    "frontier_regions",
    "find_frontiers",
    "open_frontier",
]

FREE, UNKNOWN, OCCUPIED = 0, 1, 2
"""The cell states `classify` returns."""

_EIGHT = np.ones((3, 3), dtype=bool)


@dataclass(frozen=True, eq=False)
class Frontier:
    """One frontier region.

    Attributes
    ----------
    cells : numpy.ndarray of int64, shape (K, 2)
        Its cells ``(i, j)`` (row, column).
    centroid : numpy.ndarray, shape (2,)
        Mean of its cell centres ``(x, y)``, m.
    target : numpy.ndarray, shape (2,)
        Centre of its cell nearest the centroid ``(x, y)``, m.
    size : int
        Number of cells.
    length : float
        ``size`` times the cell side, m (the frontier's rough extent).
    """

    cells: np.ndarray
    centroid: np.ndarray
    target: np.ndarray
    size: int
    length: float


def _logodds(grid) -> np.ndarray:
    L = np.asarray(getattr(grid, "logodds", grid))
    if L.ndim != 2:
        raise ValueError(f"the map must be 2-D, got shape {L.shape}")
    return L


def classify(grid, free_level: float = 0.2, occupied_level: float = 0.2) -> np.ndarray:
    """Return each cell's state: `FREE`, `UNKNOWN` or `OCCUPIED`.

    Parameters
    ----------
    grid : numpy.ndarray, shape (ny, nx), or OccupancyGrid
        Log-odds per cell.
    free_level, occupied_level : float
        A cell is free below ``-free_level``, occupied above
        ``occupied_level``, unknown between (both >= 0).

    Returns
    -------
    numpy.ndarray of int8, shape (ny, nx)
    """
    if free_level < 0 or occupied_level < 0:
        raise ValueError("free_level and occupied_level must be >= 0")
    L = _logodds(grid)
    state = np.full(L.shape, UNKNOWN, dtype=np.int8)
    state[L < -free_level] = FREE
    state[L > occupied_level] = OCCUPIED
    return state


def _next_to(mask: np.ndarray) -> np.ndarray:
    near = np.zeros_like(mask)
    near[1:, :] |= mask[:-1, :]
    near[:-1, :] |= mask[1:, :]
    near[:, 1:] |= mask[:, :-1]
    near[:, :-1] |= mask[:, 1:]
    return near


def open_frontier(state, frontier, min_cells: int) -> np.ndarray:
    """Keep the ``frontier`` cells next to an unknown piece of ``min_cells`` or more.

    An unknown piece smaller than that, all of its rim known, is a pocket
    no sensor will look into from the free space: the inside of a box whose
    wall the laser's beams grazed at a shallow angle and made free in a
    cell or two. Its frontier stays whatever the robots do.

    Parameters
    ----------
    state : array_like of int, shape (ny, nx)
        Cell states as `classify` returns them.
    frontier : array_like of bool, shape (ny, nx)
        Frontier cells (`frontier_cells`, or a student's).
    min_cells : int
        Smallest unknown piece worth a visit, cells (4-connected).

    Returns
    -------
    numpy.ndarray of bool, shape (ny, nx)
    """
    unknown = np.asarray(state) == UNKNOWN
    labels, n = ndimage.label(unknown)
    sizes = np.bincount(labels.ravel(), minlength=n + 1)
    big = (sizes >= min_cells)[labels] & unknown
    return np.asarray(frontier, dtype=bool) & _next_to(big)


def frontier_cells(state) -> np.ndarray:
    """Free cells with an unknown 4-neighbour.

    Parameters
    ----------
    state : array_like of int, shape (ny, nx)
        Cell states as `classify` returns them.

    Returns
    -------
    numpy.ndarray of bool, shape (ny, nx)
    """
    s = np.asarray(state)
    if s.ndim != 2:
        raise ValueError(f"state must be 2-D, got shape {s.shape}")
    return (s == FREE) & _next_to(s == UNKNOWN)


def frontier_regions(
    mask, origin=(0.0, 0.0), resolution: float = 1.0, min_size: int = 1
) -> list[Frontier]:
    """Group frontier cells into 8-connected regions.

    Parameters
    ----------
    mask : array_like of bool, shape (ny, nx)
        Frontier cells (`frontier_cells`).
    origin : tuple of float
        Lower-left corner of cell ``[0, 0]``, m.
    resolution : float
        Cell side, m.
    min_size : int
        Regions with fewer cells are dropped (sensor noise leaves specks).

    Returns
    -------
    list of Frontier
        Largest first (ties: the one whose first cell comes first in row
        order).
    """
    m = np.asarray(mask, dtype=bool)
    if m.ndim != 2:
        raise ValueError(f"mask must be 2-D, got shape {m.shape}")
    if not resolution > 0:
        raise ValueError("resolution must be positive")
    labels, n = ndimage.label(m, structure=_EIGHT)
    if n == 0:
        return []
    where = np.flatnonzero(labels)
    lab = labels.ravel()[where]
    order = where[np.argsort(lab, kind="stable")]
    counts = np.bincount(lab, minlength=n + 1)
    starts = np.concatenate([[0], np.cumsum(counts[1:])])
    nx = m.shape[1]
    out = []
    for k in np.flatnonzero(counts[1:] >= min_size) + 1:
        idx = order[starts[k - 1] : starts[k]]
        cells = np.column_stack(np.divmod(idx, nx)).astype(np.int64)
        centres = np.column_stack(
            [
                origin[0] + (cells[:, 1] + 0.5) * resolution,
                origin[1] + (cells[:, 0] + 0.5) * resolution,
            ]
        )
        centroid = centres.mean(axis=0)
        near = int(np.argmin(np.sum((centres - centroid) ** 2, axis=1)))
        out.append(
            Frontier(
                cells, centroid, centres[near], int(counts[k]), counts[k] * resolution
            )
        )
    out.sort(key=lambda f: (-f.size, f.cells[0, 0] * nx + f.cells[0, 1]))
    return out


def find_frontiers(
    grid,
    free_level: float = 0.2,
    occupied_level: float = 0.2,
    min_size: int = 3,
) -> list[Frontier]:
    """Return the frontier regions of an `OccupancyGrid`.

    `classify`, then `frontier_cells`, then `frontier_regions`.
    """
    state = classify(grid, free_level, occupied_level)
    return frontier_regions(
        frontier_cells(state), grid.origin, grid.resolution, min_size
    )
