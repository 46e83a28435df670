"""Numba kernels for world geometry: distances to segments and rasterisation.

Kernels take only contiguous arrays and scalars; the public functions in
`robotlib.world` validate their input and call them.
"""

import math

import numba as nb
import numpy as np

from .._config import JIT, JIT_PARALLEL, serial_and_parallel


@nb.njit(**JIT)
def point_segment_distance(px, py, x1, y1, x2, y2):
    """Euclidean distance from point ``(px, py)`` to segment ``(x1, y1)-(x2, y2)``."""
    dx = x2 - x1
    dy = y2 - y1
    len2 = dx * dx + dy * dy
    t = 0.0
    if len2 > 0.0:
        t = ((px - x1) * dx + (py - y1) * dy) / len2
        if t < 0.0:
            t = 0.0
        elif t > 1.0:
            t = 1.0
    ex = x1 + t * dx - px
    ey = y1 + t * dy - py
    return math.sqrt(ex * ex + ey * ey)


def _min_distance_to_segments(points, segments, out):
    """Write into ``out[k]`` the distance of ``points[k]`` to the nearest segment.

    ``points`` is (K, 2), ``segments`` (M, 4) as ``x1, y1, x2, y2``; ``out``
    is (K,) and receives ``inf`` when there are no segments. Compiled
    serially (``min_distance_to_segments_serial``) and in parallel
    (``min_distance_to_segments``): the same numbers.
    """
    for k in nb.prange(points.shape[0]):
        best = np.inf
        px = points[k, 0]
        py = points[k, 1]
        for m in range(segments.shape[0]):
            d = point_segment_distance(
                px, py, segments[m, 0], segments[m, 1], segments[m, 2], segments[m, 3]
            )
            if d < best:
                best = d
        out[k] = best


min_distance_to_segments_serial, min_distance_to_segments = serial_and_parallel(
    _min_distance_to_segments
)


@nb.njit(**JIT)
def rasterise_segments(segments, x0, y0, resolution, occupied):
    """Mark every cell of ``occupied`` (rows = y, cols = x) that a segment crosses.

    Walks each segment from cell to cell in order (Amanatides and Woo's
    traversal), so every cell the segment passes through is marked, including
    a cell whose corner it only clips; cells off the grid are skipped.
    """
    ny, nx = occupied.shape
    for m in range(segments.shape[0]):
        gx = (segments[m, 0] - x0) / resolution
        gy = (segments[m, 1] - y0) / resolution
        ex = (segments[m, 2] - x0) / resolution - gx
        ey = (segments[m, 3] - y0) / resolution - gy
        j = int(math.floor(gx))
        i = int(math.floor(gy))
        j_end = int(math.floor(gx + ex))
        i_end = int(math.floor(gy + ey))
        step_j = 1 if ex > 0 else -1
        step_i = 1 if ey > 0 else -1
        # Parameters (0..1 along the segment) of the next x and y cell borders.
        if ex != 0.0:
            t_max_x = ((j + 1 - gx) if ex > 0 else (gx - j)) / abs(ex)
            t_delta_x = 1.0 / abs(ex)
        else:
            t_max_x = np.inf
            t_delta_x = np.inf
        if ey != 0.0:
            t_max_y = ((i + 1 - gy) if ey > 0 else (gy - i)) / abs(ey)
            t_delta_y = 1.0 / abs(ey)
        else:
            t_max_y = np.inf
            t_delta_y = np.inf
        for _ in range(abs(j_end - j) + abs(i_end - i) + 1):
            if 0 <= i < ny and 0 <= j < nx:
                occupied[i, j] = True
            if t_max_x < t_max_y:
                j += step_j
                t_max_x += t_delta_x
            else:
                i += step_i
                t_max_y += t_delta_y


@nb.njit(**JIT)
def flood_fill(free, i0, j0, out):
    """Set ``out`` True on the cells of ``free`` 4-connected to ``(i0, j0)``.

    The cells waiting are kept as flat int32 indices (a grid of fewer than
    2**31 cells), 4 bytes each.
    """
    ny, nx = free.shape
    stack = np.empty(ny * nx, dtype=np.int32)
    stack[0] = i0 * nx + j0
    top = 1
    out[i0, j0] = True
    while top > 0:
        top -= 1
        i = stack[top] // nx
        j = stack[top] - i * nx
        for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            a = i + di
            b = j + dj
            if 0 <= a < ny and 0 <= b < nx and free[a, b] and not out[a, b]:
                out[a, b] = True
                stack[top] = a * nx + b
                top += 1


@nb.njit(**JIT)
def nearest_distance(px, py, segments):
    """Distance from ``(px, py)`` to the nearest of ``segments`` (M, 4); inf if none."""
    best = np.inf
    for m in range(segments.shape[0]):
        d = point_segment_distance(
            px, py, segments[m, 0], segments[m, 1], segments[m, 2], segments[m, 3]
        )
        if d < best:
            best = d
    return best


# -- a uniform bucket index of segments (large maps) -------------------------
@nb.njit(**JIT)
def bucket_counts(segments, x0, y0, size, nbx, nby, margin, counts):
    """Count into ``counts`` (nby * nbx + 1,) the segments of each bucket.

    A segment goes into every bucket its bounding box, grown by ``margin``,
    overlaps; ``counts[1 + b]`` receives bucket ``b``'s count (CSR layout).
    """
    for m in range(segments.shape[0]):
        j0, j1, i0, i1 = _bucket_span(segments, m, x0, y0, size, nbx, nby, margin)
        for i in range(i0, i1 + 1):
            for j in range(j0, j1 + 1):
                counts[1 + i * nbx + j] += 1


@nb.njit(**JIT)
def _bucket_span(segments, m, x0, y0, size, nbx, nby, margin):
    lo_x = min(segments[m, 0], segments[m, 2]) - margin
    hi_x = max(segments[m, 0], segments[m, 2]) + margin
    lo_y = min(segments[m, 1], segments[m, 3]) - margin
    hi_y = max(segments[m, 1], segments[m, 3]) + margin
    j0 = min(max(int(math.floor((lo_x - x0) / size)), 0), nbx - 1)
    j1 = min(max(int(math.floor((hi_x - x0) / size)), 0), nbx - 1)
    i0 = min(max(int(math.floor((lo_y - y0) / size)), 0), nby - 1)
    i1 = min(max(int(math.floor((hi_y - y0) / size)), 0), nby - 1)
    return j0, j1, i0, i1


@nb.njit(**JIT)
def bucket_fill(segments, x0, y0, size, nbx, nby, margin, start, items):
    """Fill ``items`` with segment indices per bucket, ascending (CSR ``start``)."""
    fill = start[:-1].copy()
    for m in range(segments.shape[0]):
        j0, j1, i0, i1 = _bucket_span(segments, m, x0, y0, size, nbx, nby, margin)
        for i in range(i0, i1 + 1):
            for j in range(j0, j1 + 1):
                b = i * nbx + j
                items[fill[b]] = m
                fill[b] += 1


@nb.njit(**JIT)
def indexed_nearest(px, py, segments, x0, y0, size, nbx, nby, start, items):
    """`nearest_distance` through a bucket index: the same number, found sooner.

    Searches square rings of buckets outwards from the point's bucket and
    stops once the best distance is below the ring's clearance (no segment
    outside the rings searched can be nearer). A point outside the indexed
    area is measured against every segment.
    """
    j = int(math.floor((px - x0) / size))
    i = int(math.floor((py - y0) / size))
    if not (0 <= i < nby and 0 <= j < nbx):
        return nearest_distance(px, py, segments)
    # clearance of ring k: distance from the point to the outside of the
    # (2k+1)^2 block of buckets around its own
    fx = px - (x0 + j * size)
    fy = py - (y0 + i * size)
    inner = min(fx, size - fx, fy, size - fy)
    best = np.inf
    rings = max(max(i, nby - 1 - i), max(j, nbx - 1 - j))
    for k in range(rings + 1):
        for a in range(i - k, i + k + 1):
            if a < 0 or a >= nby:
                continue
            step = 1 if (a == i - k or a == i + k) else 2 * k
            b = j - k
            while b <= j + k:
                if 0 <= b < nbx:
                    q = a * nbx + b
                    for t in range(start[q], start[q + 1]):
                        m = items[t]
                        d = point_segment_distance(
                            px,
                            py,
                            segments[m, 0],
                            segments[m, 1],
                            segments[m, 2],
                            segments[m, 3],
                        )
                        if d < best:
                            best = d
                if step == 0:
                    break
                b += step
        if best < inner + k * size - 1e-9:
            return best
    return best


@nb.njit(**JIT_PARALLEL)
def indexed_min_distance(points, segments, x0, y0, size, nbx, nby, start, items, out):
    """`min_distance_to_segments` through a bucket index (the same numbers)."""
    for k in nb.prange(points.shape[0]):
        out[k] = indexed_nearest(
            points[k, 0], points[k, 1], segments, x0, y0, size, nbx, nby, start, items
        )


@nb.njit(**JIT_PARALLEL)
def indexed_distance_field(
    x0, y0, resolution, block, segments, bx0, by0, bsize, nbx, nby, start, items,
    cut, out,
):  # fmt: skip
    """Distance from each cell centre of ``out`` (ny, nx) to the nearest segment.

    The same numbers as `min_distance_to_segments` on the centres, computed
    block by block (``block`` x ``block`` cells, in parallel): the exact
    distance ``dc`` at a block's centre bounds every cell's nearest segment
    to within ``dc + 2 r`` of that centre (``r`` the block's half-diagonal),
    so each cell is measured only against the few segments there, which the
    bucket index finds.

    With a finite ``cut`` (m; NaN for the whole field) only the cells'
    side of ``cut`` is kept where a block's bound settles it: a block whose
    cells all lie farther than ``cut`` (``dc - r`` beyond it, by more than
    1e-9 m, far above the rounding of the distances) is filled with
    ``inf``, one whose cells all lie nearer (``dc + r`` short of it) with
    ``-inf``; the others get their distances. ``out > cut`` is then the
    same mask as on the whole field, without measuring the cells of open
    space, whose blocks have the most segments in reach.
    """
    ny, nx = out.shape
    nbj = (nx + block - 1) // block
    nbi = (ny + block - 1) // block
    r = 0.5 * math.sqrt(2.0) * block * resolution
    for q in nb.prange(nbi * nbj):
        bi = q // nbj
        bj = q % nbj
        cx = x0 + (bj + 0.5) * block * resolution
        cy = y0 + (bi + 0.5) * block * resolution
        dc = indexed_nearest(cx, cy, segments, bx0, by0, bsize, nbx, nby, start, items)
        i_lo = bi * block
        i_hi = min((bi + 1) * block, ny)
        j_lo = bj * block
        j_hi = min((bj + 1) * block, nx)
        fill = np.nan  # the block's cells all on one side of `cut`: their side
        if not math.isfinite(dc) or dc - r - 1e-9 > cut:
            fill = np.inf
        elif dc + r + 1e-9 < cut:
            fill = -np.inf
        if fill == fill:
            for i in range(i_lo, i_hi):
                for j in range(j_lo, j_hi):
                    out[i, j] = fill
            continue
        reach = dc + 2.0 * r + 1e-9
        ja = min(max(int(math.floor((cx - reach - bx0) / bsize)), 0), nbx - 1)
        jb = min(max(int(math.floor((cx + reach - bx0) / bsize)), 0), nbx - 1)
        ia = min(max(int(math.floor((cy - reach - by0) / bsize)), 0), nby - 1)
        ib = min(max(int(math.floor((cy + reach - by0) / bsize)), 0), nby - 1)
        total = 0
        for a in range(ia, ib + 1):
            total += start[a * nbx + jb + 1] - start[a * nbx + ja]
        near = np.empty(total, dtype=np.int64)
        gap = np.empty(total)
        count = 0
        for a in range(ia, ib + 1):
            for t in range(start[a * nbx + ja], start[a * nbx + jb + 1]):
                m = items[t]
                d = point_segment_distance(
                    cx,
                    cy,
                    segments[m, 0],
                    segments[m, 1],
                    segments[m, 2],
                    segments[m, 3],
                )
                if d <= reach:
                    near[count] = m
                    gap[count] = d - r - 1e-9  # no cell of the block is nearer
                    if d == dc:  # the centre's nearest first: a close first bound
                        near[0], near[count] = near[count], near[0]
                        gap[0], gap[count] = gap[count], gap[0]
                    count += 1
        for i in range(i_lo, i_hi):
            py = y0 + (i + 0.5) * resolution
            for j in range(j_lo, j_hi):
                px = x0 + (j + 0.5) * resolution
                best = np.inf
                for t in range(count):
                    if gap[t] > best:  # this wall is farther: the same minimum
                        continue
                    m = near[t]
                    d = point_segment_distance(
                        px, py, segments[m, 0], segments[m, 1], segments[m, 2],
                        segments[m, 3],
                    )  # fmt: skip
                    if d < best:
                        best = d
                out[i, j] = best
