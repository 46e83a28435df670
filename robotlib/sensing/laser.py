"""The SICK LMS-200 laser range finder: beams, noise, and a scan at many poses.

A scan is 181 beams over 180 degrees (one per degree, right to left), each
the exact range to the first wall along the beam (`robotlib.raycast`'s
segment caster) or the grid caster's range on an occupancy grid, plus
Gaussian noise; a beam that hits nothing within ``max_range`` reports
``max_range``. Defaults follow the LMS-200's data sheet in its millimetre
mode (8 m range, 5 mm statistical error, 10 mm resolution) and ARIA's P3-DX
mounting (18 mm ahead of the centre of rotation, facing forward).

Imports the world and this package's casters only: never the simulator,
the robot API or anything above them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .._random import as_rng
from ..world import Grid
from . import _kernels
from .raycast import _poses, _segments, grid_field

__all__ = ["LaserModel", "laser_poses", "expected_laser", "simulate_laser"]


@dataclass(frozen=True)
class LaserModel:
    """Parameters of a planar laser range finder (default: a SICK LMS-200).

    Attributes
    ----------
    n_beams : int
        Beams per scan (181: one per degree).
    fov : float
        Angle from the first beam to the last, rad (pi: 180 degrees).
    max_range : float
        Largest reported range; also "no return", m (8 m: the LMS-200's
        millimetre mode).
    noise_std : float
        Standard deviation of the range noise, m (5 mm in the data sheet).
    resolution : float
        Ranges are rounded to this step, m (10 mm); 0: no rounding.
    mount : tuple of float
        Laser pose in the robot frame ``(x, y, heading)``, m and rad (ARIA's
        P3-DX ``LaserX 18``).
    """

    n_beams: int = 181
    fov: float = math.pi
    max_range: float = 8.0
    noise_std: float = 0.005
    resolution: float = 0.01
    mount: tuple[float, float, float] = (0.018, 0.0, 0.0)

    def __post_init__(self):
        if self.n_beams < 1:
            raise ValueError("n_beams must be at least 1")
        if not 0.0 <= self.fov <= 2.0 * math.pi:
            raise ValueError("fov must be in [0, 2 pi] rad")
        if not self.max_range > 0:
            raise ValueError("max_range must be positive")
        if self.noise_std < 0 or self.resolution < 0:
            raise ValueError("noise_std and resolution must be non-negative")
        if len(self.mount) != 3:
            raise ValueError("mount must be (x, y, heading)")

    @property
    def angles(self) -> np.ndarray:
        """Beam directions in the laser frame, shape (n_beams,), rad (right to left)."""
        if self.n_beams == 1:
            return np.zeros(1)
        return np.linspace(-self.fov / 2, self.fov / 2, self.n_beams)

    def ideal(self) -> LaserModel:
        """Return the same laser with no noise and no rounding."""
        return replace(self, noise_std=0.0, resolution=0.0)

    def subsample(self, step: int) -> LaserModel:
        """Return a laser with every ``step``-th beam (same fov, fewer beams)."""
        if step < 1 or (self.n_beams - 1) % step:
            raise ValueError(f"step must divide n_beams - 1 = {self.n_beams - 1}")
        return replace(self, n_beams=(self.n_beams - 1) // step + 1)


def laser_poses(poses, model: LaserModel | None = None) -> np.ndarray:
    """Poses of the laser itself for robot poses.

    Parameters
    ----------
    poses : array_like, shape (3,) or (K, 3)
        Robot poses ``(x, y, theta)``, m and rad.
    model : LaserModel, optional
        The laser and its mounting.

    Returns
    -------
    numpy.ndarray, shape (K, 3)
        Laser origins and headings, m and rad.
    """
    model = LaserModel() if model is None else model
    p = _poses(poses)
    mx, my, mth = model.mount
    c, s = np.cos(p[:, 2]), np.sin(p[:, 2])
    out = np.empty_like(p)
    out[:, 0] = p[:, 0] + c * mx - s * my
    out[:, 1] = p[:, 1] + s * mx + c * my
    out[:, 2] = p[:, 2] + mth
    return out


def expected_laser(walls, poses, model: LaserModel | None = None) -> np.ndarray:
    """Noise-free laser ranges.

    Parameters
    ----------
    walls : World, array_like of shape (M, 4), or Grid
        A world or its obstacle segments (exact casting), or an occupancy
        `robotlib.world.Grid` (grid casting, to the first occupied cell).
    poses : array_like, shape (3,) or (K, 3)
        Robot poses, m and rad.
    model : LaserModel, optional
        The laser (default: an LMS-200 on a P3-DX).

    Returns
    -------
    numpy.ndarray, shape (K, n_beams)
        Ranges in m, in ``[0, max_range]`` (``max_range``: no return).
    """
    model = LaserModel() if model is None else model
    lp = np.ascontiguousarray(laser_poses(poses, model))
    a = np.ascontiguousarray(model.angles)
    out = np.empty((len(lp), len(a)))
    if isinstance(walls, Grid):
        field = grid_field(walls)
        x0, y0 = walls.origin
        _kernels.cast_grid(
            lp, a, float(model.max_range), field, x0, y0, walls.resolution, out
        )
    else:
        cast = _kernels.cast_segments if len(lp) >= 8 else _kernels.cast_segments_serial
        cast(lp, a, float(model.max_range), _segments(walls), out)
    return out


def simulate_laser(
    walls,
    poses,
    model: LaserModel | None = None,
    rng: np.random.Generator | int | None = None,
) -> np.ndarray:
    """Noisy laser scans as the LMS-200 would report them.

    Parameters
    ----------
    walls : World, array_like of shape (M, 4), or Grid
        As in `expected_laser`.
    poses : array_like, shape (3,) or (K, 3)
        Robot poses, m and rad.
    model : LaserModel, optional
        The laser and its noise.
    rng : numpy.random.Generator, int or None
        Randomness; the same seed gives the same scans, bit for bit.

    Returns
    -------
    numpy.ndarray, shape (K, n_beams)
        Ranges in m, in ``[0, max_range]``; beams with no return report
        ``max_range`` exactly.
    """
    model = LaserModel() if model is None else model
    rng = as_rng(rng)
    z = expected_laser(walls, poses, model)
    noise = rng.standard_normal(z.shape)
    hit = z < model.max_range
    out = z + model.noise_std * noise
    if model.resolution > 0:
        out = np.round(out / model.resolution) * model.resolution
    out = np.clip(out, 0.0, model.max_range)
    return np.where(hit, out, model.max_range)
