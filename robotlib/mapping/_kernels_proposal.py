"""Numba kernels for laser FastSLAM's scan-matched proposal (GMapping's).

A scan is scored against a likelihood field of each particle's own map: a
return's end point scores ``log(p_rand + (1 - p_rand) exp(-d^2 / (2
sigma^2)))``, ``d`` the distance (m) from the end point to the nearest
occupied cell centre (log-odds above ``occ``) among the 3 x 3 cells around
it (none: ``exp`` is 0), measured along the surface's normal at the end
point where the scan gives one (point to line). A cell counts as occupied or
not, however often it was seen, and a wall scores an end point by how far
off the wall it lies, not where along it, so the cells a blank corridor's
walls were seen most often from do not pull the pose back along the
corridor (the fit of `robotlib.mapping._kernels_match` sums the log-odds
over whole distances, and does).

`fit_pose_many` hill-climbs each particle's predicted pose on that score
(times a temperature) plus the motion prior's log-density;
`field_loglik_many` scores K candidate poses per particle. Grids as in
`robotlib.mapping._kernels`; end points ``(bx, by)`` in the robot frame
(`robotlib.mapping._kernels_match.scan_points`). Imports nothing of
robotlib's but the JIT config.
"""

import math

import numba as nb
import numpy as np

from .._config import JIT, serial_and_parallel


@nb.njit(**JIT)
def _nearest_occupied_d2(L, x0, y0, res, px, py, nx_, ny_, occ):
    """Squared distance (m^2) from ``(px, py)`` to the nearest occupied cell centre.

    Among the 3 x 3 cells around the point's cell; ``inf`` if none is
    occupied (log-odds above ``occ``) or the cells are off the grid. With a
    unit normal ``(nx_, ny_)`` (map frame) the distance is measured along it
    only (point to line); with ``(0, 0)``, whole.
    """
    j = int(math.floor((px - x0) / res))
    i = int(math.floor((py - y0) / res))
    ny, nx = L.shape
    best = np.inf
    for ii in range(i - 1, i + 2):
        if ii < 0 or ii >= ny:
            continue
        cy = y0 + (ii + 0.5) * res
        for jj in range(j - 1, j + 2):
            if 0 <= jj < nx and L[ii, jj] > occ:
                cx = x0 + (jj + 0.5) * res
                if nx_ == 0.0 and ny_ == 0.0:
                    d2 = (px - cx) ** 2 + (py - cy) ** 2
                else:
                    d2 = ((px - cx) * nx_ + (py - cy) * ny_) ** 2
                if d2 < best:
                    best = d2
    return best


@nb.njit(**JIT)
def field_score(L, x0, y0, res, px, py, pth, bx, by, nx, ny, occ, sigma, p_rand):
    """Log-likelihood of the end points ``(bx, by)`` (B,) seen from robot pose p.

    ``(nx, ny)`` (B,): each end point's surface normal, robot frame (unit,
    or 0 and 0 for none).
    """
    c = math.cos(pth)
    s = math.sin(pth)
    k = 0.5 / (sigma * sigma)
    total = 0.0
    for r in range(bx.shape[0]):
        d2 = _nearest_occupied_d2(
            L, x0, y0, res, px + c * bx[r] - s * by[r], py + s * bx[r] + c * by[r],
            c * nx[r] - s * ny[r], s * nx[r] + c * ny[r], occ,
        )  # fmt: skip
        total += math.log(p_rand + (1.0 - p_rand) * math.exp(-d2 * k))
    return total


@nb.njit(**JIT)
def log_prior(qx, qy, qt, ux, uy, ut, sig_along, sig_lat, sig_th):
    """Motion prior's log-density (less its constant) of pose q about pose u.

    Independent Gaussians along u's heading, across it and in heading, with
    standard deviations ``sig_along``, ``sig_lat`` (m) and ``sig_th`` (rad).
    """
    c = math.cos(ut)
    s = math.sin(ut)
    dx = qx - ux
    dy = qy - uy
    a = (c * dx + s * dy) / sig_along
    b = (-s * dx + c * dy) / sig_lat
    t = math.atan2(math.sin(qt - ut), math.cos(qt - ut)) / sig_th
    return -0.5 * (a * a + b * b + t * t)


def _fit_pose_many(Ls, x0, y0, res, pred, bx, by, nx, ny, occ, sigma, p_rand,
                   temperature, sig, step_xy, step_th, levels, out):  # fmt: skip
    """Hill-climb each predicted pose ``pred[n]`` on map ``Ls[n]``; write ``out``.

    The objective is ``temperature * field_score + log_prior`` about
    ``pred[n]`` with ``sig = (along, lateral, heading)``. From each pose, try
    moves of ``step_xy`` (m) along x and y and ``step_th`` (rad) in heading,
    both ways; take the best that raises the objective; when none does,
    halve the steps, ``levels`` times (at most 20 moves per level).
    """
    for n in nb.prange(Ls.shape[0]):
        ux = pred[n, 0]
        uy = pred[n, 1]
        ut = pred[n, 2]
        px = ux
        py = uy
        pt = ut
        best = temperature * field_score(
            Ls[n], x0, y0, res, px, py, pt, bx, by, nx, ny, occ, sigma, p_rand
        )
        sxy = step_xy
        sth = step_th
        for _ in range(levels):
            for _it in range(20):
                bi = -1
                qx_ = px
                qy_ = py
                qt_ = pt
                for k in range(6):
                    qx = px + (sxy if k == 0 else (-sxy if k == 1 else 0.0))
                    qy = py + (sxy if k == 2 else (-sxy if k == 3 else 0.0))
                    qt = pt + (sth if k == 4 else (-sth if k == 5 else 0.0))
                    v = temperature * field_score(
                        Ls[n],
                        x0,
                        y0,
                        res,
                        qx,
                        qy,
                        qt,
                        bx,
                        by,
                        nx,
                        ny,
                        occ,
                        sigma,
                        p_rand,
                    ) + log_prior(qx, qy, qt, ux, uy, ut, sig[0], sig[1], sig[2])
                    if v > best:
                        best = v
                        bi = k
                        qx_ = qx
                        qy_ = qy
                        qt_ = qt
                if bi < 0:
                    break
                px = qx_
                py = qy_
                pt = qt_
            sxy *= 0.5
            sth *= 0.5
        out[n, 0] = px
        out[n, 1] = py
        out[n, 2] = math.atan2(math.sin(pt), math.cos(pt))


fit_pose_many, fit_pose_many_parallel = serial_and_parallel(_fit_pose_many)


def _field_loglik_many(Ls, x0, y0, res, poses, bx, by, nx, ny, occ, sigma, p_rand, out):
    """`field_score` of the scan at each candidate ``poses[n, k]`` in map ``Ls[n]``.

    ``poses`` (N, K, 3); writes ``out`` (N, K).
    """
    for n in nb.prange(Ls.shape[0]):
        for k in range(poses.shape[1]):
            out[n, k] = field_score(
                Ls[n], x0, y0, res, poses[n, k, 0], poses[n, k, 1], poses[n, k, 2],
                bx, by, nx, ny, occ, sigma, p_rand,
            )  # fmt: skip


field_loglik_many, field_loglik_many_parallel = serial_and_parallel(_field_loglik_many)
