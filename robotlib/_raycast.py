"""Numba kernels for ray casting against segments and grids, and the sonar cone.

All kernels take contiguous float64 arrays and scalars. Ranges are in the
units of the inputs (metres in robotlib). A ray that hits nothing within
``max_range`` returns ``inf`` from the segment casters and ``max_range`` from
the grid caster's callers; see each docstring.
"""

import math

import numba as nb
import numpy as np

from ._config import JIT, JIT_PARALLEL

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


@nb.njit(**JIT_PARALLEL)
def cast_segments(poses, angles, max_range, segments, out):
    """Cast rays from many poses: ``out[k, r]`` is ray ``r`` of pose ``k``.

    ``poses`` (K, 3), ``angles`` (R,) relative to each pose's heading,
    ``out`` (K, R). A ray with no hit within ``max_range`` gives ``max_range``.
    """
    for k in nb.prange(poses.shape[0]):
        for r in range(angles.shape[0]):
            a = poses[k, 2] + angles[r]
            t, _ = ray_segments(
                poses[k, 0], poses[k, 1], math.cos(a), math.sin(a), segments
            )
            out[k, r] = t if t < max_range else max_range


@nb.njit(**JIT)
def ray_grid(occupied, x0, y0, resolution, ox, oy, angle, max_range):
    """Distance from ``(ox, oy)`` along ``angle`` to the first occupied cell.

    Walks the cells the ray crosses in order (Amanatides and Woo's traversal)
    and returns the distance to the boundary where it enters the first
    occupied cell: 0 if it starts in one or outside the grid; the distance to
    the grid's edge if it leaves the grid first; ``max_range`` if it travels
    that far without a hit.
    """
    ny, nx = occupied.shape
    gx = (ox - x0) / resolution
    gy = (oy - y0) / resolution
    j = int(math.floor(gx))
    i = int(math.floor(gy))
    if i < 0 or i >= ny or j < 0 or j >= nx or occupied[i, j]:
        return 0.0
    dx = math.cos(angle)
    dy = math.sin(angle)
    limit = max_range / resolution
    if dx > _EPS:
        step_j = 1
        t_max_x = (j + 1 - gx) / dx
        t_delta_x = 1.0 / dx
    elif dx < -_EPS:
        step_j = -1
        t_max_x = (gx - j) / -dx
        t_delta_x = -1.0 / dx
    else:
        step_j = 0
        t_max_x = np.inf
        t_delta_x = np.inf
    if dy > _EPS:
        step_i = 1
        t_max_y = (i + 1 - gy) / dy
        t_delta_y = 1.0 / dy
    elif dy < -_EPS:
        step_i = -1
        t_max_y = (gy - i) / -dy
        t_delta_y = -1.0 / dy
    else:
        step_i = 0
        t_max_y = np.inf
        t_delta_y = np.inf
    while True:
        if t_max_x < t_max_y:
            t = t_max_x
            t_max_x += t_delta_x
            j += step_j
        else:
            t = t_max_y
            t_max_y += t_delta_y
            i += step_i
        if t >= limit:
            return max_range
        if i < 0 or i >= ny or j < 0 or j >= nx or occupied[i, j]:
            return t * resolution


@nb.njit(**JIT_PARALLEL)
def cast_grid(poses, angles, max_range, occupied, x0, y0, resolution, out):
    """Grid version of `cast_segments`: ``out[k, r]`` via `ray_grid`."""
    for k in nb.prange(poses.shape[0]):
        for r in range(angles.shape[0]):
            out[k, r] = ray_grid(
                occupied,
                x0,
                y0,
                resolution,
                poses[k, 0],
                poses[k, 1],
                poses[k, 2] + angles[r],
                max_range,
            )


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
def _scan_pose(
    k,
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
    c = math.cos(poses[k, 2])
    s = math.sin(poses[k, 2])
    for i in range(sensors.shape[0]):
        sx = poses[k, 0] + c * sensors[i, 0] - s * sensors[i, 1]
        sy = poses[k, 1] + s * sensors[i, 0] + c * sensors[i, 1]
        echo, multipath = sonar_cone(
            sx,
            sy,
            poses[k, 2] + sensors[i, 2],
            segments,
            n_rays,
            cone,
            max_range,
            cos_specular,
        )
        z = max_range
        if echo < max_range:
            z = echo * (1.0 + noise_std * normals[k, i])
        elif multipath < max_range and uniforms[k, i, 0] < multipath_prob:
            z = multipath * (1.0 + noise_std * normals[k, i])
        if uniforms[k, i, 1] < dropout_prob:
            z = max_range
        out[k, i] = min(max(z, min_range), max_range)


@nb.njit(**JIT)
def sonar_scan(
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
    for k in range(poses.shape[0]):
        _scan_pose(
            k,
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
        )


@nb.njit(**JIT_PARALLEL)
def sonar_scan_parallel(
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
    """`sonar_scan` with the poses spread over threads (for many poses)."""
    for k in nb.prange(poses.shape[0]):
        _scan_pose(
            k,
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
        )
