"""Cone tables on dense maps: every cell's rays through a bucket index, sooner.

The indexed table builder of `robotlib.localization.cones.ConeTable` for
shared rays (a cone's rays a whole number of direction bins apart): each
cell's ray along each bin is cast once through a bucket index of the walls
and each cone is the nearest echo of its rays. The same numbers as
`robotlib.sensing._kernels.indexed_ray` (and so as the every-wall kernel
`robotlib.localization._kernels.tables.cone_table_cells`), in less time:

- each bucket's walls are copied in bucket order, with their edge vectors
  (`bucket_walls`), so a bucket is read front to back;
- a wall is tested without a division first: the signs and sizes of the
  products that `ray_segments` divides rule most walls out, with a margin
  of 1e-12 (relative) that no rounding reaches, and the walls left are
  tried by `ray_segments`' own sums, step for step;
- the walk looks up its position with reciprocals and checks the distance
  field every `WALK` buckets.

Numba kernels: contiguous arrays and scalars in; they import nothing of
robotlib but the JIT options and other kernels.
"""

import math

import numba as nb
import numpy as np

from ..._config import JIT, JIT_PARALLEL
from ...sensing._kernels import _EPS, ray_segments
from .common import _TWO_PI

WALK = 8
"""Buckets a ray walks before it looks at the distance field again."""

_MARGIN = 1.0 + 1e-12  # relative margin of the division-free tests
_TINY = 1e-280  # products this small decide nothing (no quotient underflows)


@nb.njit(**JIT)
def bucket_walls(segments, items):
    """Copy the walls of every bucket in bucket order: ``(walls, ids)``.

    ``walls[q]`` is ``(px, py, ex, ey)`` of wall ``items[q]``: its first end
    point and ``end - first`` as `ray_segments` computes them (the same
    bits); ``ids[q]`` is its index.
    """
    n = items.shape[0]
    walls = np.empty((n, 4))
    ids = np.empty(n, dtype=np.int64)
    for q in range(n):
        m = items[q]
        px = segments[m, 0]
        py = segments[m, 1]
        walls[q, 0] = px
        walls[q, 1] = py
        walls[q, 2] = segments[m, 2] - px
        walls[q, 3] = segments[m, 3] - py
        ids[q] = m
    return walls, ids


@nb.njit(**JIT, inline="always")
def _bucket_first(ox, oy, dx, dy, walls, ids, lo, hi, best, best_m):
    """`_bucket_hits` over ``walls[lo:hi]``: the same better hit, fewer divisions.

    A wall is ruled out without dividing when ``s < 0``, ``s > 1``, ``t < 0``
    or ``t > best`` holds by more than the margin; the others go through the
    very sums of `ray_segments`.
    """
    for q in range(lo, hi):
        ex = walls[q, 2]
        ey = walls[q, 3]
        denom = dx * ey - dy * ex
        ad = abs(denom)
        if ad < _EPS:
            continue
        wx = walls[q, 0] - ox
        wy = walls[q, 1] - oy
        nt = wx * ey - wy * ex
        ns = wx * dy - wy * dx
        if denom < 0.0:  # t = nt / denom = (-nt) / (-denom), exactly
            nt = -nt
            ns = -ns
        if ns < -_TINY or nt < -_TINY or ns > ad * _MARGIN:
            continue
        if nt > best * ad * _MARGIN + _TINY:  # best = inf: never
            continue
        m = ids[q]
        t = (wx * ey - wy * ex) / denom
        if t < 0.0 or t > best or (t == best and m >= best_m):
            continue
        s = (wx * dy - wy * dx) / denom
        if 0.0 <= s <= 1.0:
            best = t
            best_m = m
    return best, best_m


@nb.njit(**JIT, inline="always")
def first_jump(ox, oy, size, field, fx0, fy0, fres):
    """Where `walk_ray`'s first step from ``(ox, oy)`` lands, whatever the direction.

    The clearance the field shows at the origin (less the slack) when it
    exceeds two buckets, else 0: the very sums of `walk_ray`'s first step.
    """
    fny, fnx = field.shape
    fxf = (ox - fx0) * (1.0 / fres)
    fyf = (oy - fy0) * (1.0 / fres)
    if 0.0 <= fyf < fny and 0.0 <= fxf < fnx:
        clear = field[int(fyf), int(fxf)] - (0.7072 * fres + 1e-9)
        if clear > 2.0 * size:
            return 0.0 + clear
    return 0.0


@nb.njit(**JIT)
def walk_ray(
    ox, oy, dx, dy, segments, walls, ids, x0, y0, size, nbx, nby, start, reach,
    field, fx0, fy0, fres, t_start,
):  # fmt: skip
    """`robotlib.sensing._kernels.indexed_ray` on `bucket_walls`: the same ``(t, m)``.

    Walks the buckets the ray crosses (Amanatides and Woo), jumping over
    the clearance the distance ``field`` (exact at its cells' centres, less
    half a cell's diagonal) shows where it exceeds two buckets, and stops
    at the first bucket holding a hit before the ray leaves it: the nearest
    hit, the lowest index among equals, when nearer than ``reach``. A ray
    from outside the index is cast against every wall. ``t_start`` is
    `first_jump` of the origin (the same for every direction), or 0.
    """
    inv_size = 1.0 / size
    gx = (ox - x0) * inv_size
    gy = (oy - y0) * inv_size
    if not (0.0 <= gx < nbx) or not (0.0 <= gy < nby):
        return ray_segments(ox, oy, dx, dy, segments)
    fny, fnx = field.shape
    inv_fres = 1.0 / fres
    slack = 0.7072 * fres + 1e-9  # > half a cell's diagonal
    jump = 2.0 * size
    best = np.inf
    best_m = -1
    step_j = 1 if dx > 0 else -1
    step_i = 1 if dy > 0 else -1
    adx = abs(dx)
    ady = abs(dy)
    d_x = size / adx if adx > 0.0 else np.inf
    d_y = size / ady if ady > 0.0 else np.inf
    t = t_start
    while t <= reach:
        px = ox + t * dx
        py = oy + t * dy
        fxf = (px - fx0) * inv_fres
        fyf = (py - fy0) * inv_fres
        if 0.0 <= fyf < fny and 0.0 <= fxf < fnx:
            clear = field[int(fyf), int(fxf)] - slack
            if clear > jump:
                t += clear
                continue
        gx = (px - x0) * inv_size
        gy = (py - y0) * inv_size
        if not (0.0 <= gx < nbx and 0.0 <= gy < nby):
            return best, best_m
        j = int(gx)
        i = int(gy)
        t_x = np.inf
        t_y = np.inf
        if adx > 0.0:
            t_x = t + ((j + 1 - gx) if dx > 0 else (gx - j)) * d_x
        if ady > 0.0:
            t_y = t + ((i + 1 - gy) if dy > 0 else (gy - i)) * d_y
        walked = 0
        while True:
            q = i * nbx + j
            best, best_m = _bucket_first(
                ox, oy, dx, dy, walls, ids, start[q], start[q + 1], best, best_m
            )
            t_exit = min(t_x, t_y)
            if best < t_exit - 1e-9 or t_exit > reach:
                return best, best_m
            if t_x < t_y:
                j += step_j
                t_x += d_x
                if j < 0 or j >= nbx:
                    return best, best_m
            else:
                i += step_i
                t_y += d_y
                if i < 0 or i >= nby:
                    return best, best_m
            walked += 1
            if walked >= WALK:  # look for clear space again
                t = t_exit
                break
    return best, best_m


@nb.njit(**JIT_PARALLEL)
def walked_sweep_table(
    segments, normals, walls, ids, x0, y0, resolution, n_bins, ray_step, n_rays,
    max_range, min_range, cos_specular, bx0, by0, bsize, nbx, nby, start, field,
    table,
):  # fmt: skip
    """Fill ``table`` (ny, nx, n_bins) uint16 mm: shared rays by `walk_ray`.

    The table of `robotlib.localization._kernels.tables.indexed_sweep_table`
    (the same bits): per cell, each bin's ray is walked once, kept when
    its wall echoes (``normals``: `tables._unit_normals`), and each cone is
    the nearest echo of its ``n_rays`` rays ``ray_step`` bins apart. ``field``
    is the distance field on the table's own cells. Rows in parallel.
    """
    ny, nx, _ = table.shape
    half = (n_rays - 1) // 2 if n_rays > 1 else 0
    pad = half * ray_step
    dirs = np.empty((n_bins, 2))
    for b in range(n_bins):  # as `cone_echo` computes each ray's direction
        dirs[b, 0] = math.cos(b * _TWO_PI / n_bins)
        dirs[b, 1] = math.sin(b * _TWO_PI / n_bins)
    for i in nb.prange(ny):
        rays = np.empty(n_bins + 2 * pad)
        cy = y0 + (i + 0.5) * resolution
        for j in range(nx):
            cx = x0 + (j + 0.5) * resolution
            t0 = first_jump(cx, cy, bsize, field, x0, y0, resolution)
            for b in range(n_bins):
                dx = dirs[b, 0]
                dy = dirs[b, 1]
                t, m = walk_ray(
                    cx, cy, dx, dy, segments, walls, ids, bx0, by0, bsize, nbx,
                    nby, start, max_range, field, x0, y0, resolution, t0,
                )  # fmt: skip
                r = np.inf
                if m >= 0 and t < max_range:
                    if abs(dx * normals[m, 0] + dy * normals[m, 1]) >= cos_specular:
                        r = t
                rays[pad + b] = r
            for b in range(pad):
                rays[b] = rays[n_bins + b]
                rays[pad + n_bins + b] = rays[pad + b]
            for b in range(n_bins):
                echo = np.inf
                for k in range(b, b + 2 * pad + 1, ray_step):
                    if rays[k] < echo:
                        echo = rays[k]
                z = max_range if echo >= max_range else echo  # `_table_entry`
                z = min(max(z, min_range), max_range)
                table[i, j, b] = np.uint16(round(z * 1000.0))
