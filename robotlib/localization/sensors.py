"""Sensor models for MCL: the paper's innovation, the beam model, the likelihood field.

A sensor model is any object with ``log_likelihood(particles, z)``: the
log-likelihood of the scan ``z`` (S,) for each particle (N, 3), an (N,)
array. `MCL` turns it into weights. That one method, written in NumPy, is
all a new model needs (see ARCHITECTURE.md, "Adding a sensor model").

The models here that compare readings with expected ones (the paper's and
the beam model) get those readings in one of two ways:

- exact (``fast=False``): every particle casts its sonar cones against the
  walls, as the simulator does (`robotlib.localization.cones.expected_readings`);
- fast (``fast=True``): a `robotlib.localization.cones.ConeTable`, built
  once per world, holds the reading from every grid cell in every direction
  bin; a particle's reading is looked up. The error is the quantisation's
  (half a cell in position, half a bin in direction).

With a cone table a model may also offer a fused kernel
(`robotlib.localization._kernels.steps`) that moves, weighs and normalises
every particle in one pass: ``fused`` names the kernels (serial, threaded)
and ``fused_arguments(z)`` gives their model-specific arguments. The kernel
computes what `log_likelihood` computes, and the tests hold it to that.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..sensing import SonarModel
from ._kernels import steps
from .cones import cone_table, expected_readings
from .motion import _particles

__all__ = [
    "BeamParameters",
    "BeamSensorModel",
    "LikelihoodFieldSensorModel",
    "PaperSensorModel",
    "innovation_loglik",
]


def checked_scan(z, n_sensors: int) -> np.ndarray:
    """Return ``z`` as a float array (S,) of positive finite readings, or raise."""
    z = np.ascontiguousarray(z, dtype=np.float64)
    if z.shape != (n_sensors,):
        raise ValueError(f"z must have shape ({n_sensors},), got {z.shape}")
    if not (np.all(z > 0) and np.all(np.isfinite(z))):
        raise ValueError("sonar readings must be positive and finite")
    return z


def innovation_loglik(z, zhat, n: int | None = None) -> np.ndarray:
    """Log of the paper's innovation weight, per particle (before normalising).

    ``log(exp(-d_j) + 1/n)`` with ``d_j = mean_i |(z_i - zhat_ji) / z_i|``.

    Parameters
    ----------
    z : array_like, shape (S,)
        The robot's readings, m (positive).
    zhat : array_like, shape (N, S)
        Expected readings of each particle, m.
    n : int, optional
        The ``N`` of the ``1/N`` term (default: ``len(zhat)``).

    Returns
    -------
    numpy.ndarray, shape (N,)
    """
    zhat = np.asarray(zhat, dtype=np.float64)
    if zhat.ndim != 2:
        raise ValueError(f"zhat must have shape (N, S), got {zhat.shape}")
    z = checked_scan(z, zhat.shape[1])
    d = np.mean(np.abs((z - zhat) / z), axis=1)
    return np.log(np.exp(-d) + 1.0 / (len(zhat) if n is None else n))


class _ExpectedRangeModel:
    """What the models comparing readings with expected ones share."""

    fused = None
    """The fused step's kernels ``(serial, threaded)``, or None."""

    def __init__(self, world, sonar, fast, resolution, n_bins):
        self.world = world
        self.sonar = SonarModel() if sonar is None else sonar
        self.fast = bool(fast)
        self.table = cone_table(world, self.sonar, resolution, n_bins) if fast else None

    def expected(self, particles) -> np.ndarray:
        """Return the expected readings (N, S) of particles (N, 3), m."""
        return expected_readings(self.world, particles, self.sonar, self.table)

    def checked_scan(self, z) -> np.ndarray:
        """Return ``z`` as a float array of shape (S,), or raise ``ValueError``."""
        return checked_scan(z, len(self.sonar.sensors))

    def log_likelihood(self, particles, z) -> np.ndarray:
        """Per-particle log-likelihood (N,) of readings ``z`` (S,), m."""
        z = self.checked_scan(z)
        return self.scan_log_likelihood(z, self.expected(_particles(particles)))

    def _table_arguments(self) -> tuple:
        """Return the cone table's arguments of the fused kernels."""
        t = self.table
        return (
            self.sonar.sensors, t.table, t.origin[0], t.origin[1], 1.0 / t.resolution
        )  # fmt: skip


class PaperSensorModel(_ExpectedRangeModel):
    """The paper's innovation weight: ``w_j = exp(-d_j) + 1/N``.

    ``d_j = mean_i |(z_i - zhat_ij) / z_i|``.

    Parameters
    ----------
    world : World
        The map.
    sonar : SonarModel, optional
        The sonar ring used for the expected readings.
    fast : bool
        Look expected readings up in a `ConeTable` instead of casting cones.
    resolution, n_bins
        The table's cell side (m) and direction bins, when ``fast``.
    """

    name = "paper"

    def __init__(self, world, sonar=None, fast=False, resolution=0.05, n_bins=72):
        super().__init__(world, sonar, fast, resolution, n_bins)
        if self.table is not None:
            self.fused = (steps.paper_step, steps.paper_step_parallel)

    def scan_log_likelihood(self, z, zhat) -> np.ndarray:
        """``log w_j`` (N,) from readings ``z`` (S,) and expected ``zhat`` (N, S)."""
        return innovation_loglik(z, zhat)

    def fused_arguments(self, z) -> tuple:
        """Arguments of `steps.paper_step` after the motion's, for scan ``z``."""
        return (*self._table_arguments(), z)


@dataclass(frozen=True)
class BeamParameters:
    """Mixture weights and shapes of the beam model (Thrun, table 6.1).

    Attributes
    ----------
    z_hit, z_short, z_max, z_rand : float
        Mixture weights of the measurement noise, the unexpected short
        readings, the max-range readings and the random readings.
    sigma_hit : float
        Standard deviation of the hit component, m (covers map, pose and
        sonar errors, not only the sensor's noise).
    lambda_short : float
        Rate of the short-reading exponential, 1/m.
    exponent : float
        The scan's log-likelihood is multiplied by this (tempering). The
        product over beams treats them as independent, which overstates the
        evidence of a scan (neighbouring cones see the same walls, and map and
        pose errors are shared): with 1.0 a single scan can leave a handful of
        particles carrying all the weight. Values below 1 soften it.
    """

    z_hit: float = 0.75
    z_short: float = 0.1
    z_max: float = 0.05
    z_rand: float = 0.1
    sigma_hit: float = 0.15
    lambda_short: float = 0.5
    exponent: float = 1.0


_erf = np.vectorize(math.erf, otypes=[float])


class BeamSensorModel(_ExpectedRangeModel):
    """Thrun's beam model: each reading is a mixture around its expected range.

    ``p(z_i | x) = z_hit p_hit + z_short p_short + z_max p_max + z_rand p_rand``
    with ``p_hit`` a Gaussian around the expected range normalised over
    ``[0, max_range]``, ``p_short`` an exponential up to the expected range,
    ``p_max`` a point mass at ``max_range`` and ``p_rand`` uniform; the
    scan's likelihood is the product over sensors (a max-range reading
    scores ``z_max`` alone).

    Parameters
    ----------
    world : World
        The map.
    sonar : SonarModel, optional
        The sonar ring used for the expected readings.
    fast : bool
        Look expected readings up in a `ConeTable`.
    params : BeamParameters, optional
        Mixture parameters.
    resolution, n_bins
        The table's cell side (m) and direction bins, when ``fast``.
    """

    name = "beam"

    def __init__(
        self,
        world,
        sonar=None,
        fast=False,
        params: BeamParameters | None = None,
        resolution=0.05,
        n_bins=72,
    ):
        super().__init__(world, sonar, fast, resolution, n_bins)
        self.params = BeamParameters() if params is None else params
        if self.table is not None:  # normalisers per millimetre of expected range
            zhat = np.arange(int(round(self.sonar.max_range * 1000)) + 1) * 0.001
            self._hit_norm, self._short_norm = self._normalisers(zhat)
            self.fused = (steps.beam_step, steps.beam_step_parallel)

    def _normalisers(self, zhat) -> tuple[np.ndarray, np.ndarray]:
        """``z_hit`` and ``z_short`` times their densities' normalisers at ``zhat``.

        The Gaussian is normalised over ``[0, max_range]``, the exponential
        over ``[0, zhat]``.
        """
        q, max_range = self.params, float(self.sonar.max_range)
        root2 = q.sigma_hit * math.sqrt(2.0)
        mass = 0.5 * (_erf((max_range - zhat) / root2) - _erf(-zhat / root2))
        hit = q.z_hit / (q.sigma_hit * math.sqrt(2.0 * math.pi) * mass)
        with np.errstate(divide="ignore"):
            short = q.z_short * q.lambda_short / -np.expm1(-q.lambda_short * zhat)
        return hit, short

    def scan_log_likelihood(self, z, zhat) -> np.ndarray:
        """Return ``exponent * sum_i log p(z_i | zhat_ji)``, (N,), for z and zhat."""
        q, max_range = self.params, float(self.sonar.max_range)
        hit_norm, short_norm = self._normalisers(zhat)
        p = hit_norm * np.exp(-0.5 * ((z - zhat) / q.sigma_hit) ** 2)
        p += np.where(z <= zhat, short_norm * np.exp(-q.lambda_short * z), 0.0)
        p += q.z_rand / max_range
        p = np.where(z >= max_range - 1e-3, q.z_max, p)
        return q.exponent * np.log(p).sum(axis=1)

    def fused_arguments(self, z) -> tuple:
        """Arguments of `steps.beam_step` after the motion's, for scan ``z``."""
        q, max_range = self.params, float(self.sonar.max_range)
        return (
            *self._table_arguments(), z, np.exp(-q.lambda_short * z),
            self._hit_norm, self._short_norm, 1.0 / q.sigma_hit, q.z_max,
            q.z_rand / max_range, max_range, float(q.exponent),
        )  # fmt: skip


class LikelihoodFieldSensorModel:
    """Thrun's likelihood field: end points scored by their distance to walls.

    Each reading below ``max_range`` puts an end point on its sonar's axis;
    ``p = z_hit N(d; 0, sigma_hit) + z_rand / max_range`` with ``d`` the
    end point's distance to the nearest obstacle; max readings are skipped.
    It ignores the cone and occlusion, so it suits a sonar less than a laser,
    but it needs no ray casting.

    Parameters
    ----------
    world : World
        The map.
    sonar : SonarModel, optional
        Sensor poses and maximum range.
    fast : bool
        Read distances from the world's distance field (a grid) instead of
        measuring them to the segments.
    z_hit, z_rand : float
        Mixture weights.
    sigma_hit : float
        Standard deviation of the end point's distance, m.
    resolution : float
        The distance field's cell side, m, when ``fast``.
    """

    name = "likelihood_field"

    def __init__(
        self,
        world,
        sonar=None,
        fast=False,
        z_hit=0.9,
        z_rand=0.1,
        sigma_hit=0.15,
        resolution=0.05,
    ):
        self.world = world
        self.sonar = SonarModel() if sonar is None else sonar
        self.fast = bool(fast)
        self.z_hit, self.z_rand, self.sigma_hit = z_hit, z_rand, sigma_hit
        self.field = world.distance_field(resolution) if self.fast else None

    def checked_scan(self, z) -> np.ndarray:
        """Return ``z`` as a float array of shape (S,), or raise ``ValueError``."""
        return checked_scan(z, len(self.sonar.sensors))

    def log_likelihood(self, particles, z) -> np.ndarray:
        """Per-particle ``sum_i log p(z_i | x_j)`` for readings ``z`` (S,), m."""
        p = _particles(particles)
        z = self.checked_scan(z)
        s = self.sonar.sensors
        c, si = np.cos(p[:, 2:3]), np.sin(p[:, 2:3])
        heading = p[:, 2:3] + s[:, 2]
        ex = p[:, 0:1] + c * s[:, 0] - si * s[:, 1] + z * np.cos(heading)
        ey = p[:, 1:2] + si * s[:, 0] + c * s[:, 1] + z * np.sin(heading)
        d = self._distance(ex, ey)
        gauss = np.exp(-0.5 * (d / self.sigma_hit) ** 2)
        max_range = float(self.sonar.max_range)
        prob = self.z_hit * gauss / (self.sigma_hit * math.sqrt(2 * math.pi))
        prob += self.z_rand / max_range
        return np.where(z < max_range - 1e-3, np.log(prob), 0.0).sum(axis=1)

    def _distance(self, x, y) -> np.ndarray:
        """Distance (m) from points ``x, y`` (any shape) to the nearest wall."""
        if self.field is not None:  # the distance field's cell; off the map: far
            g = self.field
            ny, nx = g.data.shape
            col = np.floor((x - g.origin[0]) / g.resolution)
            row = np.floor((y - g.origin[1]) / g.resolution)
            inside = (col >= 0) & (col < nx) & (row >= 0) & (row < ny)
            d = np.full(np.shape(x), np.inf)
            d[inside] = g.data[row[inside].astype(np.intp), col[inside].astype(np.intp)]
            return d
        return self.world.distance_to_walls(np.stack([x, y], axis=-1))
