"""Ray casting against wall segments (exact) and occupancy grids (fast).

Both casters take many poses at once and spread them over threads.
"""

from __future__ import annotations

import numpy as np

from .._config import readonly
from ..world import Grid, World
from . import _kernels

__all__ = ["cast_rays", "cast_rays_grid", "grid_field"]


def _poses(poses) -> np.ndarray:
    p = np.ascontiguousarray(np.asarray(poses, dtype=np.float64))
    if p.ndim == 1:
        p = p[None, :]
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"poses must have shape (3,) or (K, 3), got {np.shape(poses)}")
    return p


def _segments(walls) -> np.ndarray:
    seg = walls.obstacles if isinstance(walls, World) else walls
    seg = np.ascontiguousarray(np.asarray(seg, dtype=np.float64))
    if seg.ndim != 2 or seg.shape[1] != 4:
        raise ValueError(f"segments must have shape (M, 4), got {seg.shape}")
    return readonly(seg)


def cast_rays(walls, poses, angles, max_range: float = 5.0) -> np.ndarray:
    """Exact range along each ray to the nearest wall segment.

    Parameters
    ----------
    walls : World or array_like, shape (M, 4)
        A world (its `World.obstacles` are used) or segments ``x1, y1, x2, y2``, m.
    poses : array_like, shape (3,) or (K, 3)
        Ray origins and headings ``(x, y, theta)``, m and rad.
    angles : array_like, shape (R,)
        Ray directions relative to each pose's heading, rad.
    max_range : float
        Rays that hit nothing within this distance report it, m.

    Returns
    -------
    numpy.ndarray, shape (K, R)
        Ranges in m, in ``[0, max_range]``.
    """
    p = _poses(poses)
    a = np.ascontiguousarray(np.atleast_1d(np.asarray(angles, dtype=np.float64)))
    out = np.empty((len(p), len(a)))
    _kernels.cast_segments(p, a, float(max_range), _segments(walls), out)
    return out


def grid_field(grid: Grid) -> np.ndarray:
    """Precompute what `cast_rays_grid` needs from a grid.

    Compute it once per grid when casting many batches (it costs a distance
    transform of the grid).

    Parameters
    ----------
    grid : Grid
        Boolean occupancy grid.

    Returns
    -------
    numpy.ndarray of float32, shape (ny + 2, nx + 2)
        The grid padded with a ring of occupied cells: -1 where occupied,
        elsewhere a lower bound on the free distance around the cell, in cells.
    """
    occ = np.ascontiguousarray(grid.data, dtype=np.bool_)
    out = np.empty((occ.shape[0] + 2, occ.shape[1] + 2), dtype=np.float32)
    _kernels.clearance_field(occ, out)
    return out


def cast_rays_grid(
    grid: Grid, poses, angles, max_range: float = 5.0, field=None
) -> np.ndarray:
    """Range along each ray to the first occupied cell of a grid.

    Parameters
    ----------
    grid : Grid
        Boolean occupancy grid (e.g. `World.occupancy_grid`); the grid's edge
        counts as a wall.
    poses : array_like, shape (3,) or (K, 3)
        Ray origins and headings, m and rad.
    angles : array_like, shape (R,)
        Ray directions relative to each pose's heading, rad.
    max_range : float
        Rays that hit nothing within this distance report it, m.
    field : numpy.ndarray, shape (ny + 2, nx + 2), optional
        `grid_field` of ``grid``, if already computed.

    Returns
    -------
    numpy.ndarray, shape (K, R)
        Ranges in m, to the boundary of the first occupied cell (0 from
        inside an occupied cell or outside the grid).
    """
    p = _poses(poses)
    a = np.ascontiguousarray(np.atleast_1d(np.asarray(angles, dtype=np.float64)))
    field = grid_field(grid) if field is None else field
    ny, nx = grid.shape
    if field.shape != (ny + 2, nx + 2):
        raise ValueError(f"field has shape {field.shape}, grid {grid.shape}")
    out = np.empty((len(p), len(a)))
    x0, y0 = grid.origin
    _kernels.cast_grid(
        p,
        a,
        float(max_range),
        np.ascontiguousarray(field, dtype=np.float32),
        x0,
        y0,
        grid.resolution,
        out,
    )
    return out
