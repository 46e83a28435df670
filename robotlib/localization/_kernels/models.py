"""Sensor models on expected readings: the paper's, the beam and the likelihood field.

Numba kernels: contiguous arrays and scalars in, no Python objects; they
import nothing of robotlib but the JIT options and other kernels.
"""

import math

import numba as nb
import numpy as np

from ..._config import JIT, serial_and_parallel
from ...world._kernels import point_segment_distance
from .common import _LOG_SQRT_2PI
from .elementary import exp, log, sincos


@nb.njit(**JIT, inline="always")
def paper_one(j, z, zhat, n, out):
    """`paper_loglik` of row ``j`` alone: ``out[j]``."""
    s_count = z.shape[0]
    d = 0.0
    for i in range(s_count):
        d += abs((z[i] - zhat[j, i]) / z[i])
    out[j] = log(exp(-d / s_count) + 1.0 / n)


@nb.njit(**JIT)
def paper_loglik(z, zhat, n, out):
    """Compute the paper's innovation weight as a log: ``log(exp(-d_j) + 1/n)``.

    ``d_j = mean_i |(z_i - zhat_ji) / z_i|``; ``z`` (S,), ``zhat`` (N, S).
    """
    for j in range(zhat.shape[0]):
        paper_one(j, z, zhat, n, out)


@nb.njit(**JIT)
def _beam_prob(z, zhat, max_range, z_hit, z_short, z_max, z_rand, sigma, lam_short):
    """Thrun's beam model mixture ``p(z | zhat)`` for one beam."""
    p = 0.0
    if z < max_range:
        # hit: Gaussian around zhat, normalised over [0, max_range]
        u = (z - zhat) / sigma
        mass = 0.5 * (
            math.erf((max_range - zhat) / (sigma * math.sqrt(2.0)))
            - math.erf(-zhat / (sigma * math.sqrt(2.0)))
        )
        if mass > 0.0:
            p += z_hit * exp(-0.5 * u * u - _LOG_SQRT_2PI) / sigma / mass
        # short: exponential up to zhat, normalised over [0, zhat]
        if z <= zhat and zhat > 0.0:
            p += (
                z_short
                * lam_short
                * exp(-lam_short * z)
                / (1.0 - exp(-lam_short * zhat))
            )
        p += z_rand / max_range
    else:
        p += z_max
    return p


@nb.njit(**JIT)
def beam_one(j, z, zhat, max_range, z_hit, z_short, z_max, z_rand, sigma, lam, out):
    """`beam_loglik` of row ``j`` alone: ``out[j]``."""
    ll = 0.0
    for i in range(z.shape[0]):
        zi = z[i] if z[i] < max_range - 1e-3 else max_range
        ll += log(
            _beam_prob(
                zi, zhat[j, i], max_range, z_hit, z_short, z_max, z_rand, sigma, lam
            )
        )
    out[j] = ll


def _beam_loglik(
    z, zhat, max_range, z_hit, z_short, z_max, z_rand, sigma, lam_short, out
):
    """Beam model log-likelihood ``out[j] = sum_i log p(z_i | zhat_ji)``.

    A reading at or beyond ``max_range`` (to 1 mm) is a "max" reading.
    """
    for j in nb.prange(zhat.shape[0]):
        beam_one(
            j, z, zhat, max_range, z_hit, z_short, z_max, z_rand, sigma, lam_short, out
        )


beam_loglik, beam_loglik_parallel = serial_and_parallel(_beam_loglik)


def _field_loglik(
    particles,
    sensors,
    z,
    max_range,
    z_hit,
    z_rand,
    sigma,
    field,
    segments,
    x0,
    y0,
    inv_res,
    far,
    out,
):
    """Likelihood-field log-likelihood of readings ``z`` (S,) for particles (N, 3).

    Each reading below ``max_range`` puts an end point on its sensor's axis;
    ``p = z_hit N(d; 0, sigma) + z_rand / max_range`` with ``d`` the end
    point's distance to the nearest obstacle: exact to ``segments`` when
    there are any (M > 0), else looked up in ``field`` (ny, nx) float32, m
    (``far`` outside the grid). Max readings are skipped.
    """
    for j in nb.prange(particles.shape[0]):
        s, c = sincos(particles[j, 2])
        ny, nx = field.shape
        ll = 0.0
        for i in range(sensors.shape[0]):
            if z[i] >= max_range - 1e-3:
                continue
            sx = particles[j, 0] + c * sensors[i, 0] - s * sensors[i, 1]
            sy = particles[j, 1] + s * sensors[i, 0] + c * sensors[i, 1]
            a = particles[j, 2] + sensors[i, 2]
            sa, ca = sincos(a)
            ex = sx + z[i] * ca
            ey = sy + z[i] * sa
            if segments.shape[0] > 0:
                d = np.inf
                for m in range(segments.shape[0]):
                    dm = point_segment_distance(
                        ex,
                        ey,
                        segments[m, 0],
                        segments[m, 1],
                        segments[m, 2],
                        segments[m, 3],
                    )
                    if dm < d:
                        d = dm
            else:
                col = int(math.floor((ex - x0) * inv_res))
                row = int(math.floor((ey - y0) * inv_res))
                if 0 <= row < ny and 0 <= col < nx:
                    d = field[row, col]
                else:
                    d = far
            u = d / sigma
            ll += log(
                z_hit * exp(-0.5 * u * u - _LOG_SQRT_2PI) / sigma + z_rand / max_range
            )
        out[j] = ll


field_loglik, field_loglik_parallel = serial_and_parallel(_field_loglik)
