"""Numba kernel for grid FastSLAM's sonar weighing: a beam model per cone.

Each echo (``z < max_range``) is scored against the cone's first-occupied
distance in the particle's own map. Rays across the cone march out from the
sonar in steps of half a cell; along each, the first cell whose log-odds
exceed ``occ`` is a wall, and the first cell with ``|L| < known`` is a cell
the map has not seen. Over the cone:

- a wall nearer than every unseen cell: the expected range ``zhat`` is the
  nearest wall, and the echo scores ``log(p_rand + (1 - p_rand)
  exp(-(z - zhat)^2 / (2 sigma^2)))``;
- an unseen cell first (no wall before it, before ``z + 3 sigma``): the map
  cannot predict the echo, which scores ``l_unknown`` (a constant near a
  matching echo's mean score, so that looking into unmapped cells neither
  pays nor costs: scoring it lower pulls particles back into what they have
  mapped, higher pushes them out of it);
- neither (the cone free to ``z + 3 sigma``): an echo where the map is free,
  ``log(p_rand)``.

Max-range readings (no echo, or a specular miss) score 0 for every
particle: they say nothing. Grids as in `robotlib.mapping._kernels`.
Imports nothing of robotlib's but the JIT config.
"""

import math

import numba as nb
import numpy as np

from .._config import JIT, serial_and_parallel


@nb.njit(**JIT)
def sonar_cone_loglik(L, x0, y0, res, px, py, pth, sensors, ranges, half_cone,
                      max_range, n_rays, sigma, p_rand, occ, known,
                      l_unknown, offset):  # fmt: skip
    """Log-likelihood of one ring reading from robot pose ``p`` in map ``L``.

    See the module docstring. ``sensors`` (S, 3) are the sonar poses in the
    robot frame, ``ranges`` (S,) the readings (m); ``n_rays`` rays span the
    cone (``half_cone`` rad either side of its axis).
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
        dunk = np.inf
        for r in range(n_rays):
            off = 0.0 if n_rays == 1 else half_cone * (2.0 * r / (n_rays - 1) - 1.0)
            a = pth + sensors[k, 2] + off
            ca = math.cos(a)
            sa = math.sin(a)
            d = step
            while d < dlim and d < zhat and d < dunk:
                j = int(math.floor((sx + d * ca - x0) / res))
                i = int(math.floor((sy + d * sa - y0) / res))
                v = np.float64(L[i, j]) if 0 <= i < ny and 0 <= j < nx else 0.0
                if v > occ:
                    zhat = d
                    break
                if abs(v) < known:
                    dunk = d
                    break
                d += step
        if zhat < dunk:
            e = (z - zhat - offset) / sigma
            total += math.log(p_rand + (1.0 - p_rand) * math.exp(-0.5 * e * e))
        elif dunk < np.inf:
            total += l_unknown
        else:
            total += math.log(p_rand)
    return total


def _sonar_cone_loglik_many(Ls, x0, y0, res, poses, sensors, ranges, half_cone,
                            max_range, n_rays, sigma, p_rand, occ, known,
                            l_unknown, offset, out):  # fmt: skip
    """`sonar_cone_loglik` of one ring reading in each map ``Ls[n]`` at ``poses[n]``."""
    for n in nb.prange(Ls.shape[0]):
        out[n] = sonar_cone_loglik(
            Ls[n], x0, y0, res, poses[n, 0], poses[n, 1], poses[n, 2], sensors,
            ranges, half_cone, max_range, n_rays, sigma, p_rand, occ, known,
            l_unknown, offset,
        )  # fmt: skip


sonar_cone_loglik_many, sonar_cone_loglik_many_parallel = serial_and_parallel(
    _sonar_cone_loglik_many
)
