"""Numba kernels for cheap copies of particle maps in grid FastSLAM.

Two particles' maps differ only in cells written since they last held the
same map, so resampling need copy only a box around those cells
(`robotlib.mapping.sharing` keeps the boxes); these kernels give the box of
the cells a reading writes. Boxes are ``(i0, i1, j0, j1)``
cell rows and columns, inclusive, empty when ``i0 > i1``. Imports nothing of
robotlib's but the JIT config.
"""

import math

import numba as nb
import numpy as np

from .._config import JIT


@nb.njit(**JIT)
def _box_of_points(xs, ys, x0, y0, res, ny, nx, out):
    """Cells (one more all round) of the points' bounding box, clipped to the grid.

    ``xs, ys`` (P,), P >= 1, m; writes ``(i0, i1, j0, j1)`` to ``out``.
    """
    xlo = xs.min()
    xhi = xs.max()
    ylo = ys.min()
    yhi = ys.max()
    out[0] = max(0, int(math.floor((ylo - y0) / res)) - 1)
    out[1] = min(ny - 1, int(math.floor((yhi - y0) / res)) + 1)
    out[2] = max(0, int(math.floor((xlo - x0) / res)) - 1)
    out[3] = min(nx - 1, int(math.floor((xhi - x0) / res)) + 1)


@nb.njit(**JIT)
def _box_of_bounds(xlo, xhi, ylo, yhi, x0, y0, res, ny, nx, out):
    """`_box_of_points` of the points' bounds ``xlo, xhi, ylo, yhi`` (m)."""
    out[0] = max(0, int(math.floor((ylo - y0) / res)) - 1)
    out[1] = min(ny - 1, int(math.floor((yhi - y0) / res)) + 1)
    out[2] = max(0, int(math.floor((xlo - x0) / res)) - 1)
    out[3] = min(nx - 1, int(math.floor((xhi - x0) / res)) + 1)


@nb.njit(**JIT)
def laser_boxes(x0, y0, res, ny, nx, lposes, angles, ranges, max_range, out):
    """Boxes ``out`` (N, 4) holding every cell a scan from ``lposes[n]`` writes.

    Each beam writes cells from the laser to its end point (``max_range`` for
    a beam with no return), so the box of the laser and the end points, one
    cell wider all round, holds them.
    """
    nb_ = angles.shape[0]
    # the end points in the laser's frame once; each pose turns and moves them
    # (one cosine and sine a pose; the box is a cell wider than the points, so
    # the last bits of the turn do not matter)
    fx = np.empty(nb_)
    fy = np.empty(nb_)
    for r in range(nb_):
        z = ranges[r] if ranges[r] < max_range else max_range
        fx[r] = z * math.cos(angles[r])
        fy[r] = z * math.sin(angles[r])
    for n in range(lposes.shape[0]):
        lx = lposes[n, 0]
        ly = lposes[n, 1]
        c = math.cos(lposes[n, 2])
        s = math.sin(lposes[n, 2])
        xlo = xhi = lx
        ylo = yhi = ly
        for r in range(nb_):
            px = lx + c * fx[r] - s * fy[r]
            py = ly + s * fx[r] + c * fy[r]
            xlo = min(xlo, px)
            xhi = max(xhi, px)
            ylo = min(ylo, py)
            yhi = max(yhi, py)
        _box_of_bounds(xlo, xhi, ylo, yhi, x0, y0, res, ny, nx, out[n])


@nb.njit(**JIT)
def disc_boxes(x0, y0, res, ny, nx, poses, radius, out):
    """Boxes ``out`` (N, 4) of the discs of ``radius`` (m) about ``poses[n]``."""
    xs = np.empty(2)
    ys = np.empty(2)
    for n in range(poses.shape[0]):
        xs[0] = poses[n, 0] - radius
        xs[1] = poses[n, 0] + radius
        ys[0] = poses[n, 1] - radius
        ys[1] = poses[n, 1] + radius
        _box_of_points(xs, ys, x0, y0, res, ny, nx, out[n])
