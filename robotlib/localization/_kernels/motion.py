"""Motion sampling: particles moved by an odometry increment plus drawn noise.

Numba kernels: contiguous arrays and scalars in, no Python objects; they
import nothing of robotlib but the JIT options and other kernels.
"""

import numba as nb

from ..._config import JIT, serial_and_parallel
from .common import wrap
from .elementary import sincos


@nb.njit(**JIT, inline="always")
def odometry_pose(x, y, th, n1, nt, n2, rot1, trans, rot2, sd1, sdt, sd2):
    """Move the pose ``(x, y, th)`` by ``rot1, trans, rot2`` plus noise.

    Each increment gets its standard deviation (``sd1, sdt, sd2``) times its
    standard normal (``n1, nt, n2``). Returns the new ``(x, y, th)``.
    """
    r1 = rot1 + sd1 * n1
    t = trans + sdt * nt
    r2 = rot2 + sd2 * n2
    s, c = sincos(th + r1)
    return x + t * c, y + t * s, wrap(th + r1 + r2)


@nb.njit(**JIT, inline="always")
def _odometry_one(j, particles, rot1, trans, rot2, sd1, sdt, sd2, normals, out):
    x, y, th = odometry_pose(
        particles[j, 0], particles[j, 1], particles[j, 2], normals[j, 0],
        normals[j, 1], normals[j, 2], rot1, trans, rot2, sd1, sdt, sd2,
    )  # fmt: skip
    out[j, 0] = x
    out[j, 1] = y
    out[j, 2] = th
    return x, y, th


def _sample_odometry(particles, rot1, trans, rot2, sd1, sdt, sd2, normals, out):
    """Move particles (N, 3) by ``rot1, trans, rot2`` plus noise into ``out``.

    Each increment gets its standard deviation (``sd1, sdt, sd2``) times the
    caller's standard normals ``normals`` (N, 3).
    """
    for j in nb.prange(particles.shape[0]):
        _odometry_one(j, particles, rot1, trans, rot2, sd1, sdt, sd2, normals, out)


sample_odometry, sample_odometry_parallel = serial_and_parallel(_sample_odometry)
