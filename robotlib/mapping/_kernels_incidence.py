"""Numba kernels for choosing, per reading, which sonar echoes mark walls.

A sonar cone that meets a wall obliquely echoes from its edge nearest the
wall's normal, so its arc at the range lies in free space. `sonar_incidence_many`
estimates the wall's direction at each echo from the particle's own map (the
log-odds gradient about the point on the cone's axis at the range) and
returns the cosine of the angle of incidence; `sonar_update_marks_many` then
adds each reading with its arc marked or not, per particle and sonar. Grids
as in `robotlib.mapping._kernels`. Imports nothing of robotlib's but the JIT
config and the sibling kernels.
"""

import math

import numba as nb
import numpy as np

from .._config import serial_and_parallel
from ._kernels import _cone_update, cone_weights

GRADIENT_RADIUS = 2
"""Cells each side of the echo's cell that the map's gradient sums over."""


def _sonar_incidence_many(Ls, x0, y0, res, poses, sensors, ranges, max_range,
                          g_min, out):  # fmt: skip
    """Cosine of each echo's angle of incidence in each particle's map: ``out[n, k]``.

    The gradient of map ``Ls[n]`` (log-odds clamped to [-3, 3]) is summed
    over the ``2 r + 1`` cells square (``r``: `GRADIENT_RADIUS`) about the
    point on sonar ``k``'s axis at its range, from robot pose ``poses[n]``:
    ``g = sum (dj, di) L[i + di, j + dj]``. ``out[n, k]`` is ``|u . g| /
    |g|`` (``u``: the axis), or NaN when ``|g| < g_min`` (no wall mapped
    there yet), when the reading is ``max_range`` or when the point is within
    ``r`` cells of the grid's edge.
    """
    ny, nx = Ls.shape[1], Ls.shape[2]
    r = GRADIENT_RADIUS
    for n in nb.prange(Ls.shape[0]):
        c = math.cos(poses[n, 2])
        s = math.sin(poses[n, 2])
        for k in range(sensors.shape[0]):
            out[n, k] = np.nan
            z = ranges[k]
            if z >= max_range:
                continue
            a = poses[n, 2] + sensors[k, 2]
            ux = math.cos(a)
            uy = math.sin(a)
            px = poses[n, 0] + c * sensors[k, 0] - s * sensors[k, 1] + z * ux
            py = poses[n, 1] + s * sensors[k, 0] + c * sensors[k, 1] + z * uy
            j = int(math.floor((px - x0) / res))
            i = int(math.floor((py - y0) / res))
            if i < r or j < r or i >= ny - r or j >= nx - r:
                continue
            gx = 0.0
            gy = 0.0
            for di in range(-r, r + 1):
                for dj in range(-r, r + 1):
                    v = min(max(np.float64(Ls[n, i + di, j + dj]), -3.0), 3.0)
                    gx += dj * v
                    gy += di * v
            g = math.sqrt(gx * gx + gy * gy)
            if g >= g_min:
                out[n, k] = abs(ux * gx + uy * gy) / g


sonar_incidence_many, sonar_incidence_many_parallel = serial_and_parallel(
    _sonar_incidence_many
)


def _sonar_update_marks_many(Ls, x0, y0, res, poses, sensors, ranges, marks,
                             half_cone, max_range, thickness, l_occ, l_free,
                             sigma, max_weight, l_min, l_max):  # fmt: skip
    """One ring reading into each map ``Ls[n]`` at ``poses[n]``, walls per reading.

    As `robotlib.mapping._kernels.sonar_update_many`, except that sonar
    ``k``'s arc adds ``l_occ`` to map ``n`` only where ``marks[n, k]``
    (else its cone is freed only).
    """
    poly, table = cone_weights(half_cone, sigma)
    for n in nb.prange(Ls.shape[0]):
        c = math.cos(poses[n, 2])
        s = math.sin(poses[n, 2])
        for k in range(sensors.shape[0]):
            sx = poses[n, 0] + c * sensors[k, 0] - s * sensors[k, 1]
            sy = poses[n, 1] + s * sensors[k, 0] + c * sensors[k, 1]
            _cone_update(
                Ls[n], x0, y0, res, sx, sy, poses[n, 2] + sensors[k, 2], ranges[k],
                half_cone, max_range, thickness, l_occ if marks[n, k] else 0.0,
                l_free, sigma, max_weight, l_min, l_max, poly, table,
            )  # fmt: skip


sonar_update_marks_many, sonar_update_marks_many_parallel = serial_and_parallel(
    _sonar_update_marks_many
)
