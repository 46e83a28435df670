"""The configuration space: an inflated occupancy grid and a cost map.

`CSpace` holds, on one grid, the cells a robot of a given radius may not
enter (``blocked``) and a cost factor that keeps paths away from walls
(``cost``); cell and metre coordinates are converted here and nowhere else.
Build one from a `World` with `configuration_space`, or from a plain array
with `CSpace.from_array`. Unmapped obstacles (sonar hits) are added with
`CSpace.with_points`.

Imports the world layer and the planning kernels only; never plots.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..p3dx import ROBOT_RADIUS
from ..world import World
from . import _kernels

__all__ = ["CSpace", "configuration_space", "inflate", "cost_map"]


def inflate(occupied, radius: float, resolution: float = 1.0) -> np.ndarray:
    """Grow an occupancy grid by a disc.

    Parameters
    ----------
    occupied : array_like of bool, shape (ny, nx)
        Occupied cells.
    radius : float
        Disc radius, m.
    resolution : float
        Cell side, m.

    Returns
    -------
    numpy.ndarray of bool, shape (ny, nx)
        True where a cell's centre lies within ``radius`` of an occupied
        cell's centre.
    """
    occ = np.ascontiguousarray(np.asarray(occupied, dtype=np.bool_))
    if occ.ndim != 2:
        raise ValueError(f"occupied must be 2-D, got shape {occ.shape}")
    if radius < 0 or not resolution > 0:
        raise ValueError("radius must be >= 0 and resolution > 0")
    out = np.empty_like(occ)
    _kernels.inflate(occ, float(radius) / float(resolution), out)
    return out


def cost_map(distance, radius: float, falloff: float = 0.5, weight: float = 2.0):
    """Cost factor of each cell from its distance to the nearest wall.

    ``weight * (1 - (d - radius) / falloff)`` within ``falloff`` of the
    inflated wall, 0 beyond; a move into a cell costs its length times
    ``1 + cost``, so the octile heuristic stays admissible.

    Parameters
    ----------
    distance : array_like, shape (ny, nx)
        Distance of each cell centre to the nearest obstacle, m.
    radius : float
        Robot radius, m.
    falloff : float
        Width of the band that costs extra, m.
    weight : float
        Extra cost factor at the inflated wall.

    Returns
    -------
    numpy.ndarray of float64, shape (ny, nx)
    """
    d = np.asarray(distance, dtype=float)
    if falloff <= 0:
        return np.zeros_like(d)
    return weight * np.clip(1.0 - (d - radius) / falloff, 0.0, 1.0)


@dataclass(frozen=True, eq=False)
class CSpace:
    """A robot's configuration space on a grid.

    Attributes
    ----------
    blocked : numpy.ndarray of bool, shape (ny, nx)
        Cells a robot centre may not occupy (row ``i`` is ``y``).
    cost : numpy.ndarray of float64, shape (ny, nx)
        Extra cost factor of entering each cell (0: none).
    origin : tuple of float
        World coordinates of the lower-left corner of cell ``[0, 0]``, m.
    resolution : float
        Cell side, m.
    radius : float
        The robot radius the grid was inflated by, m.
    """

    blocked: np.ndarray
    cost: np.ndarray
    origin: tuple[float, float] = (0.0, 0.0)
    resolution: float = 1.0
    radius: float = 0.0

    def __post_init__(self):
        b = np.ascontiguousarray(np.asarray(self.blocked, dtype=np.bool_))
        c = np.ascontiguousarray(np.asarray(self.cost, dtype=np.float64))
        if b.ndim != 2 or c.shape != b.shape:
            raise ValueError(
                f"blocked must be 2-D and cost the same shape, got {b.shape}, {c.shape}"
            )
        if not np.all(np.isfinite(c)) or np.any(c < 0):
            raise ValueError("cost must be finite and >= 0")
        if not self.resolution > 0:
            raise ValueError(f"resolution must be positive, got {self.resolution}")
        object.__setattr__(self, "blocked", b)
        object.__setattr__(self, "cost", c)
        object.__setattr__(self, "origin", tuple(float(v) for v in self.origin))
        object.__setattr__(self, "resolution", float(self.resolution))

    @classmethod
    def from_array(cls, blocked, resolution: float = 1.0, origin=(0.0, 0.0), cost=None):
        """Wrap a plain grid (no inflation, no cost unless given)."""
        b = np.asarray(blocked, dtype=np.bool_)
        c = np.zeros(b.shape) if cost is None else cost
        return cls(b, c, origin, resolution)

    @property
    def shape(self) -> tuple[int, int]:
        """Grid shape ``(ny, nx)``."""
        return self.blocked.shape

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """``(xmin, xmax, ymin, ymax)`` in m, for ``imshow``."""
        ny, nx = self.shape
        x0, y0 = self.origin
        return (x0, x0 + nx * self.resolution, y0, y0 + ny * self.resolution)

    def to_cell(self, xy) -> np.ndarray:
        """Cells ``(i, j)`` of points ``xy`` (..., 2), m; int64 (..., 2).

        Indices may fall outside the grid; see `inside`.
        """
        xy = np.asarray(xy, dtype=float)
        j = np.floor((xy[..., 0] - self.origin[0]) / self.resolution)
        i = np.floor((xy[..., 1] - self.origin[1]) / self.resolution)
        return np.stack([i, j], axis=-1).astype(np.int64)

    def to_metres(self, cells) -> np.ndarray:
        """Centres ``(x, y)`` of cells ``(i, j)`` (..., 2), m."""
        c = np.asarray(cells, dtype=float)
        x = self.origin[0] + (c[..., 1] + 0.5) * self.resolution
        y = self.origin[1] + (c[..., 0] + 0.5) * self.resolution
        return np.stack([x, y], axis=-1)

    def inside(self, cells) -> np.ndarray:
        """Test whether cells ``(i, j)`` (..., 2) lie on the grid."""
        c = np.asarray(cells)
        ny, nx = self.shape
        return (c[..., 0] >= 0) & (c[..., 0] < ny) & (c[..., 1] >= 0) & (c[..., 1] < nx)

    def is_free(self, xy) -> np.ndarray:
        """Test whether points ``xy`` (..., 2), m, fall in an unblocked cell."""
        c = self.to_cell(xy)
        ok = self.inside(c)
        ii = np.where(ok, c[..., 0], 0)
        jj = np.where(ok, c[..., 1], 0)
        return ok & ~self.blocked[ii, jj]

    def node(self, xy, what: str = "point") -> int:
        """Flat node index of a point, m; `ValueError` if off-grid or blocked."""
        c = self.to_cell(np.asarray(xy, dtype=float)[:2])
        i, j = int(c[0]), int(c[1])
        ny, nx = self.shape
        if not (0 <= i < ny and 0 <= j < nx):
            raise ValueError(f"{what} {tuple(np.asarray(xy)[:2])} is off the grid")
        if self.blocked[i, j]:
            raise ValueError(
                f"{what} {tuple(float(v) for v in np.asarray(xy)[:2])} is inside "
                f"an obstacle (cell {i}, {j} is blocked in the configuration space)"
            )
        return i * nx + j

    def nearest_free(self, xy, max_distance: float = 0.5) -> np.ndarray | None:
        """Return the centre of the unblocked cell nearest ``xy``, m.

        None when no unblocked cell lies within ``max_distance``.
        """
        p = np.asarray(xy, dtype=float)[:2]
        if self.is_free(p):
            return self.to_metres(self.to_cell(p))
        r = int(np.ceil(max_distance / self.resolution))
        i0, j0 = self.to_cell(p)
        ny, nx = self.shape
        ia, ib = max(0, i0 - r), min(ny, i0 + r + 1)
        ja, jb = max(0, j0 - r), min(nx, j0 + r + 1)
        if ia >= ib or ja >= jb:
            return None
        window = ~self.blocked[ia:ib, ja:jb]
        cells = np.argwhere(window) + [ia, ja]
        if len(cells) == 0:
            return None
        centres = self.to_metres(cells)
        d = np.hypot(*(centres - p).T)
        k = int(np.argmin(d))
        return centres[k] if d[k] <= max_distance else None

    def with_points(self, xy, radius: float | None = None) -> CSpace:
        """Return a copy with obstacles at points ``xy`` (P, 2), m.

        Discs of ``radius`` (default: the robot's) are blocked around each
        point (e.g. sonar hits), with a cost band around them.
        """
        r = self.radius if radius is None else float(radius)
        pts = np.asarray(xy, dtype=float).reshape(-1, 2)
        mark = np.zeros(self.shape, dtype=np.bool_)
        c = self.to_cell(pts)
        ok = self.inside(c)
        mark[c[ok, 0], c[ok, 1]] = True
        if not mark.any():
            return self
        grown = inflate(mark, r + self.resolution / 2, self.resolution)
        band = inflate(mark, r + 0.5 + self.resolution / 2, self.resolution)
        cost = self.cost.copy()
        cost[band] = np.maximum(cost[band], 0.5 * (self.cost.max() or 1.0))
        return CSpace(self.blocked | grown, cost, self.origin, self.resolution, r)


def configuration_space(
    world: World,
    resolution: float = 0.05,
    radius: float = ROBOT_RADIUS,
    margin: float = 0.02,
    falloff: float = 0.5,
    weight: float = 2.0,
) -> CSpace:
    """Build the configuration space of a round robot in ``world``.

    A cell is blocked when the distance from its centre to the nearest
    obstacle (the world's exact distance field) is at most
    ``radius + margin``, or a disc of that radius would leave the bounds.

    Parameters
    ----------
    world : World
        The map.
    resolution : float
        Cell side, m.
    radius : float
        Robot radius, m (the Pioneer 3-DX's by default).
    margin : float
        Extra clearance, m.
    falloff, weight : float
        The cost band (see `cost_map`).

    Returns
    -------
    CSpace
    """
    dist = world.distance_field(resolution)
    r = float(radius) + float(margin)
    centres = dist.centres()
    xmin, ymin, xmax, ymax = world.bounds
    edge = np.minimum.reduce(
        [
            centres[..., 0] - xmin,
            xmax - centres[..., 0],
            centres[..., 1] - ymin,
            ymax - centres[..., 1],
        ]
    )
    d = np.minimum(dist.data, edge)
    blocked = d <= r
    return CSpace(blocked, cost_map(d, r, falloff, weight), dist.origin, resolution, r)
