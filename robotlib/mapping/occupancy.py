"""Occupancy-grid mapping with known poses, in log-odds, for sonar and laser.

An `OccupancyGrid` holds log-odds ``l = log(p / (1 - p))`` per cell (0:
unknown) on the same cells as `robotlib.world.World.occupancy_grid` at its
resolution, so maps and ground truth compare cell for cell. Each reading adds
its inverse sensor model's log-odds to the cells it saw (Probabilistic
Robotics, table 9.1, with a prior of 0.5):

- sonar (`InverseSonarModel`, `inverse_sonar_model`): inside the 30 degree
  cone, free nearer than the range, occupied on the arc at the range,
  unknown beyond; a reading at max range (no echo) frees the cone only;
- laser (`InverseLaserModel`): every cell a beam crosses is free, its end
  point's cell occupied.

The grid updates run as numba kernels (`robotlib.mapping._kernels`);
`inverse_sonar_model` is the same sonar model in plain NumPy for any cells.
Imports the world, the sensing models and the kernels; never plots.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from .._config import readonly
from ..sensing import SonarModel
from ..sensing.laser import LaserModel, laser_poses
from ..world import Grid, World
from . import _kernels

__all__ = [
    "InverseSonarModel",
    "InverseLaserModel",
    "OccupancyGrid",
    "inverse_sonar_model",
    "log_odds",
    "probability",
    "map_sonar",
    "map_laser",
]


def log_odds(p):
    """Return ``log(p / (1 - p))`` of probabilities ``p`` (array or float)."""
    p = np.asarray(p, dtype=float)
    return np.log(p) - np.log1p(-p)


def probability(logodds):
    """Return the probabilities ``1 - 1 / (1 + exp(l))`` of log-odds ``l``."""
    return 1.0 - 1.0 / (1.0 + np.exp(np.asarray(logodds, dtype=float)))


@dataclass(frozen=True)
class InverseSonarModel:
    """The sonar cone's inverse sensor model, in log-odds.

    Attributes
    ----------
    l_occ : float
        Log-odds added to a cell on the arc at the measured range (> 0).
    l_free : float
        Log-odds added to a cell inside the cone nearer than the range (< 0).
    thickness : float
        Depth of the occupied arc, m.
    sigma : float or None
        Weighting across the cone: each increment times
        ``exp(-phi^2 / (2 sigma^2))`` for a cell ``phi`` rad off the axis (an
        echo most likely comes from near the axis); None: uniform.
    max_weight : float
        Weight of the free space of a max-range reading (no echo): 1 frees
        the whole cone, 0 ignores such readings (specular misses pass through
        walls, so trusting them erases walls seen at grazing angles).
    l_min, l_max : float
        Each cell's log-odds is clamped to this range.
    """

    l_occ: float = 0.9
    l_free: float = -0.35
    thickness: float = 0.1
    sigma: float | None = 0.15
    max_weight: float = 0.3
    l_min: float = -6.0
    l_max: float = 6.0

    def __post_init__(self):
        if not (self.l_occ >= 0 >= self.l_free):
            raise ValueError("need l_occ >= 0 >= l_free")
        if self.thickness <= 0:
            raise ValueError("thickness must be positive")
        if self.sigma is not None and self.sigma <= 0:
            raise ValueError("sigma must be positive or None")
        if not 0 <= self.max_weight <= 1:
            raise ValueError("max_weight must be in [0, 1]")
        if not self.l_min < 0 < self.l_max:
            raise ValueError("need l_min < 0 < l_max")


@dataclass(frozen=True)
class InverseLaserModel:
    """The laser beam's inverse sensor model, in log-odds.

    Attributes
    ----------
    l_occ : float
        Added to the cell of a beam's end point (> 0).
    l_free : float
        Added to each cell the beam crosses before it (< 0).
    l_min, l_max : float
        Clamp limits.
    """

    l_occ: float = 0.9
    l_free: float = -0.4
    l_min: float = -6.0
    l_max: float = 6.0

    def __post_init__(self):
        if not (self.l_occ >= 0 >= self.l_free):
            raise ValueError("need l_occ >= 0 >= l_free")
        if not self.l_min < 0 < self.l_max:
            raise ValueError("need l_min < 0 < l_max")


def inverse_sonar_model(
    cells,
    sensor_pose,
    z: float,
    sonar: SonarModel | None = None,
    model: InverseSonarModel | None = None,
) -> np.ndarray:
    """Log-odds increments one sonar reading gives to cells (plain NumPy).

    Parameters
    ----------
    cells : array_like, shape (..., 2)
        Cell centres, m.
    sensor_pose : array_like, shape (3,)
        The sonar's pose in the world ``(x, y, heading)``, m and rad.
    z : float
        The reading, m (``sonar.max_range``: no echo).
    sonar : SonarModel, optional
        Its cone and range (default: a Pioneer 3-DX's).
    model : InverseSonarModel, optional
        The log-odds and weighting.

    Returns
    -------
    numpy.ndarray, shape (...)
        The increment per cell: ``l_free`` (times the weights) inside the
        cone nearer than ``z - thickness / 2``, ``l_occ`` within
        ``thickness / 2`` of ``z``, 0 elsewhere.
    """
    sonar = SonarModel() if sonar is None else sonar
    model = InverseSonarModel() if model is None else model
    c = np.asarray(cells, dtype=float)
    sx, sy, sth = (float(v) for v in sensor_pose)
    dx, dy = c[..., 0] - sx, c[..., 1] - sy
    along = dx * np.cos(sth) + dy * np.sin(sth)
    perp = dy * np.cos(sth) - dx * np.sin(sth)
    d = np.hypot(dx, dy)
    half = 0.5 * model.thickness
    echo = z < sonar.max_range
    reach = z + half if echo else sonar.max_range
    inside = (along > 0) & (np.abs(perp) <= along * np.tan(sonar.cone / 2))
    inside &= d * d <= reach * reach
    w = np.full(d.shape, 1.0 if echo else model.max_weight)
    if model.sigma is not None:
        phi = np.arctan2(perp, along)
        w = w * np.exp(-(phi**2) / (2 * model.sigma**2))
    occ = echo & (d >= z - half)
    out = np.where(occ, model.l_occ, model.l_free) * w
    return np.where(inside, out, 0.0)


_SONAR = SonarModel()
_SONAR_MODEL = InverseSonarModel()


@lru_cache(maxsize=64)
def cone_weights(half_cone: float, sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """Return the sonar cone's weights for the kernels, kept per cone and sigma.

    Returns ``(poly, table)`` of `robotlib.mapping._kernels.cone_weights`
    (shared between calls: not to be written); ``sigma`` rad, 0 for none.
    """
    return _kernels.cone_weights(float(half_cone), float(sigma))


class OccupancyGrid:
    """A log-odds occupancy grid (float32), updated reading by reading.

    Parameters
    ----------
    shape : tuple of int
        ``(ny, nx)`` cells.
    origin : tuple of float
        Lower-left corner of cell ``[0, 0]``, m.
    resolution : float
        Cell side, m.
    """

    def __init__(self, shape, origin, resolution: float):
        if not resolution > 0:
            raise ValueError("resolution must be positive")
        self.logodds = np.zeros(tuple(int(v) for v in shape), dtype=np.float32)
        self.origin = (float(origin[0]), float(origin[1]))
        self.resolution = float(resolution)

    @classmethod
    def for_world(cls, world: World, resolution: float = 0.05) -> OccupancyGrid:
        """Return an empty grid on the cells of ``world.occupancy_grid(resolution)``."""
        truth = world.occupancy_grid(resolution)
        return cls(truth.shape, truth.origin, resolution)

    @property
    def shape(self) -> tuple[int, int]:
        """``(ny, nx)``."""
        return self.logodds.shape

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """``(xmin, xmax, ymin, ymax)``, m."""
        ny, nx = self.shape
        x0, y0 = self.origin
        return (x0, x0 + nx * self.resolution, y0, y0 + ny * self.resolution)

    def copy(self) -> OccupancyGrid:
        """Return an independent copy."""
        g = OccupancyGrid(self.shape, self.origin, self.resolution)
        g.logodds[:] = self.logodds
        return g

    def probability(self) -> np.ndarray:
        """Occupancy probability per cell, shape (ny, nx)."""
        return probability(self.logodds)

    def occupied(self, threshold: float = 0.0) -> np.ndarray:
        """Cells whose log-odds exceed ``threshold`` (bool, (ny, nx))."""
        return self.logodds > threshold

    def to_grid(self, threshold: float = 0.0) -> Grid:
        """Return the occupied cells as a `robotlib.world.Grid` (planners, casters)."""
        return Grid(self.occupied(threshold), self.origin, self.resolution)

    def update_sonar(
        self,
        pose,
        ranges,
        sonar: SonarModel | None = None,
        model: InverseSonarModel | None = None,
    ) -> None:
        """Add one sonar ring reading taken at robot ``pose`` (3,), m and rad.

        ``ranges`` (S,) are the readings, m; ``sonar`` gives the sensor poses
        and cone (default: a Pioneer 3-DX's eight front sonars).
        """
        sonar = _SONAR if sonar is None else sonar
        model = _SONAR_MODEL if model is None else model
        p = np.ascontiguousarray(pose, dtype=np.float64).reshape(3)
        z = np.ascontiguousarray(ranges, dtype=np.float64).reshape(-1)
        if len(z) != len(sonar.sensors):
            raise ValueError(f"expected {len(sonar.sensors)} ranges, got {len(z)}")
        half = sonar.cone / 2
        sigma = model.sigma or 0.0
        _kernels._scan_update(
            self.logodds, *self.origin, self.resolution, p, readonly(sonar.sensors), z,
            half, sonar.max_range, model.thickness, model.l_occ, model.l_free,
            sigma, model.max_weight, model.l_min, model.l_max,
            *cone_weights(half, sigma),
        )  # fmt: skip

    def update_laser(
        self,
        pose,
        ranges,
        laser: LaserModel | None = None,
        model: InverseLaserModel | None = None,
    ) -> None:
        """Add one laser scan (n_beams,) taken at robot ``pose`` (3,)."""
        laser = LaserModel() if laser is None else laser
        model = InverseLaserModel() if model is None else model
        z = np.ascontiguousarray(ranges, dtype=np.float64).reshape(-1)
        if len(z) != laser.n_beams:
            raise ValueError(f"expected {laser.n_beams} ranges, got {len(z)}")
        lp = laser_poses(pose, laser)[0]
        _kernels.laser_scan_update(
            self.logodds, *self.origin, self.resolution, lp,
            np.ascontiguousarray(laser.angles), z, laser.max_range, model.l_occ,
            model.l_free, model.l_min, model.l_max,
        )  # fmt: skip


def _check_log(poses, scans, width):
    p = np.asarray(poses, dtype=float)
    z = np.asarray(scans, dtype=float)
    if p.ndim != 2 or p.shape[1] != 3 or z.ndim != 2 or len(z) != len(p):
        raise ValueError(f"need poses (T, 3) and scans (T, {width})")
    return p, z


def map_sonar(
    world: World,
    poses,
    scans,
    resolution: float = 0.1,
    sonar: SonarModel | None = None,
    model: InverseSonarModel | None = None,
    walls=None,
) -> OccupancyGrid:
    """Build a sonar map from poses (T, 3) and their ring readings (T, S).

    ``world`` only gives the grid's cells (its bounds); the poses may be the
    true ones or odometry's. ``walls`` (sonar indexes, optional): only these
    sonars' echoes mark their arcs occupied, the others' readings free their
    cones only (as `robotlib.mapping.GridFastSLAM`'s ``sonar_walls``; None:
    all mark).
    """
    sonar = SonarModel() if sonar is None else sonar
    model = _SONAR_MODEL if model is None else model
    p, z = _check_log(poses, scans, len(sonar.sensors))
    grid = OccupancyGrid.for_world(world, resolution)
    if walls is None:
        groups = [(slice(None), sonar, model)]
    else:
        mark = np.zeros(len(sonar.sensors), dtype=bool)
        mark[np.asarray(walls, dtype=np.int64)] = True
        free_only = replace(model, l_occ=0.0)
        groups = [
            (k, replace(sonar, sensors=sonar.sensors[k]), m)
            for k, m in (
                (np.flatnonzero(mark), model),
                (np.flatnonzero(~mark), free_only),
            )
            if len(k)
        ]
    for t in range(len(p)):
        for k, s, m in groups:
            grid.update_sonar(p[t], z[t][k], s, m)
    return grid


def map_laser(
    world: World,
    poses,
    scans,
    resolution: float = 0.05,
    laser: LaserModel | None = None,
    model: InverseLaserModel | None = None,
) -> OccupancyGrid:
    """Build a laser map from poses (T, 3) and their scans (T, n_beams)."""
    laser = LaserModel() if laser is None else laser
    p, z = _check_log(poses, scans, laser.n_beams)
    grid = OccupancyGrid.for_world(world, resolution)
    for t in range(len(p)):
        grid.update_laser(p[t], z[t], laser, model)
    return grid
