"""Cone tables: expected sonar ranges per grid cell and heading bin, built and read.

Numba kernels: contiguous arrays and scalars in, no Python objects; they
import nothing of robotlib but the JIT options and other kernels.
"""

import math

import numba as nb
import numpy as np

from ..._config import JIT, JIT_PARALLEL, serial_and_parallel
from ...sensing._kernels import cone_echo
from ...world._kernels import point_segment_distance
from .common import _TWO_PI


@nb.njit(**JIT)
def _cone_cell(
    cx,
    cy,
    segments,
    n_bins,
    ray_step,
    n_rays,
    cone,
    max_range,
    min_range,
    cos_specular,
    rays,
    table,
    i,
    j,
):
    """Fill ``table[i, j, :]`` for a sonar at ``(cx, cy)`` (see `build_cone_table`)."""
    half = (n_rays - 1) // 2 if n_rays > 1 else 0
    if ray_step > 0:
        for b in range(n_bins):
            # the echo alone: `sonar_cone` would also trace each miss's bounce
            rays[b] = cone_echo(
                cx, cy, b * _TWO_PI / n_bins, segments, 1, 0.0, max_range, cos_specular
            )
    for b in range(n_bins):
        if ray_step > 0:
            echo = np.inf
            for k in range(-half, half + 1):
                r = rays[(b + k * ray_step) % n_bins]
                if r < echo:
                    echo = r
        else:
            echo = cone_echo(
                cx,
                cy,
                b * _TWO_PI / n_bins,
                segments,
                n_rays,
                cone,
                max_range,
                cos_specular,
            )
        z = max_range if echo >= max_range else echo
        z = min(max(z, min_range), max_range)
        table[i, j, b] = np.uint16(round(z * 1000.0))


@nb.njit(**JIT_PARALLEL)
def build_cone_table(
    segments,
    x0,
    y0,
    resolution,
    n_bins,
    ray_step,
    n_rays,
    cone,
    max_range,
    min_range,
    cos_specular,
    block,
    table,
):
    """Fill ``table`` (ny, nx, n_bins) uint16 with cone ranges in mm.

    ``table[i, j, b]`` is the expected range of a sonar at the centre of cell
    ``(i, j)`` pointing along ``b * 2 pi / n_bins``. When the cone's rays are
    ``ray_step`` bins apart (``ray_step > 0``) each direction's single ray is
    cast once and a cone is the nearest echo of its ``n_rays`` rays, which is
    what `sonar_cone` computes; otherwise (``ray_step == 0``) every cone is
    cast with `sonar_cone`.

    Cells are filled in square blocks of ``block`` cells (in parallel), each
    against only the walls that come within ``max_range`` of the block: a
    wall further away cannot echo, so the table is the same as with all
    walls.
    """
    ny, nx, _ = table.shape
    nbx = (nx + block - 1) // block
    nby = (ny + block - 1) // block
    reach = max_range + 0.75 * block * resolution  # > max_range + half diagonal
    for q in nb.prange(nbx * nby):
        bi = q // nbx
        bj = q % nbx
        bx = x0 + (bj + 0.5) * block * resolution
        by = y0 + (bi + 0.5) * block * resolution
        keep = np.zeros(segments.shape[0], dtype=np.bool_)
        count = 0
        for m in range(segments.shape[0]):
            d = point_segment_distance(
                bx, by, segments[m, 0], segments[m, 1], segments[m, 2], segments[m, 3]
            )
            if d <= reach:
                keep[m] = True
                count += 1
        near = np.empty((count, 4))
        c = 0
        for m in range(segments.shape[0]):
            if keep[m]:
                for t in range(4):
                    near[c, t] = segments[m, t]
                c += 1
        rays = np.empty(n_bins)
        for i in range(bi * block, min((bi + 1) * block, ny)):
            cy = y0 + (i + 0.5) * resolution
            for j in range(bj * block, min((bj + 1) * block, nx)):
                cx = x0 + (j + 0.5) * resolution
                _cone_cell(
                    cx,
                    cy,
                    near,
                    n_bins,
                    ray_step,
                    n_rays,
                    cone,
                    max_range,
                    min_range,
                    cos_specular,
                    rays,
                    table,
                    i,
                    j,
                )


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
        c = math.cos(particles[j, 2])
        s = math.sin(particles[j, 2])
        for i in range(sensors.shape[0]):
            out[j, i] = (
                _table_mm(particles, j, c, s, sensors, i, table, x0, y0, inv_res)
                * 0.001
            )


expected_table, expected_table_parallel = serial_and_parallel(_expected_table)
