"""`Grid`: a regular grid over the plane (occupancy, distance field, free space).

Imports nothing of robotlib.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Grid"]


@dataclass(frozen=True)
class Grid:
    """A regular grid over the plane.

    Attributes
    ----------
    data : numpy.ndarray, shape (ny, nx)
        Cell values; row ``i`` is ``y``, column ``j`` is ``x``.
    origin : tuple of float
        ``(x0, y0)``: world coordinates of the lower-left corner of cell
        ``[0, 0]``, m.
    resolution : float
        Side of a cell, m.
    """

    data: np.ndarray
    origin: tuple[float, float]
    resolution: float

    @property
    def shape(self) -> tuple[int, int]:
        """Grid shape ``(ny, nx)``."""
        return self.data.shape

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """``(xmin, xmax, ymin, ymax)`` in m, as matplotlib's ``imshow`` wants."""
        ny, nx = self.data.shape
        x0, y0 = self.origin
        return (x0, x0 + nx * self.resolution, y0, y0 + ny * self.resolution)

    def cell_of(self, xy) -> tuple[np.ndarray, np.ndarray]:
        """Return ``(i, j)`` cell indices of points ``xy`` (shape (..., 2), m).

        Indices may fall outside the grid; check them against `shape`.
        """
        xy = np.asarray(xy, dtype=float)
        j = np.floor((xy[..., 0] - self.origin[0]) / self.resolution).astype(np.int64)
        i = np.floor((xy[..., 1] - self.origin[1]) / self.resolution).astype(np.int64)
        return i, j

    def centres(self) -> np.ndarray:
        """Return the centres of all cells, shape (ny, nx, 2), m."""
        ny, nx = self.data.shape
        xs = self.origin[0] + (np.arange(nx) + 0.5) * self.resolution
        ys = self.origin[1] + (np.arange(ny) + 0.5) * self.resolution
        gx, gy = np.meshgrid(xs, ys)
        return np.stack([gx, gy], axis=-1)
