"""Numba kernels for grid FastSLAM's laser scan fitting (GMapping-like, cheap).

`match_laser_many` hill-climbs each particle's pose to fit the scan's end
points to its own map, scored by the maps' positive log-odds, bilinear
between cell centres; `fit_curvature_many` measures how sharply that score
peaks in position at each fit (where a corridor's walls leave the pose
free). Grids as in `robotlib.mapping._kernels`, which re-exports the
fitting. Imports nothing of robotlib's but the JIT config.
"""

import math

import numba as nb
import numpy as np

from .._config import JIT, serial_and_parallel
from ._kernels_cone import JIT_CONTRACT


@nb.njit(**JIT)
def _evidence(L, i, j):
    """Positive log-odds of cell ``(i, j)`` (0 if free, unknown or off the grid)."""
    if 0 <= i < L.shape[0] and 0 <= j < L.shape[1] and L[i, j] > 0:
        return np.float64(L[i, j])
    return 0.0


@nb.njit(**JIT_CONTRACT)
def _bilinear_evidence(L, x0, y0, res, px, py):
    """`_evidence` at point ``(px, py)``, bilinear between cell centres."""
    gx = (px - x0) / res - 0.5
    gy = (py - y0) / res - 0.5
    j = int(math.floor(gx))
    i = int(math.floor(gy))
    fx = gx - j
    fy = gy - i
    if 0 <= i and i + 1 < L.shape[0] and 0 <= j and j + 1 < L.shape[1]:
        # inside the grid: the same sum without the per-cell bounds tests
        e00 = max(np.float64(L[i, j]), 0.0)
        e01 = max(np.float64(L[i, j + 1]), 0.0)
        e10 = max(np.float64(L[i + 1, j]), 0.0)
        e11 = max(np.float64(L[i + 1, j + 1]), 0.0)
        return (1 - fy) * ((1 - fx) * e00 + fx * e01) + fy * ((1 - fx) * e10 + fx * e11)
    return (1 - fy) * ((1 - fx) * _evidence(L, i, j) + fx * _evidence(L, i, j + 1)) + (
        fy * ((1 - fx) * _evidence(L, i + 1, j) + fx * _evidence(L, i + 1, j + 1))
    )


@nb.njit(**JIT_CONTRACT)
def _match_score(L, x0, y0, res, px, py, pth, bx, by):
    """Sum of `_bilinear_evidence` at the scan's end points from robot pose p.

    ``bx, by`` (B,) are the end points of the returns in the robot frame, so
    each pose costs one cosine and sine.
    """
    c = math.cos(pth)
    s = math.sin(pth)
    total = 0.0
    for r in range(bx.shape[0]):
        total += _bilinear_evidence(
            L, x0, y0, res, px + c * bx[r] - s * by[r], py + s * bx[r] + c * by[r]
        )
    return total


@nb.njit(**JIT)
def scan_points(mount, angles, ranges, max_range):
    """End points (B, 2) of the returns (``ranges < max_range``), robot frame.

    The laser sits at ``mount = (x, y, heading)`` on the robot.
    """
    nr = 0
    for r in range(angles.shape[0]):
        if ranges[r] < max_range:
            nr += 1
    out = np.empty((nr, 2))
    q = 0
    for r in range(angles.shape[0]):
        if ranges[r] < max_range:
            a = mount[2] + angles[r]
            out[q, 0] = mount[0] + ranges[r] * math.cos(a)
            out[q, 1] = mount[1] + ranges[r] * math.sin(a)
            q += 1
    return out


def _match_laser_many(Ls, x0, y0, res, poses, mount, angles, ranges, max_range,
                     step_xy, step_th, levels, w_xy, w_th, out):  # fmt: skip
    """Hill-climb each robot pose ``poses[n]`` to fit the scan to map ``Ls[n]``.

    From each pose, try moves of ``step_xy`` (m) along x and y and
    ``step_th`` (rad) in heading, both ways; take the best that raises the
    score; when none does, halve the steps, ``levels`` times. The score is
    `_match_score` less the prior ``w_xy d^2 + w_th a^2`` (``d``: distance
    from the start pose, m; ``a``: turn from it, rad; 0 and 0: no prior),
    so a scan that does not pin the pose (a corridor's walls) leaves it
    where the motion put it. The move straight back to the last pose is not
    scored (it scored below the pose it left). Writes the fitted poses to
    ``out`` (N, 3).
    """
    pts = scan_points(mount, angles, ranges, max_range)
    bx = np.ascontiguousarray(pts[:, 0])
    by = np.ascontiguousarray(pts[:, 1])
    for n in nb.prange(Ls.shape[0]):
        px = poses[n, 0]
        py = poses[n, 1]
        pth = poses[n, 2]
        best = _match_score(Ls[n], x0, y0, res, px, py, pth, bx, by)
        x_0 = px
        y_0 = py
        t_0 = pth
        sxy = step_xy
        sth = step_th
        for _ in range(levels):
            back = -1  # the move back to the last pose: never better, not scored
            for _it in range(20):
                bi = -1
                bx_ = px
                by_ = py
                bt = pth
                for k in range(6):
                    if k == back:
                        continue
                    qx = px + (sxy if k == 0 else (-sxy if k == 1 else 0.0))
                    qy = py + (sxy if k == 2 else (-sxy if k == 3 else 0.0))
                    qt = pth + (sth if k == 4 else (-sth if k == 5 else 0.0))
                    v = _match_score(Ls[n], x0, y0, res, qx, qy, qt, bx, by)
                    if w_xy > 0.0 or w_th > 0.0:
                        v -= w_xy * ((qx - x_0) ** 2 + (qy - y_0) ** 2)
                        v -= w_th * (qt - t_0) ** 2
                    if v > best:
                        best = v
                        bi = k
                        bx_ = qx
                        by_ = qy
                        bt = qt
                if bi < 0:
                    break
                back = bi ^ 1
                px = bx_
                py = by_
                pth = bt
            sxy *= 0.5
            sth *= 0.5
        out[n, 0] = px
        out[n, 1] = py
        out[n, 2] = math.atan2(math.sin(pth), math.cos(pth))


match_laser_many, match_laser_many_parallel = serial_and_parallel(_match_laser_many)


def _fit_curvature_many(Ls, x0, y0, res, poses, mount, angles, ranges, max_range,
                        h, out):  # fmt: skip
    """Curvature of the fit's score in position at each pose ``poses[n]``.

    Writes ``(cxx, cxy, cyy)`` to ``out[n]``: minus the second differences
    of `_match_score` in map ``Ls[n]`` over steps of ``h`` m in x and y (the
    heading held), score units per m^2. Large along a direction the scan
    pins; near 0 along a blank corridor.
    """
    pts = scan_points(mount, angles, ranges, max_range)
    bx = np.ascontiguousarray(pts[:, 0])
    by = np.ascontiguousarray(pts[:, 1])
    for n in nb.prange(Ls.shape[0]):
        px = poses[n, 0]
        py = poses[n, 1]
        t = poses[n, 2]
        L = Ls[n]
        f0 = _match_score(L, x0, y0, res, px, py, t, bx, by)
        fxp = _match_score(L, x0, y0, res, px + h, py, t, bx, by)
        fxm = _match_score(L, x0, y0, res, px - h, py, t, bx, by)
        fyp = _match_score(L, x0, y0, res, px, py + h, t, bx, by)
        fym = _match_score(L, x0, y0, res, px, py - h, t, bx, by)
        fpp = _match_score(L, x0, y0, res, px + h, py + h, t, bx, by)
        fpm = _match_score(L, x0, y0, res, px + h, py - h, t, bx, by)
        fmp = _match_score(L, x0, y0, res, px - h, py + h, t, bx, by)
        fmm = _match_score(L, x0, y0, res, px - h, py - h, t, bx, by)
        out[n, 0] = (2.0 * f0 - fxp - fxm) / (h * h)
        out[n, 1] = -(fpp - fpm - fmp + fmm) / (4.0 * h * h)
        out[n, 2] = (2.0 * f0 - fyp - fym) / (h * h)


fit_curvature_many, fit_curvature_many_parallel = serial_and_parallel(
    _fit_curvature_many
)
