"""Resampling: functions that return the indexes of the particles to keep.

As in filterpy, each resampler takes normalised weights and returns an index
array; ``particles[indexes]`` is the new set (with weights ``1/n``). All take
``n``, the size of the new set (default: the old size), and an ``rng``.

- `multinomial_resample`: ``n`` independent draws by weight (the paper's
  "selection with replacement"); the most variance.
- `stratified_resample`: one draw in each of ``n`` equal strata of [0, 1).
- `systematic_resample` (Thrun's low-variance sampler): one random offset,
  then ``n`` equally spaced positions; the least variance, O(n).
- `residual_resample`: ``floor(n w_j)`` copies of each particle, the rest
  multinomially.
"""

from __future__ import annotations

import numpy as np

from .._random import as_rng
from .motion import _particles

__all__ = [
    "effective_sample_size",
    "multinomial_resample",
    "stratified_resample",
    "systematic_resample",
    "residual_resample",
    "RESAMPLERS",
]


def _weights(weights) -> np.ndarray:
    w = np.ascontiguousarray(weights, dtype=np.float64)
    if w.ndim != 1 or len(w) == 0:
        raise ValueError(f"weights must have shape (N,) with N > 0, got {w.shape}")
    if not (np.all(w >= 0) and w.sum() > 0):
        raise ValueError("weights must be non-negative with a positive sum")
    return w


def _cloud(particles, weights) -> tuple[np.ndarray, np.ndarray]:
    """Return a weighted cloud as checked arrays ``(N, 3)`` and ``(N,)``, or raise."""
    p = _particles(particles)
    w = _weights(weights)
    if len(w) != len(p):
        raise ValueError("particles and weights differ in length")
    return p, w


def _search(weights: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """Index of the particle under each position in [0, 1) of the cumulative weights.

    Particle ``j`` covers ``[c_{j-1}, c_j)`` of the normalised cumulative sum
    ``c``: the first ``j`` with ``c_j > u``.
    """
    cumulative = np.cumsum(weights)
    idx = np.searchsorted(cumulative, positions * cumulative[-1], side="right")
    return np.minimum(idx, len(weights) - 1)


def effective_sample_size(weights) -> float:
    """Kish's effective sample size ``1 / sum w_j^2`` of normalised weights."""
    w = _weights(weights)
    w = w / w.sum()
    return float(1.0 / np.dot(w, w))


def multinomial_resample(
    weights, rng: np.random.Generator | int | None = None, n: int | None = None
) -> np.ndarray:
    """Draw ``n`` indexes independently, each with probability ``weights[j]``.

    Parameters
    ----------
    weights : array_like, shape (N,)
        Non-negative weights (normalised inside).
    rng : numpy.random.Generator, int or None
        Draws ``n`` uniforms.
    n : int, optional
        Number of indexes (default ``N``).

    Returns
    -------
    numpy.ndarray of int64, shape (n,)
        Indexes in draw order (independent and identically distributed).
    """
    w = _weights(weights)
    n = len(w) if n is None else int(n)
    return _search(w, as_rng(rng).random(n))


def stratified_resample(
    weights, rng: np.random.Generator | int | None = None, n: int | None = None
) -> np.ndarray:
    """Draw one index per stratum: positions ``(k + u_k) / n``, ``u_k`` uniform.

    Parameters and return as `multinomial_resample`; indexes come sorted.
    """
    w = _weights(weights)
    n = len(w) if n is None else int(n)
    return _search(w, (np.arange(n) + as_rng(rng).random(n)) / n)


def systematic_resample(
    weights, rng: np.random.Generator | int | None = None, n: int | None = None
) -> np.ndarray:
    """Low-variance resampling: positions ``(k + u) / n`` with a single ``u``.

    A particle of weight ``w`` is kept ``floor(n w)`` or ``ceil(n w)`` times.
    Parameters and return as `multinomial_resample`; indexes come sorted.
    """
    w = _weights(weights)
    n = len(w) if n is None else int(n)
    return _search(w, (np.arange(n) + as_rng(rng).random()) / n)


def residual_resample(
    weights, rng: np.random.Generator | int | None = None, n: int | None = None
) -> np.ndarray:
    """Keep ``floor(n w_j)`` copies of each particle, draw the rest multinomially.

    Parameters and return as `multinomial_resample`.
    """
    w = _weights(weights)
    w = w / w.sum()
    n = len(w) if n is None else int(n)
    copies = np.floor(n * w).astype(np.int64)
    fixed = np.repeat(np.arange(len(w)), copies)
    rest = n - len(fixed)
    if rest == 0:
        return fixed
    residual = n * w - copies
    extra = multinomial_resample(residual, rng, rest)
    return np.concatenate([fixed, extra])


RESAMPLERS = {
    "multinomial": multinomial_resample,
    "stratified": stratified_resample,
    "systematic": systematic_resample,
    "residual": residual_resample,
}
"""Resampler name to function; ``"low_variance"`` is ``"systematic"``."""
RESAMPLERS["low_variance"] = systematic_resample
