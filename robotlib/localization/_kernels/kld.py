"""KLD-sampling: draw particles by weight until the bound for their bins is met.

Numba kernel: contiguous arrays and scalars in; imports nothing of robotlib
but the JIT options.
"""

import math

import numba as nb

from ..._config import JIT


@nb.njit(**JIT)
def kld_bound(k, epsilon, z):
    """Return Fox's KLD bound: the particles needed for ``k`` occupied bins.

    ``n = (k-1)/(2 eps) * (1 - 2/(9(k-1)) + sqrt(2/(9(k-1))) z)^3``, with
    ``z`` the upper ``1 - delta`` quantile of the standard normal.
    """
    if k <= 1:
        return 1.0
    a = 2.0 / (9.0 * (k - 1))
    b = 1.0 - a + math.sqrt(a) * z
    return (k - 1) / (2.0 * epsilon) * b * b * b


@nb.njit(**JIT, inline="always")
def _bin(particles, j, x0, y0, bin_xy, bin_theta, nbx, nby, nbt):
    """Flat ``(y, x, theta)`` bin of particle ``j``, clamped to the bin grid."""
    bx = min(max(math.floor((particles[j, 0] - x0) / bin_xy), 0), nbx - 1)
    by = min(max(math.floor((particles[j, 1] - y0) / bin_xy), 0), nby - 1)
    bt = min(max(math.floor((particles[j, 2] + math.pi) / bin_theta), 0), nbt - 1)
    return (by * nbx + bx) * nbt + bt


@nb.njit(**JIT)
def kld_draw(particles, cumulative, uniforms, x0, y0, bin_xy, bin_theta, nbx, nby,
             nbt, epsilon, z, n_min, occupied, out):  # fmt: skip
    """Draw particle indexes into ``out`` until KLD-sampling's bound is met.

    Draw ``n`` takes the particle under ``uniforms[n] * cumulative[-1]`` in
    the cumulative weights (binary search) and marks its bin in
    ``occupied`` (a boolean per bin, all False on entry and on exit).
    Drawing stops at the first ``n >= max(n_min, kld_bound(k))``, ``k`` the
    bins occupied so far, or when the uniforms run out. Returns ``n``.
    """
    total = cumulative[cumulative.shape[0] - 1]
    k = 0
    n = 0
    while n < uniforms.shape[0]:
        u = uniforms[n] * total
        lo, hi = 0, cumulative.shape[0] - 1
        while lo < hi:  # the first j with cumulative[j] > u
            mid = (lo + hi) // 2
            if cumulative[mid] > u:
                hi = mid
            else:
                lo = mid + 1
        out[n] = lo
        b = _bin(particles, lo, x0, y0, bin_xy, bin_theta, nbx, nby, nbt)
        if not occupied[b]:
            occupied[b] = True
            k += 1
        n += 1
        if n >= n_min and n >= kld_bound(k, epsilon, z):
            break
    for m in range(n):
        occupied[_bin(particles, out[m], x0, y0, bin_xy, bin_theta, nbx, nby, nbt)] = (
            False
        )
    return n
