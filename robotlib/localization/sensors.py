"""Sensor models for MCL: the paper's innovation, the beam model, the likelihood field.

Each model gives a log-likelihood per particle for one sonar scan
(`log_likelihood(particles, z)`), which `MCL` turns into weights. Models
that compare against expected readings (the paper's and the beam model)
compute them in one of two ways:

- exact (``fast=False``): every particle casts its sonar cones against the
  walls as `robotlib.sensing._kernels.sonar_cone` does, the simulator's own model
  (the same numbers; each cone casts only the rays that can lower its echo,
  against the walls they may reach: `_kernels.exact.cone_echo_pruned`; cast
  and weighed in one kernel, `_kernels.exact_models`);
- fast (``fast=True``): a `ConeTable` precomputed once per world holds, per
  grid cell and per direction bin, the cone range from the cell's centre, in
  millimetres; a particle's reading is looked up at its sensor's cell and
  nearest direction. The error is that of the quantisation (half a cell in
  position, half a bin in direction).

The likelihood field's exact path measures end-point distances to the
segments; its fast path reads `robotlib.world.World.distance_field`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..sensing import SonarModel
from . import _kernels, stepping
from ._kernels import chunked, exact_models
from .cones import EXACT_PARALLEL_MIN, cone_table, exact_arguments, expected_readings
from .motion import PARALLEL_MIN, _particles
from .stepping import _NONE_P, _NONE_W, _outputs, _small_outputs

__all__ = [
    "innovation_loglik",
    "PaperSensorModel",
    "BeamSensorModel",
    "LikelihoodFieldSensorModel",
]


def _scan(z, n_sensors: int) -> np.ndarray:
    z = _shaped(z, n_sensors)
    r = z.tolist()  # quicker than NumPy for a few; a NaN makes the sum NaN
    if r and not (min(r) > 0.0 and (total := sum(r)) == total):
        raise ValueError(_NOT_POSITIVE)
    return z


def _shaped(z, n_sensors: int) -> np.ndarray:
    """`_scan` but for the values: ``z`` as a float array (S,), or ``ValueError``."""
    if not (type(z) is np.ndarray and z.dtype is _F64 and z.flags.c_contiguous):
        z = np.ascontiguousarray(z, dtype=np.float64)
    if z.shape != (n_sensors,):
        raise ValueError(f"z must have shape ({n_sensors},), got {z.shape}")
    return z


_NOT_POSITIVE = "sonar readings must be positive"


_F64 = np.dtype(np.float64)


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
    zhat = np.ascontiguousarray(zhat, dtype=np.float64)
    if zhat.ndim != 2:
        raise ValueError(f"zhat must have shape (N, S), got {zhat.shape}")
    z = _scan(z, zhat.shape[1])
    out = np.empty(len(zhat))
    _kernels.paper_loglik(z, zhat, float(len(zhat) if n is None else n), out)
    return out


_NO_WORDS = np.zeros(4, dtype=np.uint64)  # no PCG64 state: the caller drew


class _ExpectedModel:
    """Shared part of the models that compare with expected readings."""

    def __init__(self, world, sonar, fast, resolution, n_bins):
        self.world = world
        self.sonar = SonarModel() if sonar is None else sonar
        self.fast = bool(fast)
        self.table = cone_table(world, self.sonar, resolution, n_bins) if fast else None
        self._const = None

    def expected(self, particles) -> np.ndarray:
        """Return expected readings (N, S) of particles (N, 3), m."""
        return expected_readings(self.world, particles, self.sonar, self.table)

    def checked_scan(self, z) -> np.ndarray:
        """Return ``z`` as a float array of shape (S,), or raise ``ValueError``."""
        return _scan(z, len(self.sonar.sensors))

    def _shaped_scan(self, z) -> np.ndarray:
        """`checked_scan` but for the values, which `_small`'s kernel checks."""
        return _shaped(z, len(self.sonar.sensors))

    def _where(self):
        t = self.table
        return t.table, (t.origin[0], t.origin[1], 1.0 / t.resolution)

    def _run(self, particles, weights, motion, noise, key, z, scratch, u,
             checked=False, words=None):  # fmt: skip
        """Move, weigh, estimate and (``u >= 0``) resample: `MCL.step`'s fused call.

        ``noise`` (N, 3) holds the motion noise, or with ``key`` receives it
        (`stepping.run_step`); ``u`` is the systematic resampling's draw or
        -1; ``checked``: ``z`` is `checked_scan`'s already. With ``words``
        (below `PARALLEL_MIN` particles: the filter's PCG64 state,
        `motion.pcg64_words`) the call draws the noise into ``noise`` and,
        when ``u >= 0``, ``u`` itself, as the generator would. Returns
        ``(out_p, out_w, log_mean, ess, est, new_p, new_w)``: moved
        particles and their weights, and the resampled set (None without
        ``u``).
        """
        if not checked:
            z = _scan(z, len(self.sonar.sensors))
        n = len(particles)
        if self.table is not None and n < PARALLEL_MIN:  # one serial call
            return self._small(particles, weights, motion, noise, z, u, scratch, words)
        if u >= 0.0:
            new = (np.empty((n, 3)), np.empty(n))
        else:
            new = (_NONE_P, _NONE_W)
        if self.table is None:  # the exact path: one call, threaded from 64
            return self._exact_run(
                particles, weights, motion, noise, z, scratch, u, new, words
            )
        out_p, out_w, cs, mm = _outputs(scratch, n, len(z))
        out = (out_p, out_w, cs, mm, *new)
        t = self.table
        where = (float(t.origin[0]), float(t.origin[1]), 1.0 / t.resolution)
        prm, skip, lut = self._large(z, motion, where, n)
        log_mean, ess, est = stepping.run_step(
            self.name, particles, weights, prm, noise, key, self.sonar.sensors,
            skip, t.table, lut, out, u,
        )  # fmt: skip
        got = (None, None) if u < 0.0 else new
        return (out_p, out_w, log_mean, ess, est, *got)

    def _exact_run(self, particles, weights, motion, noise, z, scratch, u, new,
                   words=None):  # fmt: skip
        """`_run` on the exact path: `exact_models.exact_step`.

        The model's own arguments come from its ``_exact_model(n)``: ``(beam,
        z_hit, z_short, z_max, z_rand, sigma, lam_short, exponent, n_weight)``.
        """
        n = len(particles)
        if scratch is None:
            out_p, out_w, cs = np.empty((n, 3)), np.empty(n), np.empty((n, 2))
            zhat = np.empty((n, len(z)))
        else:
            out_p = scratch.take("particles", (n, 3))
            out_w = scratch.take("weights", (n,))
            cs = scratch.take("cs", (n, 2))
            zhat = scratch.take("zhat", (n, len(z)))
        est = np.empty(3)
        kernel = (
            exact_models.exact_step_parallel
            if n >= EXACT_PARALLEL_MIN
            else exact_models.exact_step
        )
        args = exact_arguments(self.world, self.sonar)
        log_mean, ess = kernel(
            _NO_WORDS if words is None else words, words is not None, particles,
            weights, noise, *motion, *args, z, *self._exact_model(n), u, out_p, out_w,
            *new, est, cs, zhat,
        )  # fmt: skip
        got = (None, None) if u < 0.0 else new
        return (out_p, out_w, log_mean, ess, est, *got)

    def _consts(self, key=None) -> tuple:
        """``(sensors, table, where, extra)`` of the fused step, kept while the same.

        ``where``: the table's ``(x0, y0, 1 / resolution)``; ``extra``: the
        model's scalars (`_extra`) for ``key`` (its parameters object).
        """
        t, sonar = self.table, self.sonar
        c = self._const
        if (
            c is None or c[0] is not t or c[1] is not sonar or c[2] is not key
            or c[3] is not sonar.sensors
        ):  # fmt: skip
            where = (float(t.origin[0]), float(t.origin[1]), 1.0 / t.resolution)
            c = self._const = (t, sonar, key, sonar.sensors, t.table, where,
                               self._extra(key))  # fmt: skip
        return c[3:]

    def _extra(self, key) -> tuple:
        return ()


class PaperSensorModel(_ExpectedModel):
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

    def log_likelihood(self, particles, z) -> np.ndarray:
        """Per-particle ``log w_j`` for readings ``z`` (S,), m."""
        if self.table is None:  # cast and weigh in one kernel (the same numbers)
            p = _particles(particles)
            z = _scan(z, len(self.sonar.sensors))
            out = np.empty(len(p))
            kernel = (
                exact_models.exact_paper_parallel
                if len(p) >= EXACT_PARALLEL_MIN
                else exact_models.exact_paper
            )
            kernel(p, *exact_arguments(self.world, self.sonar),
                   np.empty((len(p), len(z))), z, float(len(p)), out)  # fmt: skip
            return out
        p = _particles(particles)
        z = _scan(z, len(self.sonar.sensors))
        out = np.empty(len(p))
        t = self.table
        kernel = (
            _kernels.paper_table_loglik_parallel
            if len(p) >= PARALLEL_MIN
            else _kernels.paper_table_loglik
        )
        kernel(
            p,
            self.sonar.sensors,
            t.table,
            t.origin[0],
            t.origin[1],
            1.0 / t.resolution,
            z,
            1.0 / len(p),
            out,
        )
        return out

    def _step(self, particles, weights, motion, normals, z, scratch=None):
        """Move, weigh, estimate in one kernel (see `MCL.step`).

        ``scratch`` (a `robotlib.localization.motion.Scratch`) lends the
        output and work arrays; None makes new ones. Returns ``(out_p, out_w,
        log_mean, ess, est)``.
        """
        return self._run(particles, weights, motion, normals, None, z, scratch, -1.0)[
            :5
        ]

    def _small(self, particles, weights, motion, noise, z, u, scratch, words=None):
        """`_run` below `PARALLEL_MIN` particles: `chunked.paper_small`, one call.

        The call checks the readings' values before its draws: ``ValueError``
        for one not positive, nothing drawn or written.
        """
        out_p, out_w, new_p, new_w, est = _small_outputs(scratch, len(particles), u)
        sensors, table, where, _ = self._consts()
        log_mean, ess = chunked.paper_small(
            _NO_WORDS if words is None else words, words is not None,
            particles, weights, noise, sensors, table, z, *motion, *where,
            1.0 / len(particles), u, out_p, out_w, new_p, new_w, est,
        )  # fmt: skip
        if ess < 0.0:  # a reading not positive: refused before any draw or write
            raise ValueError(_NOT_POSITIVE)
        if u < 0.0:
            return out_p, out_w, log_mean, ess, est, None, None
        return out_p, out_w, log_mean, ess, est, new_p, new_w

    def _exact_model(self, n: int) -> tuple:
        return (False, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, float(n))

    def _large(self, z, motion, where, n):
        k = getattr(self, "_mm", None)
        if k is None:
            k = self._mm = np.arange(int(round(self.sonar.max_range * 1000)) + 1)
        terms = np.abs((z[:, None] - k * 0.001) / z[:, None])
        skip = np.zeros(len(z), dtype=np.bool_)
        return np.array([*motion, *where, 1.0 / n]), skip, terms


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


class BeamSensorModel(_ExpectedModel):
    """Thrun's beam model: each reading is a mixture around its expected range.

    ``p(z_i | x) = z_hit p_hit + z_short p_short + z_max p_max + z_rand p_rand``
    with ``p_hit`` a Gaussian around the expected range normalised over
    ``[0, max_range]``, ``p_short`` an exponential up to the expected range,
    ``p_max`` a point mass at ``max_range`` and ``p_rand`` uniform; the
    scan's likelihood is the product over sensors.

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
        if self.table is not None:
            q = self.params
            self._norms = _kernels.beam_norms(
                float(self.sonar.max_range),
                q.z_hit,
                q.z_short,
                q.sigma_hit,
                q.lambda_short,
                int(round(self.sonar.max_range * 1000)) + 1,
            )
            self._u2_skip = _kernels.beam_skip(
                float(self._norms[0].max()), q.z_rand / self.sonar.max_range
            )

    def log_likelihood(self, particles, z) -> np.ndarray:
        """Per-particle ``sum_i log p(z_i | x_j)`` for readings ``z`` (S,), m.

        Times `BeamParameters.exponent`.
        """
        if self.table is not None:
            return self._table_log_likelihood(particles, z)
        p = _particles(particles)  # cast and weigh in one kernel (the same numbers)
        z = _scan(z, len(self.sonar.sensors))
        q = self.params
        out = np.empty(len(p))
        kernel = (
            exact_models.exact_beam_parallel
            if len(p) >= EXACT_PARALLEL_MIN
            else exact_models.exact_beam
        )
        kernel(
            p, *exact_arguments(self.world, self.sonar), np.empty((len(p), len(z))),
            z, q.z_hit, q.z_short, q.z_max, q.z_rand, q.sigma_hit, q.lambda_short,
            out,
        )  # fmt: skip
        if q.exponent != 1.0:
            out *= q.exponent
        return out

    def _model(self, z) -> tuple:
        """Return the per-scan arguments of the fused beam kernels."""
        q = self.params
        max_range = float(self.sonar.max_range)
        return (
            z,
            np.exp(-q.lambda_short * z),
            z >= max_range - 1e-3,
            self._norms[0],
            self._norms[1],
            q.z_max,
            q.z_rand / max_range,
            1.0 / q.sigma_hit,
        )

    def _lut(self, model) -> np.ndarray:
        lut = np.empty((len(model[0]), len(self._norms[0])))
        _kernels.beam_scan_lut(*model, lut)
        return lut

    def _step(self, particles, weights, motion, normals, z, scratch=None):
        """Move, weigh, estimate in one kernel (see `MCL.step`).

        ``scratch`` and the result as for `PaperSensorModel._step`.
        """
        return self._run(particles, weights, motion, normals, None, z, scratch, -1.0)[
            :5
        ]

    def _small(self, particles, weights, motion, noise, z, u, scratch, words=None):
        """`_run` below `PARALLEL_MIN` particles: `chunked.beam_small`, one call.

        The call checks the readings' values before its draws: ``ValueError``
        for one not positive, nothing drawn or written.
        """
        out_p, out_w, new_p, new_w, est = _small_outputs(scratch, len(particles), u)
        sensors, table, where, (beam, rate) = self._consts(self.params)
        log_mean, ess = chunked.beam_small(
            _NO_WORDS if words is None else words, words is not None,
            particles, weights, noise, sensors, table, z,
            np.exp(z * rate), *self._norms, *motion, *where, *beam, u,
            out_p, out_w, new_p, new_w, est,
        )  # fmt: skip
        if ess < 0.0:  # a reading not positive: refused before any draw or write
            raise ValueError(_NOT_POSITIVE)
        if u < 0.0:
            return out_p, out_w, log_mean, ess, est, None, None
        return out_p, out_w, log_mean, ess, est, new_p, new_w

    def _exact_model(self, n: int) -> tuple:
        q = self.params
        return (True, q.z_hit, q.z_short, q.z_max, q.z_rand, q.sigma_hit,
                q.lambda_short, float(q.exponent), 0.0)  # fmt: skip

    def _extra(self, q) -> tuple:
        """``(scalars, rate)``: `chunked.beam_small`'s model scalars, and more.

        ``rate``: the short readings' rate negated, a 0-d array (``z * rate``
        is quicker to call than ``-lambda_short * z``: the same products).
        """
        max_range = float(self.sonar.max_range)
        return (
            (float(q.exponent), max_range - 1e-3, float(q.z_max),
             q.z_rand / max_range, 1.0 / q.sigma_hit, self._u2_skip),
            np.array(-q.lambda_short),
        )  # fmt: skip

    def _large(self, z, motion, where, n):
        model = self._model(z)
        lut = stepping.beam_lut(model, len(self._norms[0]))
        return np.array([*motion, *where, float(self.params.exponent)]), model[2], lut

    def _table_log_likelihood(self, particles, z) -> np.ndarray:
        p = _particles(particles)
        z = _scan(z, len(self.sonar.sensors))
        q, t = self.params, self.table
        out = np.empty(len(p))
        model = self._model(z)
        where = (t.table, t.origin[0], t.origin[1], 1.0 / t.resolution)
        if len(p) >= PARALLEL_MIN:  # one model table per scan, then lookups
            _kernels.lut_table_loglik_parallel(
                p, self.sonar.sensors, *where, self._lut(model), float(q.exponent), out
            )
        else:
            _kernels.beam_table_loglik(
                p, self.sonar.sensors, *where, *model, float(q.exponent), out
            )
        return out


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
        if self.fast:
            grid = world.distance_field(resolution)
            self._field = np.ascontiguousarray(grid.data, dtype=np.float32)
            self._origin = grid.origin
            self._inv_res = 1.0 / grid.resolution
            self._segments = np.zeros((0, 4))
        else:
            self._field = np.zeros((1, 1), dtype=np.float32)
            self._origin = (0.0, 0.0)
            self._inv_res = 1.0
            self._segments = np.ascontiguousarray(world.obstacles)

    def checked_scan(self, z) -> np.ndarray:
        """Return ``z`` as a float array of shape (S,), or raise ``ValueError``."""
        return _scan(z, len(self.sonar.sensors))

    def log_likelihood(self, particles, z) -> np.ndarray:
        """Per-particle ``sum_i log p(z_i | x_j)`` for readings ``z`` (S,), m."""
        p = _particles(particles)
        z = _scan(z, len(self.sonar.sensors))
        out = np.empty(len(p))
        kernel = (
            _kernels.field_loglik_parallel
            if len(p) >= PARALLEL_MIN or (not self.fast and len(p) >= 64)
            else _kernels.field_loglik
        )
        kernel(
            p,
            self.sonar.sensors,
            z,
            float(self.sonar.max_range),
            float(self.z_hit),
            float(self.z_rand),
            float(self.sigma_hit),
            self._field,
            self._segments,
            self._origin[0],
            self._origin[1],
            self._inv_res,
            1.0,
            out,
        )
        return out
