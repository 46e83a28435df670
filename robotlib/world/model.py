"""`World`: wall segments in metres, bounds, a start pose, and the grids made from them.

A `World` is immutable. Build one from segments, or read one with
`robotlib.world.load_world`. Grids (occupancy, distance field, admissible free
space) are computed on demand and cached per resolution. Imports only the
robot's constants and the world's own kernels; never a file reader (those
import this module).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._random import as_rng
from ..p3dx import ROBOT_RADIUS
from . import _kernels
from .grid import Grid
from .index import INDEX_MIN_SEGMENTS, SegmentIndex

__all__ = ["World", "POINT_SIZE", "END_FACE"]


POINT_SIZE = 0.02
"""Side of the small cross that stands for one map DATA point, m."""

END_FACE = 0.06
"""Width of the face a wall's free end shows to the simulated sensors, m.

A wall is a segment in the files, but a real partition has an end: met
end-on (a door frame, a partition's end), it echoes from its end face.
`World.sensed_obstacles` adds that face. It is about half a real wall's
thickness on purpose: wider faces echo into a sonar's cone from the side,
which VFH's grid paints on the sonar's axis, inside the door (the doorway
world, 20 pairs: 18 reached by odometry without faces, 6 with 0.12 m faces,
15 with 0.06 m, 17 with 0.02 m), while 0.02 m left 3 collisions in 60
episodes on generated office floors and trap fields (0.06 m: none)."""

_JOINED = 1e-3  # an end this close to another wall is joined to it, m

_MAX_REDRAWS = 20
_FIELD_BLOCK = 4  # cells a side of the distance field's blocks on large maps
SERIAL_MAX_DISTANCES = 16_000_000
"""Points times segments up to which `World.distance_to_walls` uses one thread.

About 0.15 s on one thread at most (the office's 5 cm field: 15 million),
and the serial kernel compiles without numba's parallel pass.
"""


@dataclass(frozen=True, eq=False)
class World:
    """A planar world of wall segments.

    Parameters
    ----------
    segments : array_like, shape (M, 4)
        Walls as ``x1, y1, x2, y2``, m.
    bounds : tuple of float, optional
        ``(xmin, ymin, xmax, ymax)``, m. Defaults to the segments' bounding
        box (with the points and the start pose), grown by 0.5 m.
    start : tuple of float, optional
        Robot start pose ``(x, y, theta)`` in m and rad; defaults to the
        centre of the bounds, heading 0.
    points : array_like, shape (P, 2), optional
        Point obstacles (a ``.map`` file's DATA), m.
    name : str, optional
        A short name, e.g. ``"corridor"``.
    source : pathlib.Path, optional
        The file the world was read from, if any.
    """

    segments: np.ndarray
    bounds: tuple[float, float, float, float] | None = None
    start: tuple[float, float, float] | None = None
    points: np.ndarray | None = None
    name: str = ""
    source: Path | None = None
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self):
        seg = np.ascontiguousarray(np.asarray(self.segments, dtype=float))
        if seg.size == 0:
            seg = np.zeros((0, 4))
        if seg.ndim != 2 or seg.shape[1] != 4:
            raise ValueError(f"segments must have shape (M, 4), got {seg.shape}")
        pts = np.zeros((0, 2)) if self.points is None else self.points
        pts = np.ascontiguousarray(np.asarray(pts, dtype=float).reshape(-1, 2))
        if not (np.all(np.isfinite(seg)) and np.all(np.isfinite(pts))):
            raise ValueError("segments and points must be finite")
        seg.setflags(write=False)
        pts.setflags(write=False)
        object.__setattr__(self, "segments", seg)
        object.__setattr__(self, "points", pts)
        if self.bounds is None:
            xy = np.concatenate([seg[:, :2], seg[:, 2:], pts])
            if self.start is not None:
                xy = np.concatenate([xy, [self.start[:2]]])
            if len(xy) == 0:
                xy = np.zeros((1, 2))
            lo, hi = xy.min(axis=0) - 0.5, xy.max(axis=0) + 0.5
            object.__setattr__(self, "bounds", (lo[0], lo[1], hi[0], hi[1]))
        b = tuple(float(v) for v in self.bounds)
        if len(b) != 4 or not (b[0] < b[2] and b[1] < b[3]):
            raise ValueError(f"bounds must be (xmin, ymin, xmax, ymax), got {b}")
        object.__setattr__(self, "bounds", b)
        if self.start is None:
            centre = ((b[0] + b[2]) / 2, (b[1] + b[3]) / 2, 0.0)
            object.__setattr__(self, "start", centre)
        object.__setattr__(self, "start", tuple(float(v) for v in self.start))

    def __eq__(self, other) -> bool:
        """Equal walls, points, bounds and start (name and source ignored)."""
        if not isinstance(other, World):
            return NotImplemented
        return (
            np.array_equal(self.segments, other.segments)
            and np.array_equal(self.points, other.points)
            and self.bounds == other.bounds
            and self.start == other.start
        )

    __hash__ = None

    def __setstate__(self, state: dict) -> None:
        """Unpickle with the arrays read-only again, as built.

        Pickling drops NumPy's read-only flag; numba types a writable array
        differently, so an unpickled world would compile every kernel anew.
        """
        for value in (*state.values(), *(state.get("_cache") or {}).values()):
            for a in (value, getattr(value, "data", None)):
                if isinstance(a, np.ndarray):
                    a.setflags(write=False)
        self.__dict__.update(state)

    @property
    def size(self) -> tuple[float, float]:
        """Width and height of the bounds, m."""
        return (self.bounds[2] - self.bounds[0], self.bounds[3] - self.bounds[1])

    @property
    def obstacles(self) -> np.ndarray:
        """All obstacle segments, shape (M', 4), m.

        The walls plus a small cross (side `POINT_SIZE`) for each point
        obstacle. Sensing and collisions use these.
        """
        if "obstacles" not in self._cache:
            h = POINT_SIZE / 2
            p = self.points
            crosses = np.concatenate(
                [
                    np.column_stack([p[:, 0] - h, p[:, 1], p[:, 0] + h, p[:, 1]]),
                    np.column_stack([p[:, 0], p[:, 1] - h, p[:, 0], p[:, 1] + h]),
                ]
            )
            obs = np.ascontiguousarray(np.concatenate([self.segments, crosses]))
            obs.setflags(write=False)
            self._cache["obstacles"] = obs
        return self._cache["obstacles"]

    @property
    def sensed_obstacles(self) -> np.ndarray:
        """The obstacles as the simulated sonar and laser see them, shape (M'', 4), m.

        `obstacles` plus, at each free end of a wall (an end that touches no
        other wall), its end face: a segment `END_FACE` wide across the wall
        through that end. Without it a wall met end-on, a segment of no
        thickness, returns no echo. Collisions and distances use `obstacles`
        (the face changes them by at most ``END_FACE / 2``).
        """
        if "sensed" not in self._cache:
            sensed = np.ascontiguousarray(
                np.concatenate([self.obstacles, _end_faces(self.segments)])
            )
            sensed.setflags(write=False)
            self._cache["sensed"] = sensed
        return self._cache["sensed"]

    def distance_to_walls(self, xy) -> np.ndarray:
        """Distance from points to the nearest obstacle.

        Parameters
        ----------
        xy : array_like, shape (..., 2)
            Points, m.

        Returns
        -------
        numpy.ndarray, shape (...)
            Distances, m (``inf`` in a world with no obstacles).
        """
        xy = np.asarray(xy, dtype=float)
        flat = np.ascontiguousarray(xy.reshape(-1, 2))
        if len(self.obstacles) >= INDEX_MIN_SEGMENTS:
            return self.segment_index().distances(flat).reshape(xy.shape[:-1])
        out = np.empty(len(flat))
        kernel = (  # one thread for small work: no parallel compile on a cold start
            _kernels.min_distance_to_segments_serial
            if len(flat) * len(self.obstacles) <= SERIAL_MAX_DISTANCES
            else _kernels.min_distance_to_segments
        )
        kernel(flat, self.obstacles, out)
        return out.reshape(xy.shape[:-1])

    def segment_index(self) -> SegmentIndex:
        """Return the obstacles sorted into buckets (`SegmentIndex`), built once.

        Distances and rays through it are the same numbers as against every
        obstacle, found much sooner on a map of many walls or points.
        """
        if "index" not in self._cache:
            self._cache["index"] = SegmentIndex.build(self.obstacles, self.bounds)
        return self._cache["index"]

    def is_free(self, xy, radius: float = ROBOT_RADIUS) -> np.ndarray:
        """Test whether a disc of ``radius`` at each point touches nothing.

        Parameters
        ----------
        xy : array_like, shape (..., 2)
            Centres, m.
        radius : float
            Disc radius, m (the Pioneer 3-DX's by default; 0 for a point).

        Returns
        -------
        numpy.ndarray of bool, shape (...)
            True where the disc lies inside the bounds and clear of every
            obstacle.
        """
        xy = np.asarray(xy, dtype=float)
        xmin, ymin, xmax, ymax = self.bounds
        inside = (
            (xy[..., 0] - radius >= xmin)
            & (xy[..., 0] + radius <= xmax)
            & (xy[..., 1] - radius >= ymin)
            & (xy[..., 1] + radius <= ymax)
        )
        return inside & (self.distance_to_walls(xy) > radius)

    def _empty_grid(self, resolution: float) -> tuple[tuple[int, int], tuple]:
        if not resolution > 0:
            raise ValueError(f"resolution must be positive, got {resolution}")
        xmin, ymin, xmax, ymax = self.bounds
        nx = max(1, int(np.ceil((xmax - xmin) / resolution - 1e-9)))
        ny = max(1, int(np.ceil((ymax - ymin) / resolution - 1e-9)))
        return (ny, nx), (xmin, ymin)

    def occupancy_grid(self, resolution: float = 0.05) -> Grid:
        """Rasterise the obstacles.

        Parameters
        ----------
        resolution : float
            Cell side, m.

        Returns
        -------
        Grid
            ``data`` is a bool array, True where an obstacle crosses the cell.
        """
        key = ("occupancy", float(resolution))
        if key not in self._cache:
            shape, origin = self._empty_grid(resolution)
            occ = np.zeros(shape, dtype=np.bool_)
            _kernels.rasterise_segments(
                self.obstacles, origin[0], origin[1], float(resolution), occ
            )
            occ.setflags(write=False)
            self._cache[key] = Grid(occ, origin, float(resolution))
        return self._cache[key]

    def distance_field(self, resolution: float = 0.05) -> Grid:
        """Distance from each cell centre to the nearest obstacle.

        Parameters
        ----------
        resolution : float
            Cell side, m.

        Returns
        -------
        Grid
            ``data`` is float64, m (exact to the segments, not to the cells).
        """
        key = ("distance", float(resolution))
        if key not in self._cache:
            shape, origin = self._empty_grid(resolution)
            if len(self.obstacles) >= INDEX_MIN_SEGMENTS:  # block by block
                dist = np.empty(shape)
                index = self.segment_index()
                _kernels.indexed_distance_field(
                    origin[0], origin[1], float(resolution), _FIELD_BLOCK,
                    index.segments, *index.args, np.nan, dist,
                )  # fmt: skip
            else:
                grid = Grid(np.zeros(shape), origin, float(resolution))
                dist = self.distance_to_walls(grid.centres())
            dist.setflags(write=False)
            self._cache[key] = Grid(dist, origin, float(resolution))
        return self._cache[key]

    def free_space(
        self, resolution: float = 0.05, radius: float = ROBOT_RADIUS
    ) -> Grid:
        """Return the admissible area: cells a robot can reach from the start.

        A cell is admissible when a disc of ``radius`` at its centre is free
        (`is_free`) and it connects to the start pose's cell through free
        cells. If the start itself is not free, every free cell is admissible.

        Parameters
        ----------
        resolution : float
            Cell side, m.
        radius : float
            Robot radius, m.

        Returns
        -------
        Grid
            ``data`` is a bool array.
        """
        key = ("free", float(resolution), float(radius))
        if key not in self._cache:
            dist = self._clearance(resolution, radius)
            # is_free at the centres, with the distances already measured (the
            # centres' rows and columns, not a (ny, nx, 2) array of them)
            ny, nx = dist.shape
            xs = dist.origin[0] + (np.arange(nx) + 0.5) * dist.resolution
            ys = dist.origin[1] + (np.arange(ny) + 0.5) * dist.resolution
            xmin, ymin, xmax, ymax = self.bounds
            free = dist.data > radius
            free &= ((ys - radius >= ymin) & (ys + radius <= ymax))[:, None]
            free &= ((xs - radius >= xmin) & (xs + radius <= xmax))[None, :]
            i, j = dist.cell_of(np.array(self.start[:2]))
            if 0 <= i < ny and 0 <= j < nx and free[i, j]:
                free = _flood_fill(free, int(i), int(j))
            free.setflags(write=False)
            self._cache[key] = Grid(free, dist.origin, dist.resolution)
        return self._cache[key]

    def _clearance(self, resolution: float, radius: float) -> Grid:
        """Return the distance field, or a grid with its side of ``radius`` per cell.

        The field when it is at hand or the map is small; on a large map
        one that measures only the cells whose side of ``radius`` their
        block's bound does not settle (the others are ``inf`` or ``-inf``:
        `_kernels.indexed_distance_field` with a ``cut``), so ``data >
        radius`` is the field's own mask. On ``columbia.map`` at 5 cm and
        0.2 m: 0.24 s of processor time against the field's 0.77 s.
        """
        if ("distance", float(resolution)) in self._cache or len(
            self.obstacles
        ) < INDEX_MIN_SEGMENTS:
            return self.distance_field(resolution)
        shape, origin = self._empty_grid(resolution)
        dist = np.empty(shape)
        index = self.segment_index()
        _kernels.indexed_distance_field(
            origin[0], origin[1], float(resolution), _FIELD_BLOCK, index.segments,
            *index.args, float(radius), dist,
        )  # fmt: skip
        return Grid(dist, origin, float(resolution))

    def sample_free_poses(
        self,
        n: int,
        rng: np.random.Generator | int | None = None,
        resolution: float = 0.05,
        radius: float = ROBOT_RADIUS,
    ) -> np.ndarray:
        """Draw poses uniformly over the admissible area, headings uniform.

        Parameters
        ----------
        n : int
            Number of poses.
        rng : numpy.random.Generator, int or None
            Randomness source or seed.
        resolution, radius : float
            Passed to `free_space`, m.

        Returns
        -------
        numpy.ndarray, shape (n, 3)
            Poses ``(x, y, theta)``, m and rad, each free (`is_free`) at
            ``radius``.
        """
        rng = as_rng(rng)
        grid = self.free_space(resolution, radius)
        key = ("free cells", float(resolution), float(radius))
        if key not in self._cache:  # found once (filters draw every step)
            self._cache[key] = _free_cells(grid.data)
        starts, cols = self._cache[key]
        n_free = int(starts[-1])
        if n_free == 0:
            raise ValueError(f"world {self.name!r} has no free space for r={radius}")
        out = np.empty((n, 3))
        todo = np.arange(n)
        # A cell whose centre is free may have a corner that is not: redraw the
        # few poses that land there (almost all are free on the first draw).
        for _ in range(_MAX_REDRAWS):
            _draw_poses(out, todo, grid, starts, cols, rng)
            todo = todo[~self.is_free(out[todo, :2], radius)]
            if len(todo) == 0:
                return out
        # Still not free after many draws: put them at free cell centres.
        ranks = rng.integers(0, n_free, size=len(todo))
        pick = _nth_true(starts, cols, grid.shape[1], ranks)
        centres = grid.centres().reshape(-1, 2)
        out[todo, :2] = centres[pick]
        return out


def _end_faces(seg: np.ndarray) -> np.ndarray:
    """End faces (`END_FACE` wide, across the wall) at the walls' free ends.

    ``seg`` (M, 4) m; returns (F, 4) m. An end is free when no other wall
    passes within `_JOINED` of it; zero-length walls get none.
    """
    faces = []
    d = seg[:, 2:] - seg[:, :2]
    length = np.hypot(d[:, 0], d[:, 1])
    a, b = seg[:, :2], seg[:, 2:]
    for i in np.flatnonzero(length > _JOINED):
        normal = np.array([-d[i, 1], d[i, 0]]) / length[i] * (END_FACE / 2)
        for p in (a[i], b[i]):
            # distance from p to every wall, its own left out
            along = np.einsum("ij,ij->i", p - a, d)
            t = np.clip(along / np.maximum(length**2, 1e-300), 0.0, 1.0)
            dist = np.hypot(*(a + t[:, None] * d - p).T)
            dist[i] = np.inf
            if dist.min() > _JOINED:
                faces.append((*(p - normal), *(p + normal)))
    return np.array(faces, dtype=float).reshape(-1, 4)


def _free_cells(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """List ``mask``'s True cells compactly: each row's first rank, each cell's column.

    Half the memory of their flat indexes (uint16 columns beside a count per
    row: 1.7 MB on a 50 m x 50 m building at 5 cm, kept beside a filter),
    found a block of rows at a time (no int64 list of them all).

    Parameters
    ----------
    mask : numpy.ndarray of bool, shape (ny, nx)
        The cells.

    Returns
    -------
    starts : numpy.ndarray of int64, shape (ny + 1,)
        Rank of each row's first True cell (``starts[-1]``: how many in all).
    cols : numpy.ndarray, shape (starts[-1],)
        Their columns, row by row (uint16, or int64 beyond 65,536 columns).
        Both read-only.
    """
    ny, nx = mask.shape
    starts = np.zeros(ny + 1, dtype=np.int64)
    np.cumsum(np.count_nonzero(mask, axis=1), out=starts[1:])
    cols = np.empty(starts[-1], dtype=np.uint16 if nx <= 1 << 16 else np.int64)
    step = max(1, (1 << 16) // max(nx, 1))  # rows at a time
    for i in range(0, ny, step):
        cols[starts[i] : starts[min(i + step, ny)]] = np.nonzero(mask[i : i + step])[1]
    starts.setflags(write=False)
    cols.setflags(write=False)
    return starts, cols


def _draw_poses(out, todo, grid: Grid, starts, cols, rng) -> None:
    """Draw ``out[todo]`` (m, m, rad): uniform in random free cells, uniform headings.

    The cells are ranks among `_free_cells`' ``starts, cols`` of ``grid``.
    A function of its own so that its draws (2.8 MB for 50,000 poses) are
    freed before the poses' clearance is measured.
    """
    k = len(todo)
    nx = grid.shape[1]
    i, j = np.divmod(
        _nth_true(starts, cols, nx, rng.integers(0, int(starts[-1]), size=k)), nx
    )
    u = rng.random((k, 3))
    out[todo, 0] = grid.origin[0] + (j + u[:, 0]) * grid.resolution
    out[todo, 1] = grid.origin[1] + (i + u[:, 1]) * grid.resolution
    out[todo, 2] = np.pi - 2.0 * np.pi * u[:, 2]


def _nth_true(
    starts: np.ndarray, cols: np.ndarray, nx: int, ranks: np.ndarray
) -> np.ndarray:
    """Return ``np.flatnonzero(mask)[ranks]`` from `_free_cells`' ``starts, cols``.

    ``nx`` is the mask's row length; ``ranks`` (k,) ints in ``[0,
    starts[-1])``. Returns (k,) int64 flat indexes (C order).
    """
    rows = np.searchsorted(starts, ranks, side="right") - 1
    return rows * nx + cols[ranks]


def _flood_fill(free: np.ndarray, i0: int, j0: int) -> np.ndarray:
    """Cells of ``free`` 4-connected to ``(i0, j0)``."""
    out = np.zeros_like(free)
    _kernels.flood_fill(free, i0, j0, out)
    return out
