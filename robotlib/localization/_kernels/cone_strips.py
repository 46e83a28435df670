"""The walls of each direction's strips, for the cone-table builder.

`build_strips` sorts the walls into strips parallel to one direction (the
lists `robotlib.localization._kernels.cone_table` casts its rays through),
with the margins that make the lists safe: a wall goes into every strip its
offset across the direction reaches within `_MU`, with its span along the
direction widened by `_MV`, and walls within `_PARALLEL` of the direction
span their whole strip. `strip_frame` is the box every strip offset is
measured in.

Numba kernels: contiguous arrays and scalars in; they import nothing of
robotlib but the JIT options and other kernels.
"""

import math

import numba as nb
import numpy as np

from ..._config import JIT
from ...sensing._kernels import _EPS

_MU = 1e-7  # m: a wall also goes into strips it misses by this little
_MV = 1e-3  # m: the span along the direction is widened by this much
_PARALLEL = 1e-6  # walls this close to the direction (sine) span their strip

# columns of a strip entry
_VMIN, _VMAX, _ULO, _UHI, _PX, _PY, _EX, _EY = range(8)


@nb.njit(**JIT)
def strip_frame(segments, x0, y0, width, height):
    """Centre and diameter ``(xc, yc, d)`` of a box holding the walls and the grid.

    Every wall end point and cell lies within ``d / 2`` of the centre, so
    its offset across any direction lies within ``d / 2`` of the centre's.
    """
    xs0 = x0
    ys0 = y0
    xs1 = x0 + width
    ys1 = y0 + height
    for m in range(segments.shape[0]):
        xs0 = min(xs0, segments[m, 0], segments[m, 2])
        xs1 = max(xs1, segments[m, 0], segments[m, 2])
        ys0 = min(ys0, segments[m, 1], segments[m, 3])
        ys1 = max(ys1, segments[m, 1], segments[m, 3])
    d = math.sqrt((xs1 - xs0) ** 2 + (ys1 - ys0) ** 2) + 2.0
    return 0.5 * (xs0 + xs1), 0.5 * (ys0 + ys1), d


@nb.njit(**JIT)
def _sort_by_start(raw, lo, hi, order, keys):
    """Sort rows ``lo:hi`` of ``raw`` by ``vmin`` into ``order[:hi - lo]``.

    Written out rather than `numpy.argsort`, which takes seconds to compile;
    the keys are sorted beside the order, side by side in memory.
    """
    n = hi - lo
    for r in range(n):
        order[r] = lo + r
        keys[r] = raw[lo + r, _VMIN]
    gap = 1
    while gap < n // 3:
        gap = 3 * gap + 1
    while gap >= 1:
        for r in range(gap, n):
            q = order[r]
            key = keys[r]
            p = r
            while p >= gap and keys[p - gap] > key:
                order[p] = order[p - gap]
                keys[p] = keys[p - gap]
                p -= gap
            order[p] = q
            keys[p] = key
        gap //= 3


@nb.njit(**JIT)
def _unseen(segments, m, c, s, c2, s2):
    """Whether wall ``m`` is parallel (`ray_segments`' test) to both directions.

    Such a wall is skipped by every ray along either direction (``denom``
    is computed as the rays compute it), so it need not be listed.
    """
    ex = segments[m, 2] - segments[m, 0]
    ey = segments[m, 3] - segments[m, 1]
    return abs(c * ey - s * ex) < _EPS and abs(c2 * ey - s2 * ex) < _EPS


@nb.njit(**JIT)
def build_strips(segments, c, s, c2, s2, u0, w, n_strips, normals, cos_specular):
    """Sort the walls into strips across ``(c, s)``: start, firsts, entries, ....

    Returns ``start, firsts, entries, codes, reach``.

    Strip ``k`` covers offsets ``u = -s x + c y`` in ``[u0 + k w, u0 + (k + 1)
    w)`` and holds ``entries[start[k]:start[k + 1]]`` (8 columns: the
    wall's span ``vmin, vmax`` along the direction within the strip, its
    offsets ``ulo, uhi``, all widened, then its first end point and edge
    vector as `ray_segments` computes them) and their ``codes``: first the
    walls nearly parallel to the direction (spanning the whole line, ``vmin
    = -inf``; up to ``firsts[k]``), then the others by ``vmin``.
    ``reach[k]`` is the longest finite span in the strip. Walls that no ray
    along ``(c, s)`` or ``(c2, s2)`` can hit (`_unseen`: on a map of
    points, one arm of every cross along the axes) are left out.

    A wall ``m``'s code is ``4 m + f``: bit 1 of ``f`` set when a ray along
    ``(c, s)`` that hits it returns an echo (``|c nx + s ny| >=
    cos_specular`` with ``normals[m] = (nx, ny)``: the specular test of
    `robotlib.sensing._kernels.cone_echo`, which `cone_table._ray_entry`
    reads), bit 2 likewise along ``(c2, s2)``. Codes order as the indexes
    do, so equal hits still go to the lowest wall index.
    """
    n_walls = segments.shape[0]
    count = np.zeros(n_strips + 1, dtype=np.int64)
    for m in range(n_walls):
        if _unseen(segments, m, c, s, c2, s2):
            continue
        up = -s * segments[m, 0] + c * segments[m, 1]
        uq = -s * segments[m, 2] + c * segments[m, 3]
        k0 = int((min(up, uq) - _MU - u0) / w)
        k1 = int((max(up, uq) + _MU - u0) / w)
        for k in range(k0, k1 + 1):
            count[k + 1] += 1
    for k in range(n_strips):
        count[k + 1] += count[k]
    n = count[n_strips]
    entries = np.empty((n, 8))
    ids = np.empty(n, dtype=np.int64)
    fill = count[:n_strips].copy()
    for m in range(n_walls):
        if _unseen(segments, m, c, s, c2, s2):
            continue
        px = segments[m, 0]
        py = segments[m, 1]
        ex = segments[m, 2] - px
        ey = segments[m, 3] - py
        up = -s * px + c * py
        uq = -s * segments[m, 2] + c * segments[m, 3]
        vp = c * px + s * py
        vq = c * segments[m, 2] + s * segments[m, 3]
        k0 = int((min(up, uq) - _MU - u0) / w)
        k1 = int((max(up, uq) + _MU - u0) / w)
        du = uq - up
        length = math.sqrt(ex * ex + ey * ey)
        parallel = abs(c * ey - s * ex) <= _PARALLEL * length
        for k in range(k0, k1 + 1):
            a = 0.0
            b = 1.0
            if k1 > k0 and du != 0.0:  # the part of the wall inside the strip
                sa = (u0 + k * w - _MU - up) / du
                sb = (u0 + (k + 1) * w + _MU - up) / du
                if sa > sb:
                    sa, sb = sb, sa
                a = min(max(sa, 0.0), 1.0)
                b = min(max(sb, 0.0), 1.0)
            va = vp + a * (vq - vp)
            vb = vp + b * (vq - vp)
            f = fill[k]
            fill[k] = f + 1
            if parallel:
                entries[f, _VMIN] = -np.inf
                entries[f, _VMAX] = np.inf
            else:
                entries[f, _VMIN] = min(va, vb) - _MV
                entries[f, _VMAX] = max(va, vb) + _MV
            entries[f, _ULO] = min(up, uq) - _MU
            entries[f, _UHI] = max(up, uq) + _MU
            entries[f, _PX] = px
            entries[f, _PY] = py
            entries[f, _EX] = ex
            entries[f, _EY] = ey
            code = 4 * m
            if abs(c * normals[m, 0] + s * normals[m, 1]) >= cos_specular:
                code += 1
            if abs(c2 * normals[m, 0] + s2 * normals[m, 1]) >= cos_specular:
                code += 2
            ids[f] = code
    # each strip sorted where it lies, through a copy of that strip alone
    # (not a second (n, 8) array: the build's memory is the table and this)
    reach = np.zeros(n_strips)
    firsts = count[:n_strips].copy()
    most = 0
    for k in range(n_strips):
        most = max(most, count[k + 1] - count[k])
    order = np.empty(most, dtype=np.int64)
    keys = np.empty(most)
    rows = np.empty((most, 8))
    codes = np.empty(most, dtype=np.int64)
    for k in range(n_strips):
        lo = count[k]
        hi = count[k + 1]
        if hi == lo:
            continue
        _sort_by_start(entries, lo, hi, order, keys)
        for r in range(hi - lo):
            for col in range(8):
                rows[r, col] = entries[lo + r, col]
            codes[r] = ids[lo + r]
        longest = 0.0
        for r in range(hi - lo):
            q = order[r] - lo
            for col in range(8):
                entries[lo + r, col] = rows[q, col]
            ids[lo + r] = codes[q]
            if rows[q, _VMIN] > -np.inf:
                longest = max(longest, rows[q, _VMAX] - rows[q, _VMIN])
            else:
                firsts[k] = lo + r + 1
        reach[k] = longest
    return count, firsts, entries, ids, reach
