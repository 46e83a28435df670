"""Cone tables on dense maps: each direction's rays through strips of the walls.

The indexed table builder of `robotlib.localization.cones.ConeTable` for
shared rays (a cone's rays a whole number of direction bins apart), in the
manner of a compressed directional distance transform: for each direction
bin the plane is cut into strips parallel to the direction, ``STRIP`` m
wide, and each strip lists the walls that cross it, sorted by where they
begin along the direction. A cell's ray along that bin lies in one strip:
it tries that strip's walls from just behind its origin onward, nearest
first, and stops once the next wall begins beyond its best hit (or the
sonar's reach); the opposite direction's rays use the same strips,
walking back from their origin. Each wall left is tried by `ray_segments`'
own sums, step for step, so every ray finds what the cast against every wall finds: the
nearest hit, the lowest wall index among equal hits
(`robotlib.localization._kernels.tables.cone_table_cells`, bit for bit).

What makes it safe (`strip_lists`): a wall is listed in every strip its
offset across the direction reaches, widened by ``_MU`` (1e-7 m, far above
the rounding of the offsets, about 1e-14 m), and with the part of it inside
the strip's widened bounds spanning ``[vmin, vmax]`` along the direction,
widened by ``_MV`` (1 mm, far above the rounding of a hit's distance for
any wall more than ``_PARALLEL`` (1e-6) rad off the direction). Walls
closer to parallel than that are tried by every ray of their strip. Why it
is fast: the walls a ray tries lie side by side in memory (their end point
and edge vector copied into the strip), about five a ray on
``columbia.map``, most ruled out by comparing two numbers; the cells' rays
are cast strip by strip (`strip_order`), so that a strip's walls are still
in the cache for its next cell; and each direction's rays are written to
their own plane (in the table's own memory), a cone then being the least of
its rays' entries (entries grow with the range, so the least entry is the
entry of the least range: the same number as the cone's nearest echo
gives).

Numba kernels: contiguous arrays and scalars in; they import nothing of
robotlib but the JIT options and other kernels.
"""

import ctypes
import math

import numba as nb
import numpy as np

from ..._config import JIT, JIT_PARALLEL
from ...sensing._kernels import _EPS
from .common import _TWO_PI
from .strip_lists import (
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

STRIP = 0.025
"""Width of the strips, m.

On ``columbia.map`` (points as 2 cm crosses) 0.025 m takes about a tenth
less processor time than 0.05 m (fewer walls of a strip miss the ray's
offset), 0.015-0.035 m about the same, 0.01 m more; likewise on the
generated large map.
"""


@nb.njit(inline="always", **JIT)  # ~12 % sooner, +0.4 s to compile
def strip_ray(
    ox, oy, dx, dy, u0, inv_w, start, firsts, entries, ids, reach, finger, limit
):  # fmt: skip
    """Nearest hit ``(t, m)`` of the ray ``o + t d`` on the walls of its strip.

    ``m`` is the wall's code (`build_strips`), -1 for none. The very ``t``
    and wall of `ray_segments` against every wall whenever the
    nearest hit is nearer than ``limit`` (else a hit beyond it, or none).
    ``finger[k]`` remembers where strip ``k``'s last ray started its search
    (rays of nearby cells start nearby).
    """
    uo = -dy * ox + dx * oy
    vo = dx * ox + dy * oy
    k = int((uo - u0) * inv_w)  # a strip's walls reach _MU into its neighbours
    lo = start[k]
    hi = start[k + 1]
    best = np.inf
    best_m = -1
    first = firsts[k]  # the nearly parallel walls, tried by every ray
    key = vo - reach[k]  # no wall beginning before this reaches the origin
    a = max(finger[k], first)
    while a > first and entries[a - 1, _VMIN] >= key:
        a -= 1
    while a < hi and entries[a, _VMIN] < key:
        a += 1
    finger[k] = a
    q = lo
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
                    best = t
                    best_m = m
                    limit = min(limit, t)
        q += 1
    return best, best_m


@nb.njit(inline="always", **JIT)  # ~12 % sooner, +0.4 s to compile
def strip_ray_back(
    ox, oy, c, s, dx, dy, u0, inv_w, start, firsts, entries, ids, reach, finger,
    limit,
):  # fmt: skip
    """`strip_ray` for the opposite direction ``(dx, dy)`` of the strips' ``(c, s)``.

    The same strips serve both directions: the ray lies in the same strip
    (its offset ``uo`` and position ``vo`` are taken along ``(c, s)``, as
    the strips were made), and it tries the walls that begin at or behind
    its origin, from the nearest down, until the next one ends beyond its
    best hit (``vmin`` below ``vo - limit - reach``). ``finger[k]`` is
    strip ``k``'s first wall beginning beyond the last origin. The hit
    test is `ray_segments`' along ``(dx, dy)``, step for step.
    """
    uo = -s * ox + c * oy
    vo = c * ox + s * oy
    k = int((uo - u0) * inv_w)  # a strip's walls reach _MU into its neighbours
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
        else:  # then down from the origin
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
                    best = t
                    best_m = m
                    limit = min(limit, t)
    return best, best_m


@nb.njit(inline="always", **JIT)  # ~12 % sooner, +0.4 s to compile
def _ray_entry(t, m, bit, max_range, min_range):
    """Table entry (uint16, mm) of one ray's first hit ``(t, m)``, as a cone of one.

    ``m`` is the wall's code (`build_strips`, -1 for none), ``bit`` the
    direction's bit in it: a hit of a wall seen too obliquely reads as no
    echo, as in `_cone`.
    """
    z = max_range
    if m >= 0 and t < max_range:
        if m & bit:
            z = t
    z = min(max(z, min_range), max_range)
    return np.uint16(round(z * 1000.0))


@nb.njit(**JIT)
def strip_order(x0, y0, resolution, ny, nx, c, s, u0, inv_w, n_strips):
    """Return the cells ``i * nx + j`` strip by strip, shape (ny * nx,) int32.

    Strip ``k`` (offsets across ``(c, s)`` from ``u0 + k / inv_w``, m) is
    the one `strip_ray` finds for the cell's centre; within a strip the
    cells keep their row-major order, which runs along the strip. Rays
    taken in this order find their strip's walls and its finger still in
    the cache (on the generated large map about a quarter less processor
    time than row by row); any order gives the same entries.
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
def _direction_rays(
    segments, normals, x0, y0, resolution, b, b2, n_bins, max_range, min_range,
    cos_specular, w, xc, yc, d, n_strips, planes,
):  # fmt: skip
    """Every cell's ray along bin ``b`` and its opposite ``b2`` (unless ``b2 < 0``).

    Both directions' rays go through one set of strips (`build_strips`,
    `strip_ray`, `strip_ray_back`), a strip's cells one after another
    (`strip_order`); the entry of cell ``(i, j)``'s ray along ``b`` goes
    to ``planes[i, b, j]`` (`strip_sweep_table`).
    """
    ny, _, nx = planes.shape
    dx = math.cos(b * _TWO_PI / n_bins)  # as `cone_echo` computes each ray
    dy = math.sin(b * _TWO_PI / n_bins)
    dx2 = dx
    dy2 = dy
    if b2 >= 0:
        dx2 = math.cos(b2 * _TWO_PI / n_bins)
        dy2 = math.sin(b2 * _TWO_PI / n_bins)
    u0 = -dy * xc + dx * yc - 0.5 * d
    start, firsts, entries, ids, reach = build_strips(
        segments, dx, dy, dx2, dy2, u0, w, n_strips, normals, cos_specular
    )
    inv_w = 1.0 / w
    finger = start[:n_strips].copy()
    finger2 = start[:n_strips].copy()
    for cell in strip_order(x0, y0, resolution, ny, nx, dx, dy, u0, inv_w, n_strips):
        i = cell // nx
        j = cell - i * nx
        cy = y0 + (i + 0.5) * resolution
        cx = x0 + (j + 0.5) * resolution
        t, m = strip_ray(
            cx, cy, dx, dy, u0, inv_w, start, firsts, entries, ids, reach,
            finger, max_range,
        )  # fmt: skip
        planes[i, b, j] = _ray_entry(t, m, 1, max_range, min_range)
        if b2 < 0:
            continue
        t, m = strip_ray_back(
            cx, cy, dx, dy, dx2, dy2, u0, inv_w, start, firsts, entries, ids,
            reach, finger2, max_range,
        )  # fmt: skip
        planes[i, b2, j] = _ray_entry(t, m, 2, max_range, min_range)


@nb.njit(**JIT_PARALLEL)
def _strip_rays(
    segments, normals, x0, y0, resolution, n_bins, max_range, min_range,
    cos_specular, w, planes,
):  # fmt: skip
    """Every cell's ray along every bin (`_direction_rays`), pairs in parallel.

    Opposite bins ``b`` and ``b + n_bins / 2`` share their strips (for an
    even ``n_bins``). One parallel loop: the cones follow in `cone_pass`.
    """
    ny, _, nx = planes.shape
    xc, yc, d = strip_frame(segments, x0, y0, nx * resolution, ny * resolution)
    n_strips = int(d / w) + 2
    half = n_bins // 2 if n_bins % 2 == 0 else n_bins
    for b in nb.prange(half):
        b2 = b + half if half < n_bins else -1
        _direction_rays(
            segments, normals, x0, y0, resolution, b, b2, n_bins, max_range,
            min_range, cos_specular, w, xc, yc, d, n_strips, planes,
        )  # fmt: skip


@nb.njit(**JIT)
def cone_pass(n_rays, ray_step, planes, table):
    """Each cone of ``table``: the least of its rays' entries in ``planes``.

    ``planes`` (ny, n_bins, nx) and ``table`` (ny, nx, n_bins) are two views
    of one buffer (row ``i`` of each is the same memory): row by row, the
    row's rays are copied out, its cones taken plane by plane (runs of one
    direction's entries) and written back in the table's layout. One
    thread: on ``columbia.map`` 0.05 s, as fast as two under load, and a
    parallel loop would cost about 2 s more to compile.
    """
    ny, nx, n_bins = table.shape
    half = (n_rays - 1) // 2 if n_rays > 1 else 0
    rays = np.empty((n_bins, nx), dtype=np.uint16)
    row = np.empty((n_bins, nx), dtype=np.uint16)
    for i in range(ny):
        for b in range(n_bins):
            for j in range(nx):
                rays[b, j] = planes[i, b, j]
        for b in range(n_bins):
            for j in range(nx):
                row[b, j] = rays[b, j]
            for q in range(1, half + 1):
                b1 = (b + q * ray_step) % n_bins
                b2 = (b - q * ray_step) % n_bins
                for j in range(nx):
                    row[b, j] = min(row[b, j], rays[b1, j], rays[b2, j])
        for j in range(nx):
            for b in range(n_bins):
                table[i, j, b] = row[b, j]


def strip_sweep_table(
    segments, normals, x0, y0, resolution, n_bins, ray_step, n_rays, max_range,
    min_range, cos_specular, w, table,
):  # fmt: skip
    """Fill ``table`` (ny, nx, n_bins) uint16 mm: shared rays through strips.

    The table of `robotlib.localization._kernels.tables.build_cone_table`
    for shared rays (the same bits): pairs of opposite directions in
    parallel, each pair with its own strips (`build_strips`) and every
    cell's ray along both (`strip_ray`, `strip_ray_back`), the entry of
    cell ``(i, j)``'s ray along bin ``b`` written to ``planes[i, b, j]``,
    ``planes`` being ``table`` seen as (ny, n_bins, nx): each row of cells
    holds its rays plane by plane until `cone_pass` turns them into the
    row's cones, each the least entry of its ``n_rays`` rays ``ray_step``
    bins apart. No memory beyond the table's own (and the strips). ``table``
    must be C-contiguous. ``normals`` are the walls' `tables._unit_normals`.
    """
    ny, nx, _ = table.shape
    planes = table.reshape(ny, n_bins, nx)  # a view: the same buffer
    with nb.parallel_chunksize(1):  # pairs to whichever thread is free
        _strip_rays(
            segments, normals, x0, y0, resolution, n_bins, max_range, min_range,
            cos_specular, w, planes,
        )  # fmt: skip
    _give_back_freed()
    cone_pass(n_rays, ray_step, planes, table)


def _give_back_freed() -> None:
    """Return the strips' freed memory to the system (glibc; elsewhere nothing).

    glibc keeps what each thread frees in that thread's own arena: 17 MB
    after ``columbia.map``'s table, which the filter set up next cannot use.
    """
    try:
        ctypes.CDLL(None).malloc_trim(0)
    except (OSError, AttributeError, TypeError):  # not glibc (Windows: no CDLL(None))
        pass
