"""The cone table: expected sonar ranges per cell and direction bin, built and read.

``table[i, j, b]`` (uint16, mm) is what a noise-free sonar at the centre of
cell ``(i, j)`` (``x0 + (j + 0.5) * res``, ``y0 + (i + 0.5) * res``),
pointing along ``b * 2 pi / n_bins``, reads: the nearest echo of its
cone's rays, clipped to ``[min_range, max_range]``. Each ray lies along a
direction bin (``offsets`` bins from the cone's axis), so a ray is cast once
per cell and direction and shared by every cone that holds it.

How the rays are cast (`build_cone_table`): for each direction the plane
is cut into strips parallel to it, `STRIP` m wide, each listing the walls
that cross it sorted by where they begin along the direction
(`cone_strips.build_strips`). A cell's ray lies in one strip; it tries that
strip's walls from just behind its origin onward, nearest first, and stops
once the next wall begins beyond its best hit (or the sonar's reach). The
opposite direction's rays use the same strips, walking backwards. Each wall
tried is tried with `robotlib.sensing._kernels.ray_segments`' own
arithmetic, so every ray finds what a cast against every wall finds: the
nearest hit, the lowest wall index among equal hits, then the specular test
of `robotlib.sensing._kernels.cone_echo`. Time grows with the walls near
each ray, not with all of them (MobileSim's ``columbia.map``: 127,092
segments). Each direction's entries go to a plane of their own (in the
table's own memory) and `cone_pass` then takes each cone as the least of
its rays' entries (entries grow with the range, so that is the entry of
the nearest echo).

`expected_table` reads the table for many particles (`pieces.table_mm`).

Numba kernels: contiguous arrays and scalars in; they import nothing of
robotlib but the JIT options and other kernels.
"""

import math

import numba as nb
import numpy as np

from ..._config import JIT, JIT_PARALLEL, serial_and_parallel
from ...sensing._kernels import _EPS
from .cone_strips import (
    _EX,
    _EY,
    _PX,
    _PY,
    _UHI,
    _ULO,
    _VMAX,
    _VMIN,
    build_strips,
    strip_frame,
)
from .pieces import TWO_PI, sensor_pose, table_mm

STRIP = 0.025
"""Width of the strips, m.

On ``columbia.map`` (points as 2 cm crosses) 0.025 m takes about a tenth
less processor time than 0.05 m (fewer of a strip's walls miss the ray's
offset); 0.015-0.035 m about the same, 0.01 m more.
"""


@nb.njit(**JIT, inline="always")
def _try_wall(q, ox, oy, dx, dy, entries, ids, best, best_m, limit):
    """Intersect the ray ``o + t d`` with strip entry ``q``; keep the nearer hit.

    Returns the new ``(best, best_m, limit)``: the entry's ``t`` and wall
    code if the ray hits it nearer than ``best`` (or as near, with a lower
    code, so that ties go as in a cast against every wall), else the old.
    """
    ex = entries[q, _EX]
    ey = entries[q, _EY]
    denom = dx * ey - dy * ex  # `ray_segments`, step for step
    if abs(denom) >= _EPS:
        wx = entries[q, _PX] - ox
        wy = entries[q, _PY] - oy
        t = (wx * ey - wy * ex) / denom
        m = ids[q]
        if t >= 0.0 and (t < best or (t == best and m < best_m)):
            sp = (wx * dy - wy * dx) / denom
            if 0.0 <= sp <= 1.0:
                return t, m, min(limit, t)
    return best, best_m, limit


@nb.njit(**JIT, inline="always")
def strip_ray(
    ox, oy, dx, dy, u0, inv_w, start, firsts, entries, ids, reach, finger, limit
):  # fmt: skip
    """Nearest hit ``(t, m)`` of the ray ``o + t d`` on the walls of its strip.

    ``start, firsts, entries, ids, reach`` are `cone_strips.build_strips`'
    strips for ``(dx, dy)``; ``m`` is the wall's code there (-1 for none).
    The very ``t`` and wall a cast against every wall finds whenever that
    hit is nearer than ``limit``
    (else a hit beyond it, or none). ``finger[k]`` remembers where strip
    ``k``'s last ray began its search (rays of nearby cells begin nearby).
    """
    uo = -dy * ox + dx * oy
    vo = dx * ox + dy * oy
    k = int((uo - u0) * inv_w)
    hi = start[k + 1]
    best = np.inf
    best_m = -1
    first = firsts[k]  # before it, the nearly parallel walls: tried by every ray
    key = vo - reach[k]  # no wall beginning before this reaches the origin
    a = max(finger[k], first)
    while a > first and entries[a - 1, _VMIN] >= key:
        a -= 1
    while a < hi and entries[a, _VMIN] < key:
        a += 1
    finger[k] = a
    q = start[k]
    while q < hi:
        if q == first:
            q = a
            if q >= hi:
                break
        if q >= first and entries[q, _VMIN] - vo > limit:
            break
        if entries[q, _VMAX] < vo or entries[q, _ULO] > uo or entries[q, _UHI] < uo:
            q += 1
            continue
        best, best_m, limit = _try_wall(
            q, ox, oy, dx, dy, entries, ids, best, best_m, limit
        )
        q += 1
    return best, best_m


@nb.njit(**JIT, inline="always")
def strip_ray_back(
    ox, oy, c, s, dx, dy, u0, inv_w, start, firsts, entries, ids, reach, finger,
    limit,
):  # fmt: skip
    """`strip_ray` along ``(dx, dy)``, the opposite of the strips' ``(c, s)``.

    The ray lies in the same strip (its offset ``uo`` and position ``vo``
    are taken along ``(c, s)``, as the strips were made); it tries the walls
    that begin at or behind its origin, nearest first, until the next one
    ends before its best hit. ``finger[k]`` is strip ``k``'s first wall
    beginning beyond the last origin.
    """
    uo = -s * ox + c * oy
    vo = c * ox + s * oy
    k = int((uo - u0) * inv_w)
    lo = start[k]
    hi = start[k + 1]
    best = np.inf
    best_m = -1
    first = firsts[k]
    a = max(finger[k], first)
    while a > first and entries[a - 1, _VMIN] > vo:
        a -= 1
    while a < hi and entries[a, _VMIN] <= vo:
        a += 1
    finger[k] = a
    n_par = first - lo
    r = 0
    while True:
        if r < n_par:  # the nearly parallel walls first
            q = lo + r
        else:  # then backwards from the origin
            q = a - 1 - (r - n_par)
            if q < first or entries[q, _VMIN] < vo - limit - reach[k]:
                break
        r += 1
        if (
            entries[q, _VMAX] < vo - limit
            or entries[q, _ULO] > uo
            or entries[q, _UHI] < uo
        ):
            continue
        best, best_m, limit = _try_wall(
            q, ox, oy, dx, dy, entries, ids, best, best_m, limit
        )
    return best, best_m


@nb.njit(**JIT, inline="always")
def _ray_entry(t, m, bit, max_range, min_range):
    """Table entry (uint16, mm) of one ray's nearest hit ``(t, m)``.

    ``m`` is the wall's code (`cone_strips.build_strips`, -1 for none) and
    ``bit`` the direction's bit in it: a wall met too obliquely gives no
    echo, as in `robotlib.sensing._kernels.cone_echo`.
    """
    z = max_range
    if m >= 0 and t < max_range and m & bit:
        z = t
    z = min(max(z, min_range), max_range)
    return np.uint16(round(z * 1000.0))


@nb.njit(**JIT)
def strip_order(x0, y0, resolution, ny, nx, c, s, u0, inv_w, n_strips):
    """Return the cells ``i * nx + j`` strip by strip, shape (ny * nx,) int32.

    Rays cast in this order find their strip's walls still in the cache (on
    a large map about a quarter less processor time than row by row); any
    order gives the same entries.
    """
    count = np.zeros(n_strips + 1, dtype=np.int64)
    for i in range(ny):
        cy = y0 + (i + 0.5) * resolution
        for j in range(nx):
            cx = x0 + (j + 0.5) * resolution
            count[int((-s * cx + c * cy - u0) * inv_w) + 1] += 1
    for k in range(n_strips):
        count[k + 1] += count[k]
    order = np.empty(ny * nx, dtype=np.int32)
    for i in range(ny):
        cy = y0 + (i + 0.5) * resolution
        for j in range(nx):
            cx = x0 + (j + 0.5) * resolution
            k = int((-s * cx + c * cy - u0) * inv_w)
            order[count[k]] = i * nx + j
            count[k] += 1
    return order


@nb.njit(**JIT)
def direction_rays(
    segments, normals, x0, y0, resolution, b, b2, n_bins, max_range, min_range,
    cos_specular, xc, yc, d, planes,
):  # fmt: skip
    """Every cell's ray along bin ``b``, and along ``b2`` unless ``b2 < 0``.

    ``b2`` is the opposite bin: both go through one set of strips. The
    entry of cell ``(i, j)``'s ray along ``b`` goes to ``planes[i, b, j]``
    (``planes``: (ny, n_bins, nx)). ``(xc, yc, d)`` is `strip_frame`'s box.
    """
    ny, _, nx = planes.shape
    dx = math.cos(b * TWO_PI / n_bins)  # as `cone_echo` computes a ray
    dy = math.sin(b * TWO_PI / n_bins)
    dx2 = dx
    dy2 = dy
    if b2 >= 0:
        dx2 = math.cos(b2 * TWO_PI / n_bins)
        dy2 = math.sin(b2 * TWO_PI / n_bins)
    n_strips = int(d / STRIP) + 2
    u0 = -dy * xc + dx * yc - 0.5 * d
    inv_w = 1.0 / STRIP
    start, firsts, entries, ids, reach = build_strips(
        segments, dx, dy, dx2, dy2, u0, STRIP, n_strips, normals, cos_specular
    )
    finger = start[:n_strips].copy()
    finger2 = start[:n_strips].copy()
    for cell in strip_order(x0, y0, resolution, ny, nx, dx, dy, u0, inv_w, n_strips):
        i = cell // nx
        j = cell - i * nx
        cy = y0 + (i + 0.5) * resolution
        cx = x0 + (j + 0.5) * resolution
        t, m = strip_ray(
            cx, cy, dx, dy, u0, inv_w, start, firsts, entries, ids, reach, finger,
            max_range,
        )  # fmt: skip
        planes[i, b, j] = _ray_entry(t, m, 1, max_range, min_range)
        if b2 >= 0:
            t, m = strip_ray_back(
                cx, cy, dx, dy, dx2, dy2, u0, inv_w, start, firsts, entries, ids,
                reach, finger2, max_range,
            )  # fmt: skip
            planes[i, b2, j] = _ray_entry(t, m, 2, max_range, min_range)


@nb.njit(**JIT_PARALLEL)
def all_rays(
    segments, normals, x0, y0, resolution, max_range, min_range, cos_specular,
    planes,
):  # fmt: skip
    """Every cell's ray along every bin (`direction_rays`), pairs of bins in parallel.

    Bins ``b`` and ``b + n_bins / 2`` share their strips when ``n_bins`` is
    even; with an odd count each bin has its own.
    """
    ny, n_bins, nx = planes.shape
    xc, yc, d = strip_frame(segments, x0, y0, nx * resolution, ny * resolution)
    half = n_bins // 2 if n_bins % 2 == 0 else n_bins
    for b in nb.prange(half):
        b2 = b + half if half < n_bins else -1
        direction_rays(
            segments, normals, x0, y0, resolution, b, b2, n_bins, max_range,
            min_range, cos_specular, xc, yc, d, planes,
        )  # fmt: skip


@nb.njit(**JIT)
def cone_pass(offsets, planes, table):
    """Turn each row of rays into the row's cones, in place.

    ``planes`` (ny, n_bins, nx) and ``table`` (ny, nx, n_bins) are two views
    of one buffer (row ``i`` of each is the same memory). Row by row the
    rays are copied out, and ``table[i, j, b]`` becomes the least of the
    entries of the rays along bins ``b + offsets`` (mod ``n_bins``).
    """
    ny, nx, n_bins = table.shape
    rays = np.empty((n_bins, nx), dtype=np.uint16)
    row = np.empty((n_bins, nx), dtype=np.uint16)
    for i in range(ny):
        for b in range(n_bins):
            for j in range(nx):
                rays[b, j] = planes[i, b, j]
        for b in range(n_bins):
            for j in range(nx):
                row[b, j] = 0xFFFF
            for o in offsets:
                bo = (b + o) % n_bins
                for j in range(nx):
                    row[b, j] = min(row[b, j], rays[bo, j])
        for j in range(nx):
            for b in range(n_bins):
                table[i, j, b] = row[b, j]


def unit_normals(segments):
    """Each wall's unit normal ``(-ey, ex) / length``, shape (M, 2).

    The very numbers `robotlib.sensing._kernels.cone_echo` computes (the same
    IEEE operations in the same order); a wall of length 0 gets NaN.
    """
    ex = segments[:, 2] - segments[:, 0]
    ey = segments[:, 3] - segments[:, 1]
    length = np.sqrt(ex * ex + ey * ey)
    out = np.empty((segments.shape[0], 2))
    with np.errstate(invalid="ignore", divide="ignore"):
        out[:, 0] = -ey / length
        out[:, 1] = ex / length
    return out


def build_cone_table(
    segments, x0, y0, resolution, offsets, max_range, min_range, cos_specular, table
):  # fmt: skip
    """Fill ``table`` (ny, nx, n_bins) uint16, C-contiguous, with cone ranges in mm.

    Parameters
    ----------
    segments : numpy.ndarray, shape (M, 4), float64
        The walls ``(x1, y1, x2, y2)``, m.
    x0, y0 : float
        Lower-left corner of cell ``[0, 0]``, m.
    resolution : float
        Cell side, m.
    offsets : numpy.ndarray, shape (R,), int64
        The cone's rays, in direction bins from its axis.
    max_range, min_range : float
        The sonar's range limits, m.
    cos_specular : float
        Cosine of the largest angle of incidence that still echoes.
    table : numpy.ndarray, shape (ny, nx, n_bins), uint16
        Filled in place (see the module's docstring).
    """
    if not table.flags.c_contiguous or table.dtype != np.uint16:
        raise ValueError("the cone table must be C-contiguous uint16")
    segments = np.ascontiguousarray(segments, dtype=np.float64).reshape(-1, 4)
    ny, nx, n_bins = table.shape
    planes = table.reshape(ny, n_bins, nx)  # a view: the same buffer
    with nb.parallel_chunksize(1):  # pairs of bins to whichever thread is free
        all_rays(
            segments, unit_normals(segments), x0, y0, resolution, max_range,
            min_range, cos_specular, planes,
        )  # fmt: skip
    cone_pass(np.ascontiguousarray(offsets, dtype=np.int64), planes, table)


def _expected_table(particles, sensors, table, x0, y0, inv_res, out):
    """Sonar ranges ``out`` (N, S), m, looked up in a cone table (mm).

    ``particles`` (N, 3) are poses (m, rad), ``sensors`` (S, 3) the sonars'
    poses on the robot; each sensor's position selects the cell (clamped to
    the grid of ``1 / inv_res`` m cells from ``(x0, y0)``), its heading the
    nearest direction bin (`pieces.table_mm`).
    """
    for n in nb.prange(particles.shape[0]):
        x = particles[n, 0]
        y = particles[n, 1]
        th = particles[n, 2]
        c = math.cos(th)
        s = math.sin(th)
        for i in range(sensors.shape[0]):
            sx, sy, sth = sensor_pose(x, y, th, c, s, sensors, i)
            out[n, i] = table_mm(table, x0, y0, inv_res, sx, sy, sth) * 0.001


expected_table, expected_table_parallel = serial_and_parallel(_expected_table)
