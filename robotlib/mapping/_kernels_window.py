"""Numba kernels for the sonar's windowed weighing in grid FastSLAM.

Eight wide cones per record say little about a pose; the last ``K`` records
together say more. Each particle keeps its last ``K`` poses (a window, not
yet in its map) and is weighed by the window's records in the map of the
records before them, so a reading is not scored against its own echoes.
Grids as in `robotlib.mapping._kernels`. Imports nothing of robotlib's but
the JIT config and the sibling kernels.
"""

import numba as nb

from .._config import serial_and_parallel
from ._kernels import sonar_beam_loglik


def _window_loglik_many(Ls, x0, y0, res, wins, sensors, scans, half_cone,
                        max_range, n_rays, sigma, p_rand, occ, c_unknown,
                        out, centre=False):  # fmt: skip
    """Sum over a window's records of `sonar_beam_loglik` in each map: ``out[n]``."""
    for n in nb.prange(Ls.shape[0]):
        total = 0.0
        for k in range(wins.shape[1]):
            total += sonar_beam_loglik(
                Ls[n], x0, y0, res, wins[n, k, 0], wins[n, k, 1], wins[n, k, 2],
                sensors, scans[k], half_cone, max_range, n_rays, sigma, p_rand,
                occ, c_unknown, centre,
            )  # fmt: skip
        out[n] = total


window_loglik_many, window_loglik_many_parallel = serial_and_parallel(
    _window_loglik_many
)
