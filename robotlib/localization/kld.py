"""KLD-sampling (Fox 2003): as many particles as the posterior's spread needs.

Particles are drawn one at a time by weight; each falls in a bin of the
``(x, y, theta)`` space. With ``k`` bins occupied, the number of draws that
keeps the Kullback-Leibler divergence between the sample-based and the true
(binned) posterior below ``epsilon`` with probability ``1 - delta`` is

``n(k) = (k - 1) / (2 epsilon) * (1 - 2/(9(k-1)) + sqrt(2/(9(k-1))) z)^3``

with ``z`` the ``1 - delta`` quantile of the standard normal. Drawing stops
once ``n >= max(n_min, n(k))`` or at ``n_max``: a spread-out posterior keeps
many particles, a peaked one few.
"""

from __future__ import annotations

import math
from statistics import NormalDist

import numpy as np

from .._random import as_rng
from ._kernels.kld import kld_bound as _bound
from ._kernels.kld import kld_draw
from .resampling import _weights

__all__ = ["kld_bound", "kld_resample"]


def kld_bound(k: int, epsilon: float = 0.05, delta: float = 0.01) -> int:
    """Particles needed for ``k`` occupied bins (Fox's bound, rounded up).

    Parameters
    ----------
    k : int
        Occupied bins.
    epsilon : float
        Bound on the KL divergence.
    delta : float
        Probability that the bound is exceeded.

    Returns
    -------
    int
    """
    z = NormalDist().inv_cdf(1.0 - delta)
    return int(math.ceil(_bound(int(k), float(epsilon), z)))


def kld_resample(
    particles,
    weights,
    bounds: tuple[float, float, float, float],
    rng: np.random.Generator | int | None = None,
    n_min: int = 300,
    n_max: int = 10_000,
    epsilon: float = 0.05,
    delta: float = 0.01,
    bin_xy: float = 0.5,
    bin_theta: float = math.radians(15.0),
) -> np.ndarray:
    """Resample by weight, stopping when the KLD bound is met.

    Parameters
    ----------
    particles : array_like, shape (N, 3)
        Poses, m and rad.
    weights : array_like, shape (N,)
        Weights.
    bounds : tuple of float
        ``(xmin, ymin, xmax, ymax)`` of the bin grid, m (positions outside
        fall in the edge bins).
    rng : numpy.random.Generator, int or None
        Draws ``n_max`` uniforms.
    n_min, n_max : int
        Fewest and most particles.
    epsilon, delta : float
        KLD bound parameters (see `kld_bound`).
    bin_xy, bin_theta : float
        Bin sizes, m and rad.

    Returns
    -------
    numpy.ndarray of int64, shape (n,)
        Indexes of the drawn particles, ``n_min <= n <= n_max`` (fewer only
        if ``n_max < n_min``).
    """
    p = np.ascontiguousarray(particles, dtype=np.float64)
    w = _weights(weights)
    if p.shape != (len(w), 3):
        raise ValueError("particles must have shape (N, 3) matching weights")
    xmin, ymin, xmax, ymax = bounds
    nbx = max(1, math.ceil((xmax - xmin) / bin_xy))
    nby = max(1, math.ceil((ymax - ymin) / bin_xy))
    nbt = max(1, math.ceil(2 * math.pi / bin_theta))
    occupied = np.zeros(nbx * nby * nbt, dtype=np.bool_)
    uniforms = as_rng(rng).random(int(n_max))
    out = np.empty(int(n_max), dtype=np.int64)
    z = NormalDist().inv_cdf(1.0 - delta)
    n = kld_draw(
        p, np.cumsum(w), uniforms, float(xmin), float(ymin), float(bin_xy),
        float(bin_theta), nbx, nby, nbt, float(epsilon), z, int(n_min), occupied, out,
    )  # fmt: skip
    return out[:n].copy()
