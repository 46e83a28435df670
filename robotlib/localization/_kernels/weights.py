"""Weights and estimates: the Bayes update, normalisation, ESS, the weighted pose mean.

Numba kernels: contiguous arrays and scalars in, no Python objects; they
import nothing of robotlib but the JIT options and other kernels.
"""

import math

import numba as nb
import numpy as np

from ..._config import JIT, jit_inner, serial_and_parallel
from .elementary import exp, sincos


@nb.njit(**JIT)
def _finish_weights(weights, top, out):
    n = weights.shape[0]
    total = 0.0
    for j in range(n):
        total += out[j]
    wsum = 0.0
    for j in range(n):
        wsum += weights[j]
    sq = 0.0
    for j in range(n):
        out[j] /= total
        sq += out[j] * out[j]
    return top + math.log(total / wsum), 1.0 / sq


@jit_inner
def _finish_estimate(weights, top, out, particles, cs, est, cum):
    """`_finish_weights`, then `_pose_mean` into ``est`` (3,): one pass after the sums.

    With ``cum`` of ``N`` rows, also `resample.cumulative`'s running sums of
    the normalised weights before its division (their total is returned).
    Each sum adds the same terms in the same order as those kernels, so the
    numbers are theirs. Returns ``(log_mean, ess, total)``.
    """
    n = weights.shape[0]
    total = 0.0
    wsum = 0.0
    for j in range(n):
        total += out[j]
        wsum += weights[j]
    keep = cum.shape[0] == n
    sq = 0.0
    sx = 0.0
    sy = 0.0
    sc = 0.0
    ss = 0.0
    sw = 0.0
    for j in range(n):
        w = out[j] / total
        out[j] = w
        sq += w * w
        sx += w * particles[j, 0]
        sy += w * particles[j, 1]
        sc += w * cs[j, 0]
        ss += w * cs[j, 1]
        sw += w
        if keep:
            cum[j] = sw
    est[0] = sx / sw
    est[1] = sy / sw
    est[2] = math.atan2(ss, sc)
    return top + math.log(total / wsum), 1.0 / sq, sw


def _update_weights(weights, loglik, out):
    """Bayes update ``out ∝ weights * exp(loglik)``, normalised in place.

    Returns ``(log_mean, ess)``: the log of ``sum_j weights_j exp(loglik_j)``
    (``weights`` summing to 1, so the mean likelihood) and the effective
    sample size ``1 / sum out_j^2`` of the result.
    """
    n = weights.shape[0]
    top = -np.inf
    for j in range(n):
        if loglik[j] > top:
            top = loglik[j]
    for j in nb.prange(n):
        out[j] = weights[j] * exp(loglik[j] - top)
    return _finish_weights(weights, top, out)


update_weights, update_weights_parallel = serial_and_parallel(_update_weights)


@nb.njit(**JIT)
def _pose_mean(particles, weights, cs):
    sx = 0.0
    sy = 0.0
    sc = 0.0
    ss = 0.0
    sw = 0.0
    for j in range(particles.shape[0]):
        w = weights[j]
        sx += w * particles[j, 0]
        sy += w * particles[j, 1]
        sc += w * cs[j, 0]
        ss += w * cs[j, 1]
        sw += w
    out = np.empty(3)
    out[0] = sx / sw
    out[1] = sy / sw
    out[2] = math.atan2(ss, sc)
    return out


def _weighted_pose_mean(particles, weights):
    """Weighted mean of ``x, y`` and circular mean of ``theta``; returns (3,)."""
    cs = np.empty((particles.shape[0], 2))
    for j in nb.prange(particles.shape[0]):
        cs[j, 1], cs[j, 0] = sincos(particles[j, 2])
    return _pose_mean(particles, weights, cs)


weighted_pose_mean, weighted_pose_mean_parallel = serial_and_parallel(
    _weighted_pose_mean
)


@nb.njit(**JIT)
def position_spread(particles, idx):
    """``sqrt(var_x + var_y)`` of the particles ``particles[idx]`` (unweighted)."""
    n = idx.shape[0]
    mx = 0.0
    my = 0.0
    for k in range(n):
        mx += particles[idx[k], 0]
        my += particles[idx[k], 1]
    mx /= n
    my /= n
    v = 0.0
    for k in range(n):
        dx = particles[idx[k], 0] - mx
        dy = particles[idx[k], 1] - my
        v += dx * dx + dy * dy
    return math.sqrt(v / n)
