"""Numba kernels for the sonar cone's inverse model: one cone into a grid.

`_cone_update` adds one cone's log-odds to a grid; its weight across the
cone, ``w(t) = exp(-atan(t)^2 / (2 sigma^2))`` (``t``: a cell's offset across
the axis over its distance along it), comes from a polynomial in ``t^2``
(`cone_weight_poly`, where it is accurate to 1e-8) or else a table of cubic
pieces (`cone_weight_table`). Grids as in `robotlib.mapping._kernels`, which
re-exports these names. Imports nothing of robotlib's but the JIT config.
"""

import math

import numba as nb
import numpy as np

from .._config import JIT

WEIGHT_PIECES = 64
"""Cubic pieces of the cone's weight table (`cone_weight_table`)."""

POLY_DEGREE = 10
"""Degree of the cone's weight polynomial in ``t^2`` (`cone_weight_poly`)."""

POLY_TOLERANCE = 1e-8
"""The polynomial is used only when its error estimate is below this."""

JIT_CONTRACT = {**JIT, "fastmath": {"contract"}}
"""`_cone_update`'s options: the JIT's, with multiply-adds fused (one rounding
instead of two; about a fifth faster a ring update, `bench/bench_ab_slam.py`)."""


@nb.njit(**JIT)
def cone_weight_table(half_cone, sigma):
    """Cubic pieces (M, 4) of ``w(t) = exp(-atan(t)^2 / (2 sigma^2))``.

    On ``0 <= t <= tan(half_cone)`` (``w`` is even), ``t`` a cell's offset
    across the cone over its distance along it. Hermite cubics between
    ``M + 1`` equally spaced nodes (values and slopes exact there); piece
    ``k`` on ``s`` in [0, 1] is ``c0 + s (c1 + s (c2 + s c3))``. With ``M =
    64`` and a 15 degree half cone the error is below ``3e-8`` for ``sigma
    >= 0.1`` rad (one exponential per node instead of one per cell).
    """
    m = WEIGHT_PIECES
    h = math.tan(half_cone) / m
    out = np.empty((m, 4))
    inv2s2 = 0.5 / (sigma * sigma)
    f0 = 0.0
    d0 = 0.0
    for k in range(m + 1):
        t = k * h
        phi = math.atan(t)
        f1 = math.exp(-phi * phi * inv2s2)
        d1 = f1 * (-2.0 * phi * inv2s2) / (1.0 + t * t) * h
        if k > 0:
            out[k - 1, 0] = f0
            out[k - 1, 1] = d0
            out[k - 1, 2] = 3.0 * (f1 - f0) - 2.0 * d0 - d1
            out[k - 1, 3] = 2.0 * (f0 - f1) + d0 + d1
        f0 = f1
        d0 = d1
    return out


@nb.njit(**JIT)
def _table_weight(table, tmax, t):
    """Return the weight at ``t`` (``|t| <= tmax``) from `cone_weight_table`."""
    m = table.shape[0]
    u = abs(t) / tmax * m
    k = int(u)
    k = m - 1 if k > m - 1 else k
    s = u - k
    return table[k, 0] + s * (table[k, 1] + s * (table[k, 2] + s * table[k, 3]))


@nb.njit(**JIT)
def _weight_of(x, sigma):
    """``exp(-atan(sqrt(x))^2 / (2 sigma^2))`` for ``x = t^2 >= 0``."""
    phi = math.atan(math.sqrt(x))
    return math.exp(-0.5 * phi * phi / (sigma * sigma))


@nb.njit(**JIT)
def _horner(poly, u):
    v = poly[POLY_DEGREE + 1]
    for k in range(POLY_DEGREE, 0, -1):
        v = v * u + poly[k]
    return v


@nb.njit(**JIT)
def cone_weight_poly(half_cone, sigma):
    """Return the cone's weight as a polynomial in ``u = 2 t^2 / tan(h)^2 - 1``.

    (``h``: ``half_cone``.) Returns ``poly`` (POLY_DEGREE + 2,): ``poly[0]`` is
    ``2 / tan(half_cone)^2``
    (so ``u = poly[0] t^2 - 1``) and ``poly[1 + k]`` the coefficient of
    ``u^k``; or ``poly[0] = 0`` when the polynomial would not be accurate
    (its last two Chebyshev coefficients, or its error halfway between the
    interpolation nodes, above `POLY_TOLERANCE`; then use
    `cone_weight_table`). The polynomial interpolates ``w`` at the Chebyshev
    nodes in ``t^2`` on ``[0, tan(half_cone)^2]``; for a 15 degree half cone
    it is used for ``sigma >= 0.15`` rad (error about 1e-11 there).
    """
    n = POLY_DEGREE + 1
    out = np.zeros(n + 1)
    if not (0.0 < half_cone < 0.5 * math.pi) or sigma <= 0.0:
        return out
    X = math.tan(half_cone) ** 2
    cheb = np.zeros(n)
    for k in range(n):
        theta = math.pi * (k + 0.5) / n
        ct = math.cos(theta)
        f = _weight_of(0.5 * (ct + 1.0) * X, sigma)
        c_prev, c_cur = 1.0, ct  # cos(m theta) by cos((m+1)t) = 2 cos t cos(mt) - ...
        cheb[0] += f
        cheb[1] += f * ct
        for m in range(2, n):
            c_prev, c_cur = c_cur, 2.0 * ct * c_cur - c_prev
            cheb[m] += f * c_cur
    for m in range(n):
        cheb[m] *= 2.0 / n
    cheb[0] *= 0.5
    if abs(cheb[n - 1]) + abs(cheb[n - 2]) > POLY_TOLERANCE:
        return out
    # Chebyshev to monomials in u: T_{m+1} = 2 u T_m - T_{m-1}, rows of T
    T = np.zeros((n, n))
    T[0, 0] = 1.0
    T[1, 1] = 1.0
    for m in range(2, n):
        for q in range(n):
            T[m, q] = (2.0 * T[m - 1, q - 1] if q > 0 else 0.0) - T[m - 2, q]
    for m in range(n):
        for q in range(m + 1):
            out[1 + q] += cheb[m] * T[m, q]
    out[0] = 2.0 / X
    for k in range(n):  # halfway between nodes, where the error peaks
        u = math.cos(math.pi * (k + 1.0) / n)
        if abs(_horner(out, u) - _weight_of(0.5 * (u + 1.0) * X, sigma)) > (
            POLY_TOLERANCE
        ):
            out[0] = 0.0
            return out
    return out


@nb.njit(**JIT)
def _cell_weight(poly, table, tan_half, perp, along):
    """Return the cone's weight at a cell ``perp`` across, ``along`` the axis."""
    if poly[0] > 0.0:
        return _horner(poly, poly[0] * (perp * perp) / (along * along) - 1.0)
    return _table_weight(table, tan_half, perp / along)


@nb.njit(**JIT)
def _clamp(v, lo, hi):
    return lo if v < lo else (hi if v > hi else v)


@nb.njit(**JIT_CONTRACT)
def _cone_update(
    L, x0, y0, res, sx, sy, sth, z, half_cone, max_range, thickness,
    l_occ, l_free, sigma, max_weight, l_min, l_max, poly, table,
):  # fmt: skip
    """Add one sonar cone's inverse-model log-odds to the grid ``L`` (ny, nx).

    The sensor sits at ``(sx, sy)`` facing ``sth``. A cell whose centre lies
    within ``half_cone`` of the axis gets ``l_free`` when nearer than
    ``z - thickness / 2``, ``l_occ`` when within ``thickness / 2`` of ``z``,
    nothing beyond. A reading at ``max_range`` (no echo) frees the cone to
    ``max_range`` with weight ``max_weight``. With ``sigma > 0`` every
    increment is weighted by ``exp(-phi^2 / (2 sigma^2))`` (``phi``: angle
    off the axis, rad), from ``poly`` (`cone_weight_poly`) when its
    ``poly[0] > 0``, else from ``table`` (`cone_weight_table`), both for
    this ``half_cone`` and ``sigma``.

    Each row visits the cells between the cone's edges and inside its reach:
    cells more than 1e-6 cells inside that interval pass every test and are
    written by a loop without branches; those within 1e-6 cells of its ends
    (and every cell of a row whose interval is not exact: an edge along the
    row) are tested.
    """
    ny, nx = L.shape
    echo = z < max_range
    half = 0.5 * thickness
    reach = z + half if echo else max_range
    w0 = 1.0 if echo else max_weight
    if reach <= 0.0 or w0 == 0.0:
        return
    ux = math.cos(sth)
    uy = math.sin(sth)
    ch = math.cos(half_cone)
    sh = math.sin(half_cone)
    tan_half = math.tan(half_cone)
    e1x = ux * ch + uy * sh  # the edge at sth - half_cone
    e1y = uy * ch - ux * sh
    e2x = ux * ch - uy * sh  # the edge at sth + half_cone
    e2y = uy * ch + ux * sh
    # the sector's bounding box: apex, both edge ends, and any axis direction
    # (E, N, W, S) inside the cone
    xlo = min(0.0, min(reach * e1x, reach * e2x))
    xhi = max(0.0, max(reach * e1x, reach * e2x))
    ylo = min(0.0, min(reach * e1y, reach * e2y))
    yhi = max(0.0, max(reach * e1y, reach * e2y))
    if ux >= ch:
        xhi = reach
    if -ux >= ch:
        xlo = -reach
    if uy >= ch:
        yhi = reach
    if -uy >= ch:
        ylo = -reach
    j0 = max(0, int(math.floor((sx + xlo - x0) / res)))
    j1 = min(nx - 1, int(math.floor((sx + xhi - x0) / res)))
    i0 = max(0, int(math.floor((sy + ylo - y0) / res)))
    i1 = min(ny - 1, int(math.floor((sy + yhi - y0) / res)))
    reach2 = reach * reach
    inner = z - half
    inner2 = (inner * inner if inner > 0.0 else -1.0) if echo else np.inf
    weighted = sigma > 0.0
    use_poly = weighted and poly[0] > 0.0
    wocc = w0 * l_occ
    wfree = w0 * l_free
    # the polynomial's coefficients as scalars (the branch-free loop below)
    p0, c0, c1, c2, c3, c4 = poly[0], poly[1], poly[2], poly[3], poly[4], poly[5]
    c5, c6, c7, c8, c9, c10 = poly[6], poly[7], poly[8], poly[9], poly[10], poly[11]
    narrow = half_cone < 0.5 * math.pi
    for i in range(i0, i1 + 1):
        cy = y0 + (i + 0.5) * res - sy
        rr = reach2 - cy * cy
        if rr < 0.0:
            continue
        lo = -math.sqrt(rr)
        hi = -lo
        exact = narrow
        if narrow:
            # left of edge 1: -e1y cx >= -e1x cy; right of edge 2: e2y cx >= e2x cy
            for e in range(2):
                a = -e1y if e == 0 else e2y
                b = -e1x * cy if e == 0 else e2x * cy
                if a > 1e-9:
                    lo = max(lo, b / a)
                elif a < -1e-9:
                    hi = min(hi, b / a)
                else:
                    exact = False
        if lo > hi + res:
            continue
        c_lo = (lo + sx - x0) / res - 0.5  # the interval's ends in cell indexes
        c_hi = (hi + sx - x0) / res - 0.5
        if exact:
            # centres inside [lo, hi] are in the cone; only those within 1e-6
            # cells of an end (rounding) are tested
            ja = max(j0, int(math.ceil(c_lo - 1e-6)))
            jb = min(j1, int(math.floor(c_hi + 1e-6)))
            ia = max(ja, int(math.ceil(c_lo + 1e-6)))
            ib = min(jb, int(math.floor(c_hi - 1e-6)))
        else:
            ja = max(j0, int(math.floor(c_lo)) - 1)
            jb = min(j1, int(math.ceil(c_hi)) + 1)
            ia = jb + 1
            ib = jb

        cy2 = cy * cy
        # the ends of the interval: every test
        end0 = min(ia - 1, jb)
        for seg in range(2):
            ja_ = ja if seg == 0 else max(ib + 1, end0 + 1)
            jb_ = end0 if seg == 0 else jb
            for j in range(ja_, jb_ + 1):
                cx = x0 + (j + 0.5) * res - sx
                along = cx * ux + cy * uy
                perp = cy * ux - cx * uy
                d2 = cx * cx + cy2
                if along <= 0.0 or abs(perp) > along * tan_half or d2 > reach2:
                    continue
                inc = wocc if d2 >= inner2 else wfree
                if weighted:
                    inc *= _cell_weight(poly, table, tan_half, perp, along)
                L[i, j] = _clamp(L[i, j] + inc, l_min, l_max)
        # inside it: no tests, no branches (a slice indexed from 0 by unsigned
        # integers, so numba adds no negative-index fix and LLVM vectorises)
        if ib < ia:
            continue
        sub = L[i, ia : ib + 1]
        cxa = x0 + 0.5 * res - sx
        if use_poly:
            for k in range(ib + 1 - ia):
                cx = cxa + (ia + k) * res
                along = cx * ux + cy * uy
                perp = cy * ux - cx * uy
                inc = wocc if cx * cx + cy2 >= inner2 else wfree
                u = p0 * (perp * perp) / (along * along) - 1.0
                w = c10 * u + c9
                w = w * u + c8
                w = w * u + c7
                w = w * u + c6
                w = w * u + c5
                w = w * u + c4
                w = w * u + c3
                w = w * u + c2
                w = w * u + c1
                w = w * u + c0
                q = np.uint64(k)
                sub[q] = min(max(sub[q] + inc * w, l_min), l_max)
        elif not weighted:
            for k in range(ib + 1 - ia):
                cx = cxa + (ia + k) * res
                inc = wocc if cx * cx + cy2 >= inner2 else wfree
                q = np.uint64(k)
                sub[q] = min(max(sub[q] + inc, l_min), l_max)
        else:
            for j in range(ia, ib + 1):
                cx = x0 + (j + 0.5) * res - sx
                along = cx * ux + cy * uy
                perp = cy * ux - cx * uy
                inc = wocc if cx * cx + cy2 >= inner2 else wfree
                inc *= _table_weight(table, tan_half, perp / along)
                L[i, j] = _clamp(L[i, j] + inc, l_min, l_max)


@nb.njit(**JIT)
def cone_weights(half_cone, sigma):
    """``(poly, table)`` for `_cone_update` (the table only where ``poly`` fails)."""
    poly = cone_weight_poly(half_cone, sigma) if sigma > 0.0 else np.zeros(
        POLY_DEGREE + 2
    )  # fmt: skip
    if sigma > 0.0 and poly[0] == 0.0:
        return poly, cone_weight_table(half_cone, sigma)
    return poly, np.zeros((1, 4))
