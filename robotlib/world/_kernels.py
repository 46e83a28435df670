"""Numba kernels for world geometry: distances to segments and rasterisation.

Kernels take only contiguous arrays and scalars; the public functions in
`robotlib.world` validate their input and call them.
"""

import math

import numba as nb
import numpy as np

from .._config import JIT, JIT_PARALLEL


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
