"""Plain NumPy references for robotlib's numba kernels (slow, obvious, independent)."""

import math

import numpy as np


def ray_segment_hits(origin, direction, segments):
    """Distance along a unit ray to each segment it crosses (inf otherwise), by solving
    ``o + t d = p + s e`` for every segment with ``numpy.linalg.solve``."""
    out = np.full(len(segments), np.inf)
    for m, (x1, y1, x2, y2) in enumerate(np.asarray(segments, float)):
        a = np.array([[direction[0], -(x2 - x1)], [direction[1], -(y2 - y1)]])
        if abs(np.linalg.det(a)) < 1e-12:
            continue
        t, s = np.linalg.solve(a, np.array([x1 - origin[0], y1 - origin[1]]))
        if t >= 0 and -1e-12 <= s <= 1 + 1e-12:
            out[m] = t
    return out


def cast_rays(segments, poses, angles, max_range):
    out = np.empty((len(poses), len(angles)))
    for k, (x, y, th) in enumerate(poses):
        for r, a in enumerate(angles):
            d = (math.cos(th + a), math.sin(th + a))
            out[k, r] = min(ray_segment_hits((x, y), d, segments).min(), max_range)
    return out


def cast_ray_grid_marching(occupied, origin, resolution, pose, angle, max_range, step):
    """March along the ray in small steps; return the first distance in an occupied
    cell (or outside the grid), ``max_range`` if none: within ``step`` of the truth."""
    ny, nx = occupied.shape
    d = np.array([math.cos(pose[2] + angle), math.sin(pose[2] + angle)])
    for t in np.arange(0.0, max_range, step):
        x, y = np.array(pose[:2]) + t * d
        j = math.floor((x - origin[0]) / resolution)
        i = math.floor((y - origin[1]) / resolution)
        if not (0 <= i < ny and 0 <= j < nx) or occupied[i, j]:
            return t
    return max_range


def sonar_cone(sx, sy, sth, segments, n_rays, cone, max_range, specular_angle):
    """(echo, multipath) of one sonar, as `sensing._kernels.sonar_cone` defines it."""
    segments = np.asarray(segments, float)
    echo, multipath = np.inf, np.inf
    offsets = [0.0] if n_rays == 1 else np.linspace(-cone / 2, cone / 2, n_rays)
    for off in offsets:
        a = sth + off
        d = np.array([math.cos(a), math.sin(a)])
        hits = ray_segment_hits((sx, sy), d, segments)
        m = int(np.argmin(hits))
        t = hits[m]
        if not np.isfinite(t) or t >= max_range:
            continue
        e = segments[m, 2:] - segments[m, :2]
        n = np.array([-e[1], e[0]]) / np.linalg.norm(e)
        incidence = math.acos(min(1.0, abs(d @ n)))
        if specular_angle is None or incidence <= specular_angle:
            echo = min(echo, t)
            continue
        reflected = d - 2 * (d @ n) * n
        hit = np.array([sx, sy]) + t * d + 1e-9 * reflected
        t2 = ray_segment_hits(hit, reflected, segments).min()
        if t + t2 < max_range:
            multipath = min(multipath, t + t2)
    return echo, multipath


def sonar_scan(segments, poses, model, uniforms, normals):
    """Readings (K, S) as `robotlib.sensing.sonar` says, from the same noise draws."""
    out = np.empty((len(poses), len(model.sensors)))
    for k, (x, y, th) in enumerate(poses):
        for i, (ox, oy, oth) in enumerate(model.sensors):
            sx = x + math.cos(th) * ox - math.sin(th) * oy
            sy = y + math.sin(th) * ox + math.cos(th) * oy
            echo, multi = sonar_cone(
                sx,
                sy,
                th + oth,
                segments,
                model.n_rays,
                model.cone,
                model.max_range,
                model.specular_angle,
            )
            z = model.max_range
            if echo < model.max_range:
                z = echo * (1 + model.noise_std * normals[k, i])
            elif multi < model.max_range and uniforms[k, i, 0] < model.multipath_prob:
                z = multi * (1 + model.noise_std * normals[k, i])
            if uniforms[k, i, 1] < model.dropout_prob:
                z = model.max_range
            out[k, i] = np.clip(z, model.min_range, model.max_range)
    return out
