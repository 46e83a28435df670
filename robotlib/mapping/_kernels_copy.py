"""Numba kernels for cheap copies of particle maps in grid FastSLAM.

Two particles' maps differ only in cells written since they last held the
same map, so resampling need copy only a box around those cells
(`robotlib.mapping.sharing` keeps the boxes). Boxes are ``(i0, i1, j0, j1)``
cell rows and columns, inclusive, empty when ``i0 > i1``. Imports nothing of
robotlib's but the JIT config.
"""

import math

import numba as nb
import numpy as np

from .._config import JIT, serial_and_parallel


def _copy_boxes(Ls, src, dst, boxes):
    """Copy box ``boxes[q]`` of map ``Ls[src[q]]`` over map ``Ls[dst[q]]``.

    No ``dst`` may also be a ``src``.
    """
    for q in nb.prange(src.shape[0]):
        i0, i1, j0, j1 = boxes[q, 0], boxes[q, 1], boxes[q, 2], boxes[q, 3]
        if i0 > i1 or j0 > j1:
            continue
        for i in range(i0, i1 + 1):
            for j in range(j0, j1 + 1):
                Ls[dst[q], i, j] = Ls[src[q], i, j]


copy_boxes, copy_boxes_parallel = serial_and_parallel(_copy_boxes)


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
def laser_boxes(x0, y0, res, ny, nx, lposes, angles, ranges, max_range, out):
    """Boxes ``out`` (N, 4) holding every cell a scan from ``lposes[n]`` writes.

    Each beam writes cells from the laser to its end point (``max_range`` for
    a beam with no return), so the box of the laser and the end points, one
    cell wider all round, holds them.
    """
    nb_ = angles.shape[0]
    xs = np.empty(nb_ + 1)
    ys = np.empty(nb_ + 1)
    for n in range(lposes.shape[0]):
        xs[nb_] = lposes[n, 0]
        ys[nb_] = lposes[n, 1]
        for r in range(nb_):
            z = ranges[r] if ranges[r] < max_range else max_range
            a = lposes[n, 2] + angles[r]
            xs[r] = lposes[n, 0] + z * math.cos(a)
            ys[r] = lposes[n, 1] + z * math.sin(a)
        _box_of_points(xs, ys, x0, y0, res, ny, nx, out[n])


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
