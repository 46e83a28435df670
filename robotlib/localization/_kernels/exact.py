"""Exact expected readings: each sonar cone cast against the walls near its sensor.

Numba kernels: contiguous arrays and scalars in, no Python objects; they
import nothing of robotlib but the JIT options and other kernels.
"""

import math

import numba as nb
import numpy as np

from ..._config import JIT, JIT_PARALLEL
from ...sensing._kernels import cone_echo, cone_walls

_CULL_MARGIN = 1e-6
"""Widening of each cone for `robotlib.sensing._kernels.cone_walls`, rad."""


@nb.njit(**JIT)
def _expected_pose_blocks(
    k, poses, sensors, segments, start, block_segs, grid, n_rays, cone, max_range,
    min_range, cos_specular, near, out,
):  # fmt: skip
    x0, y0, inv_block, nbx, nby = grid
    half = 0.5 * cone + _CULL_MARGIN
    ch = math.cos(half) if half < 0.5 * math.pi else 0.0
    sh = math.sin(half)
    c = math.cos(poses[k, 2])
    s = math.sin(poses[k, 2])
    for i in range(sensors.shape[0]):
        sx = poses[k, 0] + c * sensors[i, 0] - s * sensors[i, 1]
        sy = poses[k, 1] + s * sensors[i, 0] + c * sensors[i, 1]
        bx = math.floor((sx - x0) * inv_block)
        by = math.floor((sy - y0) * inv_block)
        if 0 <= bx < nbx and 0 <= by < nby:
            b = int(by) * int(nbx) + int(bx)
            walls = block_segs[start[b] : start[b + 1]]
        else:
            walls = segments
        ci = math.cos(sensors[i, 2])
        si = math.sin(sensors[i, 2])
        count = cone_walls(
            sx, sy, c * ci - s * si, s * ci + c * si, ch, sh, walls, max_range, near
        )
        echo = cone_echo(
            sx, sy, poses[k, 2] + sensors[i, 2], near[:count], n_rays, cone,
            max_range, cos_specular,
        )  # fmt: skip
        z = echo if echo < max_range else max_range
        out[k, i] = min(max(z, min_range), max_range)


@nb.njit(**JIT)
def expected_scan_blocks(
    poses, sensors, segments, start, block_segs, grid, n_rays, cone, max_range,
    min_range, cos_specular, out,
):  # fmt: skip
    """`expected_scan` (of `robotlib.sensing._kernels`), each cone against nearby walls.

    ``grid`` ``(x0, y0, 1 / side, nbx, nby)`` cuts the plane into square
    blocks; the walls a sensor in block ``b`` may reach within ``max_range``
    are ``block_segs[start[b]:start[b + 1]]`` (`wall_blocks`), and of those
    the ones in its cone (`robotlib.sensing._kernels.cone_walls`). A sensor outside
    the blocks tests all ``segments``. The same readings as `expected_scan`.
    """
    near = np.empty_like(segments)
    for k in range(poses.shape[0]):
        _expected_pose_blocks(
            k, poses, sensors, segments, start, block_segs, grid, n_rays, cone,
            max_range, min_range, cos_specular, near, out,
        )  # fmt: skip


@nb.njit(**JIT_PARALLEL)
def expected_scan_blocks_parallel(
    poses, sensors, segments, start, block_segs, grid, n_rays, cone, max_range,
    min_range, cos_specular, out,
):  # fmt: skip
    """`expected_scan_blocks` with the poses spread over threads."""
    for k in nb.prange(poses.shape[0]):
        near = np.empty_like(segments)
        _expected_pose_blocks(
            k, poses, sensors, segments, start, block_segs, grid, n_rays, cone,
            max_range, min_range, cos_specular, near, out,
        )  # fmt: skip


@nb.njit(**JIT)
def _block_span(lo, hi, origin, side, count):
    """Blocks ``[first, last]`` of ``count`` whose span overlaps ``[lo, hi]``."""
    first = 0
    while first < count and origin + side * first + side < lo:
        first += 1
    last = first - 1
    while last + 1 < count and hi >= origin + side * (last + 1):
        last += 1
    return first, last


@nb.njit(**JIT)
def _wall_blocks(seg, xmin, ymin, side, nbx, nby, grow):
    """`wall_blocks` in two passes over the walls: count, then fill."""
    m = seg.shape[0]
    spans = np.empty((m, 4), dtype=np.int64)
    counts = np.zeros(nby * nbx + 1, dtype=np.int64)
    for k in range(m):
        bx0, bx1 = _block_span(
            min(seg[k, 0], seg[k, 2]) - grow, max(seg[k, 0], seg[k, 2]) + grow,
            xmin, side, nbx,
        )  # fmt: skip
        by0, by1 = _block_span(
            min(seg[k, 1], seg[k, 3]) - grow, max(seg[k, 1], seg[k, 3]) + grow,
            ymin, side, nby,
        )  # fmt: skip
        spans[k, 0], spans[k, 1], spans[k, 2], spans[k, 3] = bx0, bx1, by0, by1
        for by in range(by0, by1 + 1):
            for bx in range(bx0, bx1 + 1):
                counts[by * nbx + bx + 1] += 1
    start = np.cumsum(counts)
    fill = start[:-1].copy()
    block_segs = np.empty((start[-1], 4))
    for k in range(m):  # walls in order: each block's list keeps it
        for by in range(spans[k, 2], spans[k, 3] + 1):
            for bx in range(spans[k, 0], spans[k, 1] + 1):
                b = by * nbx + bx
                for t in range(4):
                    block_segs[fill[b], t] = seg[k, t]
                fill[b] += 1
    return start, block_segs


def wall_blocks(segments, bounds, max_range, side=1.0):
    """List the walls each block of ``side`` m may reach (`expected_scan_blocks`).

    A wall is listed for a block when its bounding box, grown by
    ``max_range`` (and 1e-6 m), overlaps the block: then and only then can a
    sensor in the block pass `robotlib.sensing._kernels.cone_walls`'s range test for
    it. Walls keep their order. Memory: the lists themselves (no block by
    wall table).

    Returns
    -------
    tuple
        ``(start, block_segs, grid)``: offsets (nby * nbx + 1,) int64, the
        walls of each block in turn (K, 4), and ``(x0, y0, 1 / side, nbx, nby)``.
    """
    seg = np.ascontiguousarray(segments, dtype=np.float64).reshape(-1, 4)
    xmin, ymin, xmax, ymax = (float(v) for v in bounds)
    nbx = max(1, math.ceil((xmax - xmin) / side))
    nby = max(1, math.ceil((ymax - ymin) / side))
    start, block_segs = _wall_blocks(
        seg, xmin, ymin, float(side), nbx, nby, float(max_range) + 1e-6
    )
    return start, block_segs, (xmin, ymin, 1.0 / side, nbx, nby)
