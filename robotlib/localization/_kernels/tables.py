"""Cone tables: expected sonar ranges per grid cell and heading bin, built and read.

Numba kernels: contiguous arrays and scalars in, no Python objects; they
import nothing of robotlib but the JIT options and other kernels.
"""

import math

import numba as nb
import numpy as np

from ..._config import JIT, JIT_PARALLEL, jit_inner, serial_and_parallel
from ...sensing._kernels import _EPS, cone_echo, indexed_cone_echo
from ...world._kernels import point_segment_distance
from .common import _TWO_PI
from .elementary import sincos
from .table_strips import STRIP, strip_sweep_table


@jit_inner
def _pseudo_atan2(y, x):
    """``math.atan2(y, x)`` within 1e-5 rad (a polynomial; for bin ranges only)."""
    ax = abs(x)
    ay = abs(y)
    # min and max spelled as numba's builtins compute them (``max(a, b)`` is
    # ``b if b > a else a``): no builtin for numba to compile on a cold start
    hi = ay if ay > ax else ax
    if hi == 0.0:
        return 0.0
    a = (ay if ay < ax else ax) / hi
    s = a * a
    r = ((-0.0464964749 * s + 0.15931422) * s - 0.327622764) * s * a + a
    if ay > ax:
        r = 0.5 * math.pi - r
    if x < 0.0:
        r = math.pi - r
    return -r if y < 0.0 else r


_SORT_MAX = 256
"""Walls near a block up to which `_ray_echoes` sorts them (beyond: in order)."""


@jit_inner
def _ray_echoes(
    cx, cy, segments, normals, max_range, cos_specular, dirs, best, best_m, rays,
    pad, dist, order,
):  # fmt: skip
    """Single-ray echoes from ``(cx, cy)`` along every direction bin, into ``rays``.

    ``rays[b]`` is `robotlib.sensing._kernels.cone_echo` of one ray along
    ``dirs[b]`` (the cosine and sine of ``b * 2 pi / n_bins``): each ray's
    nearest hit, the lowest wall index among equal hits. Walls further than
    ``max_range`` are left out; the others are taken nearest first, each
    tried only on the bins within two bins of the directions it subtends
    (all bins when it nearly faces the point), and on a bin only while the
    ray's hit so far is not nearer than the wall itself; once every ray has
    a hit nearer than the next wall, the rest are left out (more than
    `_SORT_MAX` walls are taken in order, none left out). No pair left out
    can be a hit the ray keeps, and equal hits go to the lower index, so the
    echoes are the same numbers as the cast against every wall. ``normals``
    are the walls' `_unit_normals`. The echoes go to ``rays[pad:pad +
    n_bins]``, and the ``pad`` bins before and after the turn to both ends
    (a cone's rays read without wrapping). ``best``, ``best_m`` (n_bins,)
    and ``dist``, ``order`` (M,) are scratch.
    """
    n_bins = dirs.shape[0]
    w = _TWO_PI / n_bins
    for b in range(n_bins):
        best[b] = np.inf
        best_m[b] = -1
    far = max_range * (1.0 + 1e-9) + 1e-9
    k = 0
    ordered = segments.shape[0] <= _SORT_MAX
    for m in range(segments.shape[0]):  # the walls in reach, nearest first
        d = point_segment_distance(
            cx, cy, segments[m, 0], segments[m, 1], segments[m, 2], segments[m, 3]
        )
        if d > far:
            continue
        j = k
        while ordered and j > 0 and dist[j - 1] > d:
            dist[j] = dist[j - 1]
            order[j] = order[j - 1]
            j -= 1
        dist[j] = d
        order[j] = m
        k += 1
    open_rays = n_bins  # rays with no hit yet
    worst = 0.0  # once every ray has a hit: at least the farthest (or stale, 0)
    for q in range(k):
        m = order[q]
        near = dist[q] * (1.0 - 1e-9) - 1e-12  # below any hit on wall m
        if ordered and open_rays == 0 and near > worst:
            worst = 0.0
            for b in range(n_bins):
                if best[b] > worst:  # max(worst, best[b]), as `_pseudo_atan2`
                    worst = best[b]
            if near > worst:
                break  # every ray has a hit nearer than the walls left
        px = segments[m, 0]
        py = segments[m, 1]
        qx = segments[m, 2]
        qy = segments[m, 3]
        ex = qx - px
        ey = qy - py
        wx = px - cx
        wy = py - cy
        vx = qx - cx
        vy = qy - cy
        first = 0
        count = n_bins
        if wx * wx + wy * wy > 1e-18 and vx * vx + vy * vy > 1e-18:
            a0 = _pseudo_atan2(wy, wx)
            span = _pseudo_atan2(vy, vx) - a0
            if span > math.pi:
                span -= _TWO_PI
            elif span <= -math.pi:
                span += _TWO_PI
            if abs(span) < math.pi - 5.0 * w:
                lo = a0 if span >= 0.0 else a0 + span  # floor, ceil: int64 in numba
                first = math.floor(lo / w) - 2
                count = math.ceil((lo + abs(span)) / w) + 3 - first
                if n_bins < count:  # min(count, n_bins)
                    count = n_bins
        b = first % n_bins - 1
        for _ in range(count):
            b += 1
            if b == n_bins:
                b = 0
            if best[b] < near:
                continue
            dx = dirs[b, 0]
            dy = dirs[b, 1]
            denom = dx * ey - dy * ex  # `ray_segments`, step for step
            if abs(denom) < _EPS:
                continue
            t = (wx * ey - wy * ex) / denom
            if t < 0.0 or t > best[b] or (t == best[b] and m > best_m[b]):
                continue
            s = (wx * dy - wy * dx) / denom
            if 0.0 <= s <= 1.0:
                if best_m[b] < 0:
                    open_rays -= 1
                best[b] = t
                best_m[b] = m
    for b in range(n_bins):  # `_cone`'s echo test on each ray's first hit
        t = best[b]
        m = best_m[b]
        rays[pad + b] = np.inf
        if m < 0 or t >= max_range:
            continue
        cos_inc = abs(dirs[b, 0] * normals[m, 0] + dirs[b, 1] * normals[m, 1])
        if cos_inc >= cos_specular:
            rays[pad + b] = t
    for b in range(pad):  # the turn continued on both sides
        rays[b] = rays[n_bins + b]
        rays[pad + n_bins + b] = rays[pad + b]


@jit_inner
def _unit_normals(segments):
    """Each wall's unit normal ``(-ey, ex) / length`` as `_cone` computes it, (M, 2).

    For the kernels; Python takes `unit_normals` (the same numbers).
    """
    out = np.empty((segments.shape[0], 2))
    for m in range(segments.shape[0]):
        ex = segments[m, 2] - segments[m, 0]
        ey = segments[m, 3] - segments[m, 1]
        length = math.sqrt(ex * ex + ey * ey)
        out[m, 0] = -ey / length
        out[m, 1] = ex / length
    return out


def unit_normals(segments):
    """`_unit_normals` in NumPy, for Python callers: the same bits.

    Each entry is the same IEEE operations in the same order (two products,
    a sum, a square root, a division; no fused multiply-add either way), and
    each is correctly rounded in both. A point (a wall of length 0) gets
    NaN normals, as in the kernel, and no warning.
    """
    ex = segments[:, 2] - segments[:, 0]
    ey = segments[:, 3] - segments[:, 1]
    length = np.sqrt(ex * ex + ey * ey)
    out = np.empty((segments.shape[0], 2))
    with np.errstate(invalid="ignore", divide="ignore"):
        out[:, 0] = -ey / length
        out[:, 1] = ex / length
    return out


@jit_inner
def _table_entry(echo, max_range, min_range):
    """Return the table entry (uint16, mm) of a cone's echo (m, ``inf`` for none)."""
    z = max_range if echo >= max_range else echo
    if min_range > z:  # min(max(z, min_range), max_range), as `_pseudo_atan2`
        z = min_range
    if max_range < z:
        z = max_range
    return np.uint16(round(z * 1000.0))


@jit_inner
def _near_walls(segments, bx, by, reach):
    """Copy the walls within ``reach`` of ``(bx, by)``, in order, to a new (K, 4)."""
    keep = np.empty(segments.shape[0], dtype=np.bool_)  # each written: no np.zeros
    count = 0
    for m in range(segments.shape[0]):
        d = point_segment_distance(
            bx, by, segments[m, 0], segments[m, 1], segments[m, 2], segments[m, 3]
        )
        keep[m] = d <= reach
        if keep[m]:
            count += 1
    near = np.empty((count, 4))
    c = 0
    for m in range(segments.shape[0]):
        if keep[m]:
            for t in range(4):
                near[c, t] = segments[m, t]
            c += 1
    return near


def _sweep_table(
    segments, x0, y0, resolution, n_bins, ray_step, n_rays, max_range, min_range,
    cos_specular, block, table,
):  # fmt: skip
    """`build_cone_table` for shared rays (``ray_step > 0``): the sweep."""
    ny, nx, _ = table.shape
    nbx = (nx + block - 1) // block
    nby = (ny + block - 1) // block
    reach = max_range + 0.75 * block * resolution  # > max_range + half diagonal
    half = (n_rays - 1) // 2 if n_rays > 1 else 0
    for q in nb.prange(nbx * nby):
        bi = q // nbx
        bj = q % nbx
        near = _near_walls(
            segments, x0 + (bj + 0.5) * block * resolution,
            y0 + (bi + 0.5) * block * resolution, reach,
        )  # fmt: skip
        normals = _unit_normals(near)
        pad = half * ray_step
        rays = np.empty(n_bins + 2 * pad)
        best = np.empty(n_bins)
        best_m = np.empty(n_bins, dtype=np.int64)
        dist = np.empty(near.shape[0])
        order = np.empty(near.shape[0], dtype=np.int64)
        dirs = np.empty((n_bins, 2))
        for b in range(n_bins):  # as `cone_echo` computes each ray's direction
            dirs[b, 0] = math.cos(b * _TWO_PI / n_bins)
            dirs[b, 1] = math.sin(b * _TWO_PI / n_bins)
        i_end = (bi + 1) * block
        if ny < i_end:  # min(i_end, ny), as `_pseudo_atan2`
            i_end = ny
        j_end = (bj + 1) * block
        if nx < j_end:
            j_end = nx
        for i in range(bi * block, i_end):
            cy = y0 + (i + 0.5) * resolution
            for j in range(bj * block, j_end):
                cx = x0 + (j + 0.5) * resolution
                _ray_echoes(
                    cx, cy, near, normals, max_range, cos_specular, dirs, best,
                    best_m, rays, pad, dist, order,
                )  # fmt: skip
                for b in range(n_bins):
                    echo = np.inf
                    for k in range(b, b + 2 * pad + 1, ray_step):
                        r = rays[k]
                        if r < echo:
                            echo = r
                    table[i, j, b] = _table_entry(echo, max_range, min_range)


sweep_table, sweep_table_parallel = serial_and_parallel(_sweep_table)


def compile_sweep_helpers(segments=None) -> None:
    """Compile `_sweep_table`'s helpers ahead of it: `_ray_echoes`, or the others.

    Without ``segments``, `_ray_echoes` (the largest); given the walls (M, 4)
    the sweep will take (its first argument), the others. With a helper
    process at work (`robotlib.localization._prebuild`), `ConeTable`
    compiles the first before its sweep and the helper the others
    meanwhile, into numba's cache, where the sweep's compile then finds
    them (for the sweep's argument types). The same table.
    """
    f8, a1, a2, i1 = nb.float64, nb.float64[::1], nb.float64[:, ::1], nb.int64[::1]
    if segments is None:
        _ray_echoes.compile((f8, f8, a2, a2, f8, f8, a2, a1, i1, a1, nb.int64, a1, i1))
        return
    _near_walls.compile((nb.typeof(segments), f8, f8, f8))
    _unit_normals.compile((a2,))
    _table_entry.compile((f8, f8, f8))


@nb.njit(**JIT_PARALLEL)
def cone_cast_table(
    segments, x0, y0, resolution, n_bins, n_rays, cone, max_range, min_range,
    cos_specular, block, table,
):  # fmt: skip
    """`build_cone_table` for whole cones (``ray_step == 0``): each cone cast."""
    ny, nx, _ = table.shape
    nbx = (nx + block - 1) // block
    nby = (ny + block - 1) // block
    reach = max_range + 0.75 * block * resolution  # > max_range + half diagonal
    for q in nb.prange(nbx * nby):
        bi = q // nbx
        bj = q % nbx
        near = _near_walls(
            segments, x0 + (bj + 0.5) * block * resolution,
            y0 + (bi + 0.5) * block * resolution, reach,
        )  # fmt: skip
        for i in range(bi * block, min((bi + 1) * block, ny)):
            cy = y0 + (i + 0.5) * resolution
            for j in range(bj * block, min((bj + 1) * block, nx)):
                cx = x0 + (j + 0.5) * resolution
                for b in range(n_bins):
                    echo = cone_echo(
                        cx, cy, b * _TWO_PI / n_bins, near, n_rays, cone, max_range,
                        cos_specular,
                    )  # fmt: skip
                    table[i, j, b] = _table_entry(echo, max_range, min_range)


SERIAL_MAX_WORK = 20_000_000
"""Cells times walls up to which `build_cone_table` sweeps on one thread.

The serial kernel compiles in about 1.5 s less processor time than the
parallel one on an empty numba cache, and a table is built once per map
and model (then read from the disk cache, see
`robotlib.localization.cones.table_cache_dir`): the corridor (92,800 cells,
44 walls) takes 0.24 s on one thread, the office (134,400, 113) 0.44 s.
"""


def build_cone_table(
    segments, x0, y0, resolution, n_bins, ray_step, n_rays, cone, max_range,
    min_range, cos_specular, block, table,
):  # fmt: skip
    """Fill ``table`` (ny, nx, n_bins) uint16 with cone ranges in mm.

    ``table[i, j, b]`` is the expected range of a sonar at the centre of cell
    ``(i, j)`` pointing along ``b * 2 pi / n_bins``. When the cone's rays are
    ``ray_step`` bins apart (``ray_step > 0``) each direction's single ray is
    cast once and a cone is the nearest echo of its ``n_rays`` rays, which is
    what `sonar_cone` computes (`sweep_table`, on one thread for a table of
    at most `SERIAL_MAX_WORK` cells times walls); otherwise (``ray_step ==
    0``) every cone is cast with `sonar_cone` (`cone_cast_table`).

    Cells are filled in square blocks of ``block`` cells (in parallel), each
    against only the walls that come within ``max_range`` of the block: a
    wall further away cannot echo, so the table is the same as with all
    walls.
    """
    if ray_step == 0:
        cone_cast_table(
            segments, x0, y0, resolution, n_bins, n_rays, cone, max_range,
            min_range, cos_specular, block, table,
        )  # fmt: skip
        return
    work = table.shape[0] * table.shape[1] * segments.shape[0]
    kernel = sweep_table if work <= SERIAL_MAX_WORK else sweep_table_parallel
    kernel(
        segments, x0, y0, resolution, n_bins, ray_step, n_rays, max_range,
        min_range, cos_specular, block, table,
    )  # fmt: skip


@nb.njit(**JIT_PARALLEL)
def indexed_cone_table(
    segments, x0, y0, resolution, n_bins, n_rays, cone, max_range, min_range,
    cos_specular, bx0, by0, bsize, nbx, nby, start, items, field, table,
):  # fmt: skip
    """`build_cone_table_indexed` for whole cones (``ray_step == 0``)."""
    ny, nx, _ = table.shape
    for i in nb.prange(ny):
        cy = y0 + (i + 0.5) * resolution
        for j in range(nx):
            cx = x0 + (j + 0.5) * resolution
            for b in range(n_bins):
                echo = indexed_cone_echo(
                    cx, cy, b * _TWO_PI / n_bins, segments, n_rays, cone,
                    max_range, cos_specular, bx0, by0, bsize, nbx, nby, start,
                    items, field, x0, y0, resolution,
                )  # fmt: skip
                table[i, j, b] = _table_entry(echo, max_range, min_range)


def build_cone_table_strips(
    segments, x0, y0, resolution, n_bins, ray_step, n_rays, cone, max_range,
    min_range, cos_specular, table,
):  # fmt: skip
    """`build_cone_table` for shared rays (``ray_step > 0``) on dense maps.

    The same table, each direction's rays cast through strips of the walls
    (`table_strips.strip_sweep_table`): time grows with the walls near each
    ray rather than with all of them, for maps of many walls or points
    (MobileSim's ``columbia.map``: 127,092 segments). ``cone`` is unused
    (the rays are ``ray_step`` bins apart).
    """
    if ray_step <= 0:
        raise ValueError("the strips builder casts shared rays: ray_step > 0")
    segments = np.ascontiguousarray(segments, dtype=np.float64)
    if not table.flags.c_contiguous:
        raise ValueError("the strips builder fills a C-contiguous table")
    strip_sweep_table(
        segments, unit_normals(segments), x0, y0, resolution, n_bins, ray_step,
        n_rays, max_range, min_range, cos_specular, STRIP, table,
    )  # fmt: skip


def build_cone_table_indexed(
    segments, x0, y0, resolution, n_bins, ray_step, n_rays, cone, max_range,
    min_range, cos_specular, bx0, by0, bsize, nbx, nby, start, items, field,
    table,
):  # fmt: skip
    """`build_cone_table` with every ray cast through a bucket index of the walls.

    The same table (each ray finds the same nearest wall, see
    `robotlib.sensing._kernels.indexed_ray`), in time that grows with the
    walls near each ray rather than with all of them: for maps of many
    walls or points. ``field`` is the distance field on the table's own
    cells (rays jump over clear space with it). Whole cones (``ray_step ==
    0``) are cast through the index in parallel rows (`indexed_cone_table`);
    shared rays go to `build_cone_table_strips` (the index is not needed).
    """
    if ray_step > 0:
        build_cone_table_strips(
            segments, x0, y0, resolution, n_bins, ray_step, n_rays, cone,
            max_range, min_range, cos_specular, table,
        )  # fmt: skip
    else:
        indexed_cone_table(
            segments, x0, y0, resolution, n_bins, n_rays, cone, max_range,
            min_range, cos_specular, bx0, by0, bsize, nbx, nby, start, items,
            field, table,
        )  # fmt: skip


@nb.njit(**JIT)
def cone_table_cells(
    segments, x0, y0, resolution, rows, cols, n_bins, ray_step, n_rays, cone,
    max_range, min_range, cos_specular, out,
):  # fmt: skip
    """Compute `build_cone_table`'s entries for chosen cells by their plain definition.

    ``out[k, b]`` (uint16, mm) is the entry of cell ``(rows[k], cols[k])``:
    the cell's centre ``(x0 + (col + 0.5) * resolution, y0 + (row + 0.5) *
    resolution)`` (the builders' own arithmetic), a cone along
    ``b * 2 pi / n_bins`` cast against every wall by
    `robotlib.sensing._kernels.cone_echo`; with ``ray_step > 0`` each ray
    along its own direction bin and the cone the nearest echo of its
    ``n_rays`` rays. No culling, no index, no sharing between cells: the
    reference the fast builders must equal bit for bit.
    """
    half = (n_rays - 1) // 2 if n_rays > 1 else 0
    rays = np.empty(n_bins)
    for k in range(rows.shape[0]):
        cx = x0 + (cols[k] + 0.5) * resolution
        cy = y0 + (rows[k] + 0.5) * resolution
        if ray_step > 0:
            for b in range(n_bins):
                rays[b] = cone_echo(
                    cx, cy, b * _TWO_PI / n_bins, segments, 1, 0.0, max_range,
                    cos_specular,
                )  # fmt: skip
        for b in range(n_bins):
            if ray_step > 0:
                echo = np.inf
                for q in range(-half, half + 1):
                    echo = min(echo, rays[(b + q * ray_step) % n_bins])
            else:
                echo = cone_echo(
                    cx, cy, b * _TWO_PI / n_bins, segments, n_rays, cone,
                    max_range, cos_specular,
                )  # fmt: skip
            z = max_range if echo >= max_range else echo
            z = min(max(z, min_range), max_range)
            out[k, b] = np.uint16(round(z * 1000.0))


@nb.njit(**JIT, inline="always")
def table_bin(x, y, th, c, s, sensors, i, ny, nx, n_bins, x0, y0, inv_res):
    """Cone table ``(row, col, bin)`` of sensor ``i`` on a robot at ``(x, y, th)``.

    ``c, s`` are the cosine and sine of ``th``; the sensor's position selects
    the cell (clamped to the grid) and its heading the nearest direction bin.
    """
    sx = x + c * sensors[i, 0] - s * sensors[i, 1]
    sy = y + s * sensors[i, 0] + c * sensors[i, 1]
    col = int(math.floor((sx - x0) * inv_res))
    row = int(math.floor((sy - y0) * inv_res))
    col = min(max(col, 0), nx - 1)
    row = min(max(row, 0), ny - 1)
    b = int(math.floor((th + sensors[i, 2]) * (n_bins / _TWO_PI) + 0.5))
    # b % n_bins, without an integer division for headings in (-2 pi, 4 pi)
    if b < 0:
        b += n_bins
        if b < 0:
            b %= n_bins
    elif b >= n_bins:
        b -= n_bins
        if b >= n_bins:
            b %= n_bins
    return row, col, b


@nb.njit(**JIT, inline="always")
def _table_mm(particles, j, c, s, sensors, i, table, x0, y0, inv_res):
    """Table entry (mm) for sensor ``i`` of particle ``j`` (heading cos, sin)."""
    ny, nx, n_bins = table.shape
    row, col, b = table_bin(
        particles[j, 0], particles[j, 1], particles[j, 2], c, s, sensors, i,
        ny, nx, n_bins, x0, y0, inv_res,
    )  # fmt: skip
    return table[row, col, b]


def _expected_table(particles, sensors, table, x0, y0, inv_res, out):
    """Sonar ranges ``out`` (N, S) looked up in a cone table (see `build_cone_table`).

    Each sensor's position selects the cell (clamped to the grid) and its
    heading the nearest direction bin.
    """
    for j in nb.prange(particles.shape[0]):
        s, c = sincos(particles[j, 2])
        for i in range(sensors.shape[0]):
            out[j, i] = (
                _table_mm(particles, j, c, s, sensors, i, table, x0, y0, inv_res)
                * 0.001
            )


expected_table, expected_table_parallel = serial_and_parallel(_expected_table)
