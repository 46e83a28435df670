"""Resampling: cumulative weights, index search, KLD-sampling, gathering, admissibility.

Numba kernels: contiguous arrays and scalars in, no Python objects; they
import nothing of robotlib but the JIT options and other kernels.
"""

import math

import numba as nb
import numpy as np

from ..._config import JIT


@nb.njit(**JIT)
def cumulative(weights):
    """Cumulative sum of weights with the last entry forced to exactly 1."""
    n = weights.shape[0]
    c = np.empty(n)
    total = 0.0
    for j in range(n):
        total += weights[j]
        c[j] = total
    for j in range(n):
        c[j] /= total
    c[n - 1] = 1.0
    return c


@nb.njit(**JIT)
def search_indexes(cum, positions, out):
    """``out[k]`` = first ``j`` with ``cum[j] > positions[k]`` (binary search)."""
    n = cum.shape[0]
    for k in range(positions.shape[0]):
        u = positions[k]
        lo = 0
        hi = n - 1
        while lo < hi:
            mid = (lo + hi) // 2
            if cum[mid] > u:
                hi = mid
            else:
                lo = mid + 1
        out[k] = lo


@nb.njit(**JIT)
def sorted_indexes(cum, positions, out):
    """As `search_indexes` for increasing ``positions``, by one merge pass."""
    n = cum.shape[0]
    j = 0
    for k in range(positions.shape[0]):
        while j < n - 1 and cum[j] <= positions[k]:
            j += 1
        out[k] = j


@nb.njit(**JIT)
def kld_bound(k, epsilon, z):
    """Fox's KLD bound: particles needed for ``k`` occupied bins.

    ``n = (k-1)/(2 eps) * (1 - 2/(9(k-1)) + sqrt(2/(9(k-1))) z)^3``, with
    ``z`` the upper ``1 - delta`` quantile of the standard normal.
    """
    if k <= 1:
        return 1.0
    a = 2.0 / (9.0 * (k - 1))
    b = 1.0 - a + math.sqrt(a) * z
    return (k - 1) / (2.0 * epsilon) * b * b * b


@nb.njit(**JIT, inline="always")
def _pose_bin(particles, lo, x0, y0, bin_xy, bin_theta, nbx, nby, nbt):
    """Flat ``(y, x, theta)`` bin of particle ``lo``, clamped to the bin grid."""
    # numba's math.floor is an int64 already: no int() (numba compiles one per process)
    bx = math.floor((particles[lo, 0] - x0) / bin_xy)
    by = math.floor((particles[lo, 1] - y0) / bin_xy)
    bt = math.floor((particles[lo, 2] + math.pi) / bin_theta)
    bx = min(max(bx, 0), nbx - 1)
    by = min(max(by, 0), nby - 1)
    bt = min(max(bt, 0), nbt - 1)
    return (by * nbx + bx) * nbt + bt


@nb.njit(**JIT)
def kld_resample(
    particles,
    cum,
    uniforms,
    x0,
    y0,
    bin_xy,
    bin_theta,
    nbx,
    nby,
    nbt,
    epsilon,
    z,
    n_min,
    occupied,
    out,
):
    """KLD-sampling: draw by ``uniforms`` until the bound for the bins is met.

    Draws particle indexes one at a time (``uniforms`` (n_max,) in [0, 1),
    searched in ``cum``), counts the distinct ``(x, y, theta)`` bins of the
    drawn particles in ``occupied`` (nby * nbx * nbt bools, all False on
    entry and on exit), and stops at ``n >= max(n_min, kld_bound(k))`` or
    when the uniforms run out. Writes indexes into ``out`` and returns the
    count.
    """
    n_max = uniforms.shape[0]
    n_cum = cum.shape[0]
    k = 0
    n = 0
    while n < n_max:
        u = uniforms[n]
        lo = 0
        hi = n_cum - 1
        while lo < hi:
            mid = (lo + hi) // 2
            if cum[mid] > u:
                hi = mid
            else:
                lo = mid + 1
        out[n] = lo
        cell = _pose_bin(particles, lo, x0, y0, bin_xy, bin_theta, nbx, nby, nbt)
        if not occupied[cell]:
            occupied[cell] = True
            k += 1
        n += 1
        if n >= n_min and n >= kld_bound(k, epsilon, z):
            break
    for m in range(n):
        occupied[
            _pose_bin(particles, out[m], x0, y0, bin_xy, bin_theta, nbx, nby, nbt)
        ] = False
    return n


@nb.njit(**JIT)
def gather(particles, idx, out):
    """``out[k] = particles[idx[k]]`` for (N, 3) particles."""
    for k in range(idx.shape[0]):
        j = idx[k]
        out[k, 0] = particles[j, 0]
        out[k, 1] = particles[j, 1]
        out[k, 2] = particles[j, 2]


@nb.njit(**JIT)
def outside(particles, admissible, x0, y0, inv_res, out):
    """``out[j]`` True where particle ``j`` is not on an admissible cell."""
    ny, nx = admissible.shape
    count = 0  # math.floor is an int64 in numba: no int() to compile (`_pose_bin`)
    for j in range(particles.shape[0]):
        col = math.floor((particles[j, 0] - x0) * inv_res)
        row = math.floor((particles[j, 1] - y0) * inv_res)
        bad = not (0 <= row < ny and 0 <= col < nx and admissible[row, col])
        out[j] = bad
        if bad:
            count += 1
    return count


@nb.njit(**JIT)
def systematic_gather(particles, weights, u, out):
    """Low-variance resampling of ``particles`` (N, 3) into ``out`` (n, 3).

    Positions ``(k + u) / n`` in the cumulative weights, as
    `robotlib.localization.resampling.systematic_resample` then `gather`.
    """
    cum = cumulative(weights)
    n_cum = cum.shape[0]
    n = out.shape[0]
    j = 0
    for k in range(n):
        position = (k + u) / n
        while j < n_cum - 1 and cum[j] <= position:
            j += 1
        out[k, 0] = particles[j, 0]
        out[k, 1] = particles[j, 1]
        out[k, 2] = particles[j, 2]
