"""Numba kernels for world geometry: distances to segments and rasterisation.

Kernels take only contiguous arrays and scalars; the public functions in
`robotlib.world` validate their input and call them.
"""

import math

import numba as nb
import numpy as np

from ._config import JIT, JIT_PARALLEL


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


@nb.njit(**JIT_PARALLEL)
def min_distance_to_segments(points, segments, out):
    """Write into ``out[k]`` the distance of ``points[k]`` to the nearest segment.

    ``points`` is (K, 2), ``segments`` (M, 4) as ``x1, y1, x2, y2``; ``out``
    is (K,) and receives ``inf`` when there are no segments.
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


@nb.njit(**JIT)
def rasterise_segments(segments, x0, y0, resolution, occupied):
    """Mark every cell of ``occupied`` (rows = y, cols = x) that a segment crosses.

    Walks each segment in steps of a quarter cell, which marks every cell the
    segment passes through (and possibly a diagonal neighbour).
    """
    ny, nx = occupied.shape
    for m in range(segments.shape[0]):
        x1 = segments[m, 0]
        y1 = segments[m, 1]
        x2 = segments[m, 2]
        y2 = segments[m, 3]
        length = math.hypot(x2 - x1, y2 - y1)
        steps = int(math.ceil(4.0 * length / resolution)) + 1
        for s in range(steps + 1):
            t = s / steps
            i = int(math.floor((y1 + t * (y2 - y1) - y0) / resolution))
            j = int(math.floor((x1 + t * (x2 - x1) - x0) / resolution))
            if 0 <= i < ny and 0 <= j < nx:
                occupied[i, j] = True


@nb.njit(**JIT)
def flood_fill(free, i0, j0, out):
    """Set ``out`` True on the cells of ``free`` 4-connected to ``(i0, j0)``."""
    ny, nx = free.shape
    stack = np.empty((ny * nx, 2), dtype=np.int64)
    top = 0
    stack[0, 0] = i0
    stack[0, 1] = j0
    top = 1
    out[i0, j0] = True
    while top > 0:
        top -= 1
        i = stack[top, 0]
        j = stack[top, 1]
        for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            a = i + di
            b = j + dj
            if 0 <= a < ny and 0 <= b < nx and free[a, b] and not out[a, b]:
                out[a, b] = True
                stack[top, 0] = a
                stack[top, 1] = b
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
