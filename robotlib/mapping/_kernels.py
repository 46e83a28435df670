"""Numba kernels for occupancy-grid mapping and grid FastSLAM.

Grids are log-odds arrays ``L[i, j]`` (row ``i`` is y, column ``j`` is x)
with the lower-left corner of cell ``[0, 0]`` at ``(x0, y0)`` and cells of
side ``res``; stacks of grids ``L[n, i, j]`` hold one map per particle.
Every kernel takes contiguous arrays and scalars only; updates clamp each
cell to ``[l_min, l_max]``. The per-particle kernels (``*_many``,
`copy_maps`) come serial and ``*_parallel`` (over threads), from one body,
with the same bits. Imports nothing of robotlib's but the JIT config.
"""

import math

import numba as nb
import numpy as np

from .._config import JIT, serial_and_parallel
from ._kernels_cone import (  # noqa: F401  (re-exported)
    POLY_DEGREE,
    WEIGHT_PIECES,
    _clamp,
    _cone_update,
    _table_weight,
    cone_weight_poly,
    cone_weight_table,
    cone_weights,
)


@nb.njit(**JIT)
def sonar_cone_update(
    L, x0, y0, res, sx, sy, sth, z, half_cone, max_range, thickness,
    l_occ, l_free, sigma, max_weight, l_min, l_max,
):  # fmt: skip
    """Add one sonar cone's inverse-model log-odds to the grid ``L`` (ny, nx).

    See `_cone_update` (this builds its weights, `cone_weights`).
    """
    poly, table = cone_weights(half_cone, sigma)
    _cone_update(
        L, x0, y0, res, sx, sy, sth, z, half_cone, max_range, thickness,
        l_occ, l_free, sigma, max_weight, l_min, l_max, poly, table,
    )  # fmt: skip


@nb.njit(**JIT)
def sonar_scan_update(
    L, x0, y0, res, pose, sensors, ranges, half_cone, max_range, thickness,
    l_occ, l_free, sigma, max_weight, l_min, l_max,
):  # fmt: skip
    """Apply `sonar_cone_update` for each sonar of a ring at robot ``pose`` (3,).

    ``sensors`` (S, 3) are the sonar poses in the robot frame, ``ranges``
    (S,) the readings, m.
    """
    poly, table = cone_weights(half_cone, sigma)
    _scan_update(
        L, x0, y0, res, pose, sensors, ranges, half_cone, max_range, thickness,
        l_occ, l_free, sigma, max_weight, l_min, l_max, poly, table,
    )  # fmt: skip


@nb.njit(**JIT)
def _scan_update(
    L, x0, y0, res, pose, sensors, ranges, half_cone, max_range, thickness,
    l_occ, l_free, sigma, max_weight, l_min, l_max, poly, table,
):  # fmt: skip
    """`sonar_scan_update` with the cone's weights (`cone_weights`) given."""
    c = math.cos(pose[2])
    s = math.sin(pose[2])
    for k in range(sensors.shape[0]):
        sx = pose[0] + c * sensors[k, 0] - s * sensors[k, 1]
        sy = pose[1] + s * sensors[k, 0] + c * sensors[k, 1]
        _cone_update(
            L, x0, y0, res, sx, sy, pose[2] + sensors[k, 2], ranges[k], half_cone,
            max_range, thickness, l_occ, l_free, sigma, max_weight, l_min, l_max,
            poly, table,
        )  # fmt: skip


@nb.njit(**JIT)
def laser_beam_update(L, x0, y0, res, ox, oy, a, z, max_range, l_occ, l_free,
                      l_min, l_max):  # fmt: skip
    """Trace one beam from ``(ox, oy)`` along angle ``a`` to range ``z``.

    Every cell the beam crosses before its end point's cell gets ``l_free``;
    the end point's cell gets ``l_occ`` when ``z < max_range`` (a return),
    else the beam is free to ``max_range`` and marks nothing occupied. Cells
    are walked in order (Amanatides and Woo's traversal); cells off the grid
    are skipped.
    """
    ny, nx = L.shape
    echo = z < max_range
    length = z if echo else max_range
    gx = (ox - x0) / res
    gy = (oy - y0) / res
    dx = math.cos(a)
    dy = math.sin(a)
    ex = gx + dx * length / res
    ey = gy + dy * length / res
    j = int(math.floor(gx))
    i = int(math.floor(gy))
    je = int(math.floor(ex))
    ie = int(math.floor(ey))
    step_j = 1 if dx > 0 else -1
    step_i = 1 if dy > 0 else -1
    t_dx = abs(1.0 / dx) if dx != 0.0 else np.inf
    t_dy = abs(1.0 / dy) if dy != 0.0 else np.inf
    if dx > 0:
        t_x = (j + 1.0 - gx) * t_dx
    elif dx < 0:
        t_x = (gx - j) * t_dx
    else:
        t_x = np.inf
    if dy > 0:
        t_y = (i + 1.0 - gy) * t_dy
    elif dy < 0:
        t_y = (gy - i) * t_dy
    else:
        t_y = np.inf
    n_steps = abs(je - j) + abs(ie - i)
    uny = np.uint64(ny)
    unx = np.uint64(nx)
    for _ in range(n_steps):
        # unsigned: one test a side, and no negative-index fix
        ui = np.uint64(i)
        uj = np.uint64(j)
        if ui < uny and uj < unx:
            L[ui, uj] = min(max(L[ui, uj] + l_free, l_min), l_max)
        if t_x < t_y:
            j += step_j
            t_x += t_dx
        else:
            i += step_i
            t_y += t_dy
    if 0 <= ie < ny and 0 <= je < nx:
        if echo:
            L[ie, je] = _clamp(L[ie, je] + l_occ, l_min, l_max)
        else:
            L[ie, je] = _clamp(L[ie, je] + l_free, l_min, l_max)


@nb.njit(**JIT)
def laser_scan_update(L, x0, y0, res, lpose, angles, ranges, max_range, l_occ,
                      l_free, l_min, l_max):  # fmt: skip
    """Apply `laser_beam_update` for every beam of a scan from laser pose ``lpose``."""
    for r in range(angles.shape[0]):
        laser_beam_update(
            L, x0, y0, res, lpose[0], lpose[1], lpose[2] + angles[r], ranges[r],
            max_range, l_occ, l_free, l_min, l_max,
        )  # fmt: skip


def _laser_update_many(Ls, x0, y0, res, lposes, angles, ranges, max_range, l_occ,
                      l_free, l_min, l_max):  # fmt: skip
    """`laser_scan_update` of one scan into each map ``Ls[n]`` from ``lposes[n]``."""
    for n in nb.prange(Ls.shape[0]):
        laser_scan_update(
            Ls[n], x0, y0, res, lposes[n], angles, ranges, max_range, l_occ,
            l_free, l_min, l_max,
        )  # fmt: skip


laser_update_many, laser_update_many_parallel = serial_and_parallel(_laser_update_many)


def _sonar_update_many(Ls, x0, y0, res, poses, sensors, ranges, half_cone,
                      max_range, thickness, l_occ, l_free, sigma, max_weight,
                      l_min, l_max):  # fmt: skip
    """`sonar_scan_update` of one ring reading into each ``Ls[n]`` at ``poses[n]``."""
    poly, table = cone_weights(half_cone, sigma)
    for n in nb.prange(Ls.shape[0]):
        _scan_update(
            Ls[n], x0, y0, res, poses[n], sensors, ranges, half_cone, max_range,
            thickness, l_occ, l_free, sigma, max_weight, l_min, l_max, poly, table,
        )  # fmt: skip


sonar_update_many, sonar_update_many_parallel = serial_and_parallel(_sonar_update_many)


@nb.njit(**JIT)
def _occ_prob(L, i, j):
    """Occupancy probability of cell ``(i, j)``; 0.5 (unknown) off the grid."""
    if 0 <= i < L.shape[0] and 0 <= j < L.shape[1]:
        return 1.0 - 1.0 / (1.0 + math.exp(np.float64(L[i, j])))
    return 0.5


@nb.njit(**JIT)
def _best_near(L, x0, y0, res, px, py):
    """Largest occupancy probability in the 3 x 3 cells around point ``(px, py)``.

    Cells off the grid count as unknown (log-odds 0); the largest log-odds
    gives the largest probability, so one exponential does.
    """
    j = int(math.floor((px - x0) / res))
    i = int(math.floor((py - y0) / res))
    ny, nx = L.shape
    best = -np.inf
    for ii in range(i - 1, i + 2):
        for jj in range(j - 1, j + 2):
            v = np.float64(L[ii, jj]) if 0 <= ii < ny and 0 <= jj < nx else 0.0
            if v > best:
                best = v
    return 1.0 - 1.0 / (1.0 + math.exp(best))


def _laser_loglik_many(Ls, x0, y0, res, lposes, angles, ranges, max_range, p_rand,
                      out):  # fmt: skip
    """Log-likelihood of one scan in each particle's own map: ``out[n]``.

    Each return (``z < max_range``) scores ``log(p_rand + (1 - p_rand) p)``,
    ``p`` the largest occupancy probability within one cell of the beam's end
    point in map ``Ls[n]`` seen from laser pose ``lposes[n]`` (the end-point
    model; an unknown cell counts 0.5).
    """
    for n in nb.prange(Ls.shape[0]):
        total = 0.0
        for r in range(angles.shape[0]):
            if ranges[r] >= max_range:
                continue
            a = lposes[n, 2] + angles[r]
            px = lposes[n, 0] + ranges[r] * math.cos(a)
            py = lposes[n, 1] + ranges[r] * math.sin(a)
            p = _best_near(Ls[n], x0, y0, res, px, py)
            total += math.log(p_rand + (1.0 - p_rand) * p)
        out[n] = total


laser_loglik_many, laser_loglik_many_parallel = serial_and_parallel(_laser_loglik_many)


def _sonar_loglik_many(Ls, x0, y0, res, poses, sensors, ranges, half_cone,
                      max_range, n_rays, p_rand, out):  # fmt: skip
    """Log-likelihood of one ring reading in each particle's own map: ``out[n]``.

    An echo at ``z`` says some wall lies on the cone's arc at ``z``: each
    reading with ``z < max_range`` scores ``log(p_rand + (1 - p_rand) p)``,
    ``p`` the largest occupancy probability within one cell of ``n_rays``
    points spread over the arc (map ``Ls[n]``, robot pose ``poses[n]``).
    """
    for n in nb.prange(Ls.shape[0]):
        c = math.cos(poses[n, 2])
        s = math.sin(poses[n, 2])
        total = 0.0
        for k in range(sensors.shape[0]):
            z = ranges[k]
            if z >= max_range:
                continue
            sx = poses[n, 0] + c * sensors[k, 0] - s * sensors[k, 1]
            sy = poses[n, 1] + s * sensors[k, 0] + c * sensors[k, 1]
            best = 0.0
            for r in range(n_rays):
                off = 0.0 if n_rays == 1 else half_cone * (2.0 * r / (n_rays - 1) - 1)
                a = poses[n, 2] + sensors[k, 2] + off
                p = _best_near(
                    Ls[n], x0, y0, res, sx + z * math.cos(a), sy + z * math.sin(a)
                )
                if p > best:
                    best = p
            total += math.log(p_rand + (1.0 - p_rand) * best)
        out[n] = total


sonar_loglik_many, sonar_loglik_many_parallel = serial_and_parallel(_sonar_loglik_many)


@nb.njit(**JIT)
def sonar_beam_loglik(L, x0, y0, res, px, py, pth, sensors, ranges, half_cone,
                      max_range, n_rays, sigma, p_rand, occ, c_unknown,
                      centre=False):  # fmt: skip
    """Log-likelihood of one ring reading from robot pose ``p`` in map ``L``.

    A beam model on the map: for each echo ``z < max_range``, ``n_rays`` rays
    across the cone march (in steps of half a cell, up to ``z + 3 sigma``)
    to the first cell whose log-odds exceed ``occ``; the nearest such cell
    over the cone is the expected range ``zhat``. The reading scores
    ``log(p_rand + (1 - p_rand) p)`` with ``p`` the larger of
    ``exp(-(z - zhat)^2 / (2 sigma^2))`` (0 when no cell was found) and
    ``c_unknown`` times the largest occupancy probability at the arc's ray
    ends (an echo from cells the map has not seen yet), the latter 0 when
    the map holds a wall more than ``3 sigma`` before the echo (the echo
    would have come from it). Max-range readings (specular misses) score 0.

    ``centre``: a ray's range to its first wall cell is the distance from the
    sonar to that cell's centre, not to where the ray enters it. The inverse
    model marks the cells whose centres lie at the echo's range, so the
    entry point falls short of the echo by about half a cell (0.06-0.15 m
    at the true poses of the loop world's drives, 10 cm cells), which the
    centre does not.
    """
    ny, nx = L.shape
    c = math.cos(pth)
    s = math.sin(pth)
    step = 0.5 * res
    total = 0.0
    for k in range(sensors.shape[0]):
        z = ranges[k]
        if z >= max_range:
            continue
        sx = px + c * sensors[k, 0] - s * sensors[k, 1]
        sy = py + s * sensors[k, 0] + c * sensors[k, 1]
        dlim = z + 3.0 * sigma
        zhat = np.inf
        q = 0.0
        # (centre: a cell entered at d has its centre at least d - res/sqrt(2) away)
        slack = 0.7072 * res if centre else 0.0
        for r in range(n_rays):
            off = 0.0 if n_rays == 1 else half_cone * (2.0 * r / (n_rays - 1) - 1.0)
            a = pth + sensors[k, 2] + off
            ca = math.cos(a)
            sa = math.sin(a)
            d = step
            while d < dlim and d < zhat + slack:
                j = int(math.floor((sx + d * ca - x0) / res))
                i = int(math.floor((sy + d * sa - y0) / res))
                if 0 <= i < ny and 0 <= j < nx and L[i, j] > occ:
                    if centre:
                        dc = math.hypot(x0 + (j + 0.5) * res - sx,
                                        y0 + (i + 0.5) * res - sy)  # fmt: skip
                        if dc < zhat:
                            zhat = dc
                    else:
                        zhat = d
                    break
                d += step
            p_end = _occ_prob(
                L, int(math.floor((sy + z * sa - y0) / res)),
                int(math.floor((sx + z * ca - x0) / res)),
            )  # fmt: skip
            if p_end > q:
                q = p_end
        p = 0.0
        if zhat < np.inf:
            e = (z - zhat) / sigma
            p = math.exp(-0.5 * e * e)
            if zhat < z - 3.0 * sigma:
                q = 0.0
        if c_unknown * q > p:
            p = c_unknown * q
        total += math.log(p_rand + (1.0 - p_rand) * p)
    return total


def _sonar_beam_loglik_many(Ls, x0, y0, res, poses, sensors, ranges, half_cone,
                            max_range, n_rays, sigma, p_rand, occ, c_unknown,
                            out, centre=False):  # fmt: skip
    """`sonar_beam_loglik` of one ring reading in each map ``Ls[n]`` at ``poses[n]``."""
    for n in nb.prange(Ls.shape[0]):
        out[n] = sonar_beam_loglik(
            Ls[n], x0, y0, res, poses[n, 0], poses[n, 1], poses[n, 2], sensors,
            ranges, half_cone, max_range, n_rays, sigma, p_rand, occ, c_unknown,
            centre,
        )  # fmt: skip


sonar_beam_loglik_many, sonar_beam_loglik_many_parallel = serial_and_parallel(
    _sonar_beam_loglik_many
)


def _copy_maps(Ls, src, dst):
    """Copy map ``Ls[src[q]]`` over ``Ls[dst[q]]`` for every ``q`` (in place).

    No ``dst`` may also be a ``src`` (the caller copies survivors over the
    maps of particles that died).
    """
    for q in nb.prange(src.shape[0]):
        Ls[dst[q]] = Ls[src[q]]


copy_maps, copy_maps_parallel = serial_and_parallel(_copy_maps)


# the laser's scan fitting lives in _kernels_match (this module's size); same names here
from ._kernels_match import (  # noqa: E402, F401
    _bilinear_evidence,
    _evidence,
    _match_score,
    match_laser_many,
    match_laser_many_parallel,
    scan_points,
)
