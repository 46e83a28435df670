"""Numba kernels for ray casting against segments and grids, and the sonar cone.

All kernels take contiguous float64 arrays and scalars. Ranges are in the
units of the inputs (metres in robotlib). A ray that hits nothing within
``max_range`` returns ``inf`` from the segment casters and ``max_range`` from
the grid caster's callers; see each docstring.
"""

import math

import numba as nb
import numpy as np

from .._config import JIT, JIT_PARALLEL, serial_and_parallel

_EPS = 1e-12


@nb.njit(**JIT)
def ray_segments(ox, oy, dx, dy, segments):
    """Nearest hit of the ray ``o + t d`` (``d`` a unit vector) on any segment.

    Returns ``(t, m)``: the distance to the hit and the segment's index, or
    ``(inf, -1)`` if the ray meets no segment. Segments parallel to the ray are
    not hit.
    """
    best = np.inf
    best_m = -1
    for m in range(segments.shape[0]):
        px = segments[m, 0]
        py = segments[m, 1]
        ex = segments[m, 2] - px
        ey = segments[m, 3] - py
        denom = dx * ey - dy * ex
        if abs(denom) < _EPS:
            continue
        wx = px - ox
        wy = py - oy
        t = (wx * ey - wy * ex) / denom
        if t < 0.0 or t >= best:
            continue
        s = (wx * dy - wy * dx) / denom
        if 0.0 <= s <= 1.0:
            best = t
            best_m = m
    return best, best_m


def _cast_segments(poses, angles, max_range, segments, out):
    """Cast rays from many poses: ``out[k, r]`` is ray ``r`` of pose ``k``.

    ``poses`` (K, 3), ``angles`` (R,) relative to each pose's heading,
    ``out`` (K, R). A ray with no hit within ``max_range`` gives ``max_range``.
    ``cast_segments`` runs over threads, ``cast_segments_serial`` in one (for
    a few poses, e.g. one laser scan, where waking threads costs more).
    """
    for k in nb.prange(poses.shape[0]):
        for r in range(angles.shape[0]):
            a = poses[k, 2] + angles[r]
            t, _ = ray_segments(
                poses[k, 0], poses[k, 1], math.cos(a), math.sin(a), segments
            )
            out[k, r] = t if t < max_range else max_range


cast_segments_serial, cast_segments = serial_and_parallel(_cast_segments)


@nb.njit(**JIT)
def _edt_1d(f, n, v, z, out):
    """Write the squared distance transform of ``f[:n]`` into ``out``.

    Felzenszwalb and Huttenlocher's lower envelope of parabolas; ``v`` and
    ``z`` are scratch arrays.
    """
    k = 0
    v[0] = 0
    z[0] = -np.inf
    z[1] = np.inf
    for q in range(1, n):
        if f[q] == np.inf:
            continue
        while True:
            p = v[k]
            if f[p] == np.inf:
                s = -np.inf
            else:
                s = ((f[q] + q * q) - (f[p] + p * p)) / (2.0 * q - 2.0 * p)
            if s <= z[k] and k > 0:
                k -= 1
            else:
                break
        if f[v[k]] == np.inf:
            v[k] = q
            continue
        k += 1
        v[k] = q
        z[k] = s
        z[k + 1] = np.inf
    k = 0
    for q in range(n):
        while z[k + 1] < q:
            k += 1
        p = v[k]
        out[q] = np.inf if f[p] == np.inf else (q - p) * (q - p) + f[p]


@nb.njit(**JIT)
def clearance_field(occupied, out):
    """Write the grid caster's field into ``out``, shape ``occupied.shape + 2``.

    ``out`` is the occupancy grid padded with a ring of occupied cells (the
    grid's edge counts as a wall): -1 on occupied cells, elsewhere the cell's
    clearance in cells, a lower bound on the distance from any point of the
    cell to an occupied cell (an exact Euclidean distance transform between
    cell centres, less one cell diagonal).
    """
    ny, nx = occupied.shape
    n = max(ny, nx) + 2
    f = np.empty(n)
    d = np.empty(n)
    v = np.empty(n, dtype=np.int64)
    z = np.empty(n + 1)
    sq = np.empty((ny + 2, nx + 2))
    for i in range(ny + 2):
        for j in range(nx + 2):
            inside = 0 < i <= ny and 0 < j <= nx
            f[j] = np.inf if inside and not occupied[i - 1, j - 1] else 0.0
        _edt_1d(f, nx + 2, v, z, d)
        for j in range(nx + 2):  # a loop: a slice copy compiles seconds slower
            sq[i, j] = d[j]
    for j in range(nx + 2):
        for i in range(ny + 2):
            f[i] = sq[i, j]
        _edt_1d(f, ny + 2, v, z, d)
        for i in range(ny + 2):
            if d[i] == 0.0:
                out[i, j] = -1.0
            else:
                out[i, j] = max(math.sqrt(d[i]) - math.sqrt(2.0), 0.0)


_GRID_CHUNK = 32
"""Poses one thread casts with one set of scratch arrays (`cast_grid`)."""


_RAY = 8
"""Values per ray in `_cast_grid_pose`'s scratch (a 64-byte row; one unused)."""


@nb.njit(**JIT, inline="always")
def _cast_grid_pose(
    k, poses, ca, sa, max_range, field, x0, y0, resolution, out, ray, active
):  # fmt: skip
    """Cast every ray of pose ``k`` on a `clearance_field`; write ``out[k]``.

    Each ray advances from its origin by the clearance of the cell it is in
    (a distance within which it cannot hit anything) or, where that is under
    one cell, to the next cell boundary; it stops on entering an occupied
    cell (0 if it starts in one or outside the grid, the grid's edge counting
    as a wall) or past ``max_range``. The rays of a pose advance together, one
    step each per round, so that their reads of ``field`` overlap in memory;
    both steps are computed and one selected, and a ray's end (a hit, or past
    ``max_range``) is a select too: its range is written every step and it
    is dropped from the active list by its count (no branch to mispredict).
    ``ray`` (`_RAY` * R,) float64 and ``active`` (R,) uint64 are scratch: per
    ray its direction, the inverse of each component, the offsets to the
    cell boundary ahead (1 or 0 in x and y) and its distance so far (cells).
    Indexes are unsigned (no negative-index wrap tests).
    """
    n_rays = ca.shape[0]
    gx = (poses[k, 0] - x0) / resolution + 1.0
    gy = (poses[k, 1] - y0) / resolution + 1.0
    if not (1.0 <= gx < field.shape[1] - 1 and 1.0 <= gy < field.shape[0] - 1):
        out[k, :] = 0.0
        return
    limit = max_range / resolution
    c0 = math.cos(poses[k, 2])
    s0 = math.sin(poses[k, 2])
    for r in range(n_rays):
        dx = c0 * ca[r] - s0 * sa[r]
        dy = s0 * ca[r] + c0 * sa[r]
        b = _RAY * r
        ray[b] = dx
        ray[b + 1] = dy
        ray[b + 2] = 1.0 / dx if dx != 0.0 else np.inf
        ray[b + 3] = 1.0 / dy if dy != 0.0 else np.inf
        ray[b + 4] = 1.0 if dx >= 0 else 0.0
        ray[b + 5] = 1.0 if dy >= 0 else 0.0
        ray[b + 6] = 0.0
        active[r] = r
    stride = np.uint64(field.shape[1])
    flat = field.reshape(field.size)
    row = out[k]
    one = np.uint64(1)
    n = np.uint64(n_rays)
    while n > 0:
        still = np.uint64(0)
        for q in range(n):
            r = active[np.uint64(q)]
            b = r * np.uint64(_RAY)
            tr = ray[b + np.uint64(6)]
            px = gx + tr * ray[b]
            py = gy + tr * ray[b + one]
            # px, py >= 1 (the ring of the field is occupied): int() floors,
            # and the flat index is never negative (read unsigned: no wrap test)
            j = int(px)
            i = int(py)
            c = flat[np.uint64(i) * stride + np.uint64(j)]
            hit = c < 0.0  # the ray ends here: entered an occupied cell
            bx = (float(j) + ray[b + np.uint64(4)] - px) * ray[b + np.uint64(2)]
            by = (float(i) + ray[b + np.uint64(5)] - py) * ray[b + np.uint64(3)]
            edge = min(bx, by) + 1e-9
            t2 = tr + (c if c >= 1.0 else edge)
            ray[b + np.uint64(6)] = t2
            over = t2 >= limit  # or past max_range
            # every ray's range is written each step, the last one stays: no branch
            row[r] = tr * resolution if hit else max_range
            active[np.uint64(still)] = r
            still += np.uint64(not (hit | over))  # the others leave the active list
        n = still


@nb.njit(**JIT_PARALLEL)
def cast_grid(poses, angles, max_range, field, x0, y0, resolution, out):
    """Grid version of `cast_segments` on a `clearance_field`: ``out[k, r]``.

    Ranges are to the boundary where each ray enters its first occupied cell.
    Poses are cast in chunks of `_GRID_CHUNK`, each chunk with its own scratch.
    """
    ca = np.cos(angles)
    sa = np.sin(angles)
    n_rays = angles.shape[0]
    n = poses.shape[0]
    for q in nb.prange((n + _GRID_CHUNK - 1) // _GRID_CHUNK):
        ray = np.empty(_RAY * n_rays)
        active = np.empty(n_rays, dtype=np.uint64)
        for k in range(q * _GRID_CHUNK, min(n, (q + 1) * _GRID_CHUNK)):
            _cast_grid_pose(
                k, poses, ca, sa, max_range, field, x0, y0, resolution, out, ray,
                active,
            )  # fmt: skip


@nb.njit(**JIT)
def _cone(sx, sy, sth, segments, n_rays, cone, max_range, cos_specular, bounce):
    """Body of `sonar_cone` (``bounce``) and `cone_echo` (no bounce)."""
    echo = np.inf
    multipath = np.inf
    for r in range(n_rays):
        if n_rays == 1:
            a = sth
        else:
            a = sth - 0.5 * cone + cone * r / (n_rays - 1)
        dx = math.cos(a)
        dy = math.sin(a)
        t, m = ray_segments(sx, sy, dx, dy, segments)
        if m < 0 or t >= max_range or t >= echo:
            continue
        ex = segments[m, 2] - segments[m, 0]
        ey = segments[m, 3] - segments[m, 1]
        length = math.sqrt(ex * ex + ey * ey)
        nxn = -ey / length
        nyn = ex / length
        cos_inc = abs(dx * nxn + dy * nyn)
        if cos_inc >= cos_specular:
            echo = t
            continue
        if not bounce:
            continue
        dot = dx * nxn + dy * nyn
        rx = dx - 2.0 * dot * nxn
        ry = dy - 2.0 * dot * nyn
        hx = sx + t * dx + 1e-9 * rx
        hy = sy + t * dy + 1e-9 * ry
        t2, m2 = ray_segments(hx, hy, rx, ry, segments)
        if m2 >= 0 and t + t2 < max_range and t + t2 < multipath:
            multipath = t + t2
    return echo, multipath


@nb.njit(**JIT)
def sonar_cone(sx, sy, sth, segments, n_rays, cone, max_range, cos_specular):
    """One sonar's first echo and its one-bounce multipath range.

    The cone of full width ``cone`` around heading ``sth`` is sampled by
    ``n_rays`` rays (evenly, edges included; one ray on the axis if
    ``n_rays == 1``). A ray that meets a wall whose normal makes an angle with
    the ray larger than the specular angle (``cos`` of incidence below
    ``cos_specular``) reflects away and gives no echo; it travels on, mirrored
    by the wall, to the next wall it meets.

    Returns ``(echo, multipath)``: the shortest echoing range (``inf`` if no
    ray echoes or none within ``max_range``) and the shortest total path of a
    reflected ray's bounce (``inf`` if none within ``max_range``).
    """
    return _cone(sx, sy, sth, segments, n_rays, cone, max_range, cos_specular, True)


@nb.njit(**JIT)
def _sensor_cone(
    k, i, poses, sensors, segments, n_rays, cone, max_range, cos_specular, bounce
):
    """`_cone` of sensor ``i`` (robot frame) on robot pose ``k``."""
    c = math.cos(poses[k, 2])
    s = math.sin(poses[k, 2])
    return _cone(
        poses[k, 0] + c * sensors[i, 0] - s * sensors[i, 1],
        poses[k, 1] + s * sensors[i, 0] + c * sensors[i, 1],
        poses[k, 2] + sensors[i, 2],
        segments,
        n_rays,
        cone,
        max_range,
        cos_specular,
        bounce,
    )


def _expected_scan(
    poses, sensors, segments, n_rays, cone, max_range, min_range, cos_specular, out
):
    """Noise-free sonar readings ``out`` (K, S) for poses (K, 3), sensors (S, 3).

    Each reading is the cone's first echo (`sonar_cone`), ``max_range`` when
    nothing echoes, clipped to ``[min_range, max_range]``: `sonar_scan` with
    no noise, multipath or dropouts.
    """
    for k in nb.prange(poses.shape[0]):
        for i in range(sensors.shape[0]):
            echo, _ = _sensor_cone(
                k,
                i,
                poses,
                sensors,
                segments,
                n_rays,
                cone,
                max_range,
                cos_specular,
                False,
            )
            z = echo if echo < max_range else max_range
            out[k, i] = min(max(z, min_range), max_range)


expected_scan, expected_scan_parallel = serial_and_parallel(_expected_scan)


def _sonar_scan(
    poses,
    sensors,
    segments,
    n_rays,
    cone,
    max_range,
    min_range,
    cos_specular,
    noise_std,
    multipath_prob,
    dropout_prob,
    uniforms,
    normals,
    out,
):
    """Sonar readings ``out`` (K, S) for poses (K, 3) and sensors (S, 3).

    Per reading: the cone's first echo (`sonar_cone`) times
    ``1 + noise_std * normals[k, i]``; with no echo, the multipath range if
    ``uniforms[k, i, 0] < multipath_prob``, else ``max_range``; a dropout
    (``max_range``) if ``uniforms[k, i, 1] < dropout_prob``; clipped to
    ``[min_range, max_range]``. ``uniforms`` (K, S, 2) in [0, 1) and
    ``normals`` (K, S) are drawn by the caller, so a seed fixes the result.
    """
    for k in nb.prange(poses.shape[0]):
        for i in range(sensors.shape[0]):
            echo, multipath = _sensor_cone(
                k,
                i,
                poses,
                sensors,
                segments,
                n_rays,
                cone,
                max_range,
                cos_specular,
                True,
            )
            z = max_range
            if echo < max_range:
                z = echo * (1.0 + noise_std * normals[k, i])
            elif multipath < max_range and uniforms[k, i, 0] < multipath_prob:
                z = multipath * (1.0 + noise_std * normals[k, i])
            if uniforms[k, i, 1] < dropout_prob:
                z = max_range
            out[k, i] = min(max(z, min_range), max_range)


sonar_scan, sonar_scan_parallel = serial_and_parallel(_sonar_scan)


@nb.njit(**JIT)
def cone_walls(sx, sy, ux, uy, cos_half, sin_half, segments, max_range, out):
    """Copy into ``out`` (M, 4) the walls a sonar cone may echo from; return the count.

    The cone has its apex at ``(sx, sy)``, its axis along the unit vector
    ``(ux, uy)`` and the half-width whose cosine and sine are given (widen
    it a little: the axis and the edges are rotated, not exact). A wall is
    dropped when both its end points lie outside the same edge of the cone's
    wedge, or when its bounding box lies further than ``max_range`` from
    ``(sx, sy)`` along x or y. No ray of the cone can meet a dropped wall
    within ``max_range``, and the kept walls keep their order, so
    `sonar_cone` on the kept walls gives the same echo as on all of them (its
    multipath range, which the bounce may find on a dropped wall, can
    differ). With ``cos_half <= 0`` (half-width of ``pi / 2`` or more) walls
    are culled by range only.
    """
    return _cone_walls_range(
        sx, sy, ux, uy, cos_half, sin_half, segments, 0, segments.shape[0], max_range,
        out,
    )  # fmt: skip


@nb.njit(**JIT, inline="always")
def _cone_walls_range(
    sx, sy, ux, uy, cos_half, sin_half, segments, lo, hi, max_range, out
):  # fmt: skip
    """`cone_walls` over the walls ``segments[lo:hi]`` (no slice made)."""
    by_angle = cos_half > 0.0
    lx = ux * cos_half - uy * sin_half  # left edge
    ly = uy * cos_half + ux * sin_half
    rx = ux * cos_half + uy * sin_half  # right edge
    ry = uy * cos_half - ux * sin_half
    k = 0
    for m in range(lo, hi):
        ax = segments[m, 0] - sx
        ay = segments[m, 1] - sy
        bx = segments[m, 2] - sx
        by = segments[m, 3] - sy
        if (ax > max_range and bx > max_range) or (ax < -max_range and bx < -max_range):
            continue
        if (ay > max_range and by > max_range) or (ay < -max_range and by < -max_range):
            continue
        if by_angle:
            if lx * ay - ly * ax > 1e-9 and lx * by - ly * bx > 1e-9:
                continue  # left of the left edge
            if rx * ay - ry * ax < -1e-9 and rx * by - ry * bx < -1e-9:
                continue  # right of the right edge
        for t in range(4):
            out[k, t] = segments[m, t]
        k += 1
    return k


@nb.njit(**JIT)
def cone_echo(sx, sy, sth, segments, n_rays, cone, max_range, cos_specular):
    """`sonar_cone`'s first echo alone (no multipath bounce): the same number."""
    echo, _ = _cone(sx, sy, sth, segments, n_rays, cone, max_range, cos_specular, False)
    return echo
