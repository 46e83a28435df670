"""The paper's MCL (Frontoni et al. 2006, section III) as small procedural pieces.

One step of the paper's filter, with these functions::

    particles = predict(particles, odo_prev, odo_now, alphas, rng)
    zhat = expected(world, particles)              # (N, 8) simulated sonar
    w = innovation_weights(z, zhat)                # exp(-d_j) + 1/N, normalised
    pose = estimate(particles, w)                  # weighted / circular mean
    idx = resample_indexes(w, rng)                 # (1) selection with replacement
    particles = particles[idx]
    n = resize(len(particles), dispersion_index(particles, world.size), lam, floor)
    particles = particles[:n]                      # (2) resize (draws are i.i.d.)
    particles, w = check_particles(world, particles, np.full(n, 1 / n), rng)  # (3)

Each piece is what a lab asks students to write; `robotlib.localization.MCL`
composes the same pieces (`MCL.paper`).
"""

from __future__ import annotations

import math

import numpy as np

from .._random import as_rng
from ..sensing import SonarModel
from ..world import World
from .cones import ConeTable, expected_readings
from .motion import _particles, sample_motion_odometry
from .resampling import _cloud, multinomial_resample
from .sensors import innovation_loglik

__all__ = [
    "ADMISSIBLE_RADIUS",
    "REGEN_WEIGHT",
    "RESIZE_FLOOR",
    "uniform_particles",
    "predict",
    "expected",
    "innovation_weights",
    "resample_indexes",
    "dispersion_index",
    "resize",
    "admissible",
    "check_particles",
    "on_grid",
    "estimate",
]

RESIZE_FLOOR = 50
"""Default smallest population the resize may leave (the paper gives none)."""
REGEN_WEIGHT = 0.1
"""Default weight of a regenerated particle, relative to the mean weight."""
ADMISSIBLE_RADIUS = 0.2
"""Default clearance a particle needs from every wall to be admissible, m.

A little less than the robot's 0.25 m radius, so that odometry noise and the
grid's 5 cm cells do not evict particles at the true pose next to a wall.
"""


def uniform_particles(
    world: World,
    n: int,
    rng: np.random.Generator | int | None = None,
    radius: float = ADMISSIBLE_RADIUS,
    resolution: float = 0.05,
) -> tuple[np.ndarray, np.ndarray]:
    """Draw ``n`` particles uniformly over the admissible area, weights ``1/n``.

    Parameters
    ----------
    world : World
        The map.
    n : int
        Number of particles.
    rng : numpy.random.Generator, int or None
        Randomness.
    radius, resolution : float
        Admissible area: cells of this side (m) clear of walls by ``radius``
        (m) and connected to the start (`World.free_space`).

    Returns
    -------
    particles : numpy.ndarray, shape (n, 3)
    weights : numpy.ndarray, shape (n,)
    """
    particles = world.sample_free_poses(int(n), as_rng(rng), resolution, radius)
    return particles, np.full(int(n), 1.0 / n)


def predict(
    particles,
    odo_prev,
    odo_now,
    alphas=(0.002, 0.005, 0.01, 0.0005),
    rng: np.random.Generator | int | None = None,
) -> np.ndarray:
    """Move particles by the odometry increment plus motion noise.

    See `robotlib.localization.motion.sample_motion_odometry`.
    """
    return sample_motion_odometry(particles, odo_prev, odo_now, alphas, rng)


def expected(
    world: World,
    particles,
    sonar: SonarModel | None = None,
    table: ConeTable | None = None,
) -> np.ndarray:
    """Simulate the sonar readings ``zhat`` (N, S) from each particle's pose, m.

    See `robotlib.localization.sensors.expected_readings`.
    """
    return expected_readings(world, particles, sonar, table)


def innovation_weights(z, zhat) -> np.ndarray:
    """Compute the paper's weights: ``w_j = exp(-d_j) + 1/N``, normalised to sum 1.

    ``d_j = mean_i |(z_i - zhat_ij) / z_i|``: the mean relative innovation
    of particle ``j``'s simulated readings.

    Parameters
    ----------
    z : array_like, shape (S,)
        The robot's sonar readings, m (positive).
    zhat : array_like, shape (N, S)
        Each particle's expected readings, m.

    Returns
    -------
    numpy.ndarray, shape (N,)
    """
    w = np.exp(innovation_loglik(z, zhat))
    return w / w.sum()


def resample_indexes(
    weights, rng: np.random.Generator | int | None = None, n: int | None = None
) -> np.ndarray:
    """Step (1): select ``n`` particles with replacement by weight (multinomial)."""
    return multinomial_resample(weights, rng, n)


def dispersion_index(particles, map_size) -> float:
    """Compute the paper's ``Ip = sqrt(var_x + var_y) / sqrt(xMap^2 + yMap^2)``.

    Parameters
    ----------
    particles : array_like, shape (N, 3)
        Poses (unweighted, e.g. just resampled), m.
    map_size : tuple of float
        ``(xMap, yMap)``: the map's width and height, m (`World.size`).

    Returns
    -------
    float
        Dimensionless, 0 for coincident particles.
    """
    p = _particles(particles)
    spread = math.sqrt(p[:, 0].var() + p[:, 1].var())
    return spread / math.hypot(*map_size)


def resize(n: int, ip: float, lam: float, floor: int = RESIZE_FLOOR) -> int:
    """Step (2): ``N = int(N * exp(-lambda * Ip))``, never below ``floor``.

    Parameters
    ----------
    n : int
        Current particle count.
    ip : float
        Dispersion index (`dispersion_index`).
    lam : float
        The paper's lambda (0: no resize).
    floor : int
        Smallest count returned (also never above ``n``).

    Returns
    -------
    int
    """
    return min(int(n), max(int(floor), int(n * math.exp(-lam * ip))))


def admissible(
    world: World,
    particles,
    radius: float = ADMISSIBLE_RADIUS,
    resolution: float = 0.05,
) -> np.ndarray:
    """Test whether each particle lies on the admissible area (`World.free_space`).

    Returns
    -------
    numpy.ndarray of bool, shape (N,)
    """
    p = _particles(particles)
    return on_grid(world.free_space(resolution, radius), p)


def on_grid(grid, particles: np.ndarray) -> np.ndarray:
    """Whether each particle (N, 3) lies on a true cell of a boolean grid, (N,).

    ``grid`` is a `robotlib.world.grid.Grid` (``data`` (ny, nx) bool, its
    ``origin`` and ``resolution``); particles off the grid are not on it.
    """
    ny, nx = grid.data.shape
    col = np.floor((particles[:, 0] - grid.origin[0]) / grid.resolution)
    row = np.floor((particles[:, 1] - grid.origin[1]) / grid.resolution)
    inside = (col >= 0) & (col < nx) & (row >= 0) & (row < ny)
    ok = np.zeros(len(particles), dtype=bool)
    ok[inside] = grid.data[row[inside].astype(np.intp), col[inside].astype(np.intp)]
    return ok


def check_particles(
    world: World,
    particles,
    weights,
    rng: np.random.Generator | int | None = None,
    regen_weight: float = REGEN_WEIGHT,
    radius: float = ADMISSIBLE_RADIUS,
    resolution: float = 0.05,
) -> tuple[np.ndarray, np.ndarray, int]:
    """Step (3): replace particles outside the admissible area by random ones.

    Each particle off the admissible area is dropped and a new one drawn
    uniformly over it, with weight ``regen_weight`` times the mean weight;
    then the weights are normalised.

    Parameters
    ----------
    world : World
        The map.
    particles : array_like, shape (N, 3)
        Poses, m and rad.
    weights : array_like, shape (N,)
        Their weights.
    rng : numpy.random.Generator, int or None
        Draws the new particles.
    regen_weight : float
        Relative weight of a regenerated particle (the paper's "small
        weight").
    radius, resolution : float
        The admissible area, as in `admissible`.

    Returns
    -------
    particles : numpy.ndarray, shape (N, 3)
    weights : numpy.ndarray, shape (N,)
    n_regenerated : int
    """
    p, w = (a.copy() for a in _cloud(particles, weights))
    bad = ~admissible(world, p, radius, resolution)
    k = int(bad.sum())
    if k:
        p[bad] = world.sample_free_poses(k, as_rng(rng), resolution, radius)
        w[bad] = regen_weight * w.mean()
    return p, w / w.sum(), k


def estimate(particles, weights) -> np.ndarray:
    """Weighted mean pose; the heading is the weighted circular mean.

    Parameters
    ----------
    particles : array_like, shape (N, 3)
        Poses, m and rad.
    weights : array_like, shape (N,)
        Weights (need not be normalised).

    Returns
    -------
    numpy.ndarray, shape (3,)
        ``(x, y, theta)``, m and rad.
    """
    p, w = _cloud(particles, weights)
    w = w / w.sum()
    heading = math.atan2(w @ np.sin(p[:, 2]), w @ np.cos(p[:, 2]))
    return np.array([w @ p[:, 0], w @ p[:, 1], heading])
