"""Per-particle pieces the localization kernels are built from.

Each piece handles one particle (or one of its sensors) and is inlined
into the kernels that loop over particles, so a kernel reads as the
textbook's loop: move the particle, look up what each sensor should read,
score the reading. Units: metres and radians; cone tables hold millimetres.
"""

import math

import numba as nb

from ..._config import JIT

TWO_PI = 2.0 * math.pi


@nb.njit(**JIT, inline="always")
def wrap(a):
    """Wrap an angle to (-pi, pi]."""
    w = a - TWO_PI * math.floor((a + math.pi) / TWO_PI)
    if w <= -math.pi:
        w += TWO_PI
    elif w > math.pi:
        w -= TWO_PI
    return w


@nb.njit(**JIT, inline="always")
def move(x, y, th, rot1, trans, rot2, sd1, sd2, sd3, n1, n2, n3):
    """Move one pose by an odometry increment with noise (Thrun, table 5.6).

    ``rot1, trans, rot2`` is the increment (rad, m, rad), ``sd1..sd3`` the
    standard deviations of its noise and ``n1..n3`` standard normal draws.
    Returns the new ``(x, y, theta)``.
    """
    r1 = rot1 + sd1 * n1
    t = trans + sd2 * n2
    r2 = rot2 + sd3 * n3
    a = th + r1
    return x + t * math.cos(a), y + t * math.sin(a), wrap(a + r2)


@nb.njit(**JIT, inline="always")
def sensor_pose(x, y, th, c, s, sensors, i):
    """Return the world pose ``(x, y, heading)`` of sensor ``i`` on pose x, y, th.

    ``sensors`` (S, 3) holds the sensors' poses in the robot's frame; ``c``
    and ``s`` are the cosine and sine of ``th``, computed once per pose.
    """
    return (
        x + c * sensors[i, 0] - s * sensors[i, 1],
        y + s * sensors[i, 0] + c * sensors[i, 1],
        th + sensors[i, 2],
    )


@nb.njit(**JIT, inline="always")
def table_mm(table, x0, y0, inv_res, sx, sy, sth):
    """Return the cone table's entry (mm) for a sensor at ``(sx, sy)`` along ``sth``.

    ``table`` (ny, nx, n_bins) holds ranges from each cell's centre; the
    sensor's position selects the cell (clamped to the grid), its heading
    the nearest of the ``n_bins`` directions ``b * 2 pi / n_bins``.
    """
    ny, nx, n_bins = table.shape
    col = min(max(int(math.floor((sx - x0) * inv_res)), 0), nx - 1)
    row = min(max(int(math.floor((sy - y0) * inv_res)), 0), ny - 1)
    b = int(math.floor(sth * (n_bins / TWO_PI) + 0.5)) % n_bins
    return table[row, col, b]
