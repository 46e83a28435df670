"""KLD-sampling's stopping rule: count occupied bins until the bound is met.

Numba kernel: contiguous arrays and scalars in; imports nothing of robotlib
but the JIT options.
"""

import math

import numba as nb

from ..._config import JIT


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


@nb.njit(**JIT)
def kld_count(bins, epsilon, z, n_min, occupied):
    """How many of the drawn particles KLD-sampling keeps.

    ``bins`` (n_max,) are the flat ``(x, y, theta)`` bins of the particles
    in draw order; ``occupied`` a boolean array over every bin, all False
    on entry (and on exit). Stops at the first ``n`` with
    ``n >= max(n_min, kld_bound(k))``, ``k`` the bins occupied by the first
    ``n`` draws, or when the draws run out. Returns ``n``.
    """
    k = 0
    n = 0
    while n < bins.shape[0]:
        if not occupied[bins[n]]:
            occupied[bins[n]] = True
            k += 1
        n += 1
        if n >= n_min and n >= kld_bound(k, epsilon, z):
            break
    for m in range(n):
        occupied[bins[m]] = False
    return n
