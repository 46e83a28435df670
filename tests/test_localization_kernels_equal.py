"""Rewritten kernels against the ones they replace: the same numbers, bit for bit."""

import math

import numba as nb
import numpy as np
import pytest

from robotlib.localization._kernels.exact import cone_echo_rays
from robotlib.localization._kernels.fused import _flat_index
from robotlib.localization._kernels.tables import table_bin
from robotlib.sensing import SonarModel
from robotlib.sensing._kernels import cone_echo


@nb.njit
def _echoes_both(cones, walls, counts, n_rays, cone, max_range, cos_specular):
    out = np.empty((cones.shape[0], 2))
    ray = np.empty((4, max(n_rays, 1)))
    for k in range(cones.shape[0]):
        w = walls[k, : counts[k]]
        sx, sy, sth = cones[k, 0], cones[k, 1], cones[k, 2]
        out[k, 0] = cone_echo(sx, sy, sth, w, n_rays, cone, max_range, cos_specular)
        out[k, 1] = cone_echo_rays(
            sx, sy, sth, walls[k], counts[k], n_rays, cone, max_range, cos_specular,
            ray,
        )  # fmt: skip
    return out


@pytest.mark.parametrize("n_rays", [1, 2, 7, 9])
def test_cone_echo_rays_equals_cone_echo(n_rays):
    """Random walls, repeated walls, walls through the apex, parallel walls."""
    rng = np.random.default_rng(n_rays)
    k, m = 4000, 10
    cones = np.column_stack(
        [rng.uniform(-1, 1, k), rng.uniform(-1, 1, k), rng.uniform(-4, 4, k)]
    )
    walls = rng.uniform(-3, 3, (k, m, 4))
    walls[::5, 1] = walls[::5, 0]  # the same wall twice: the first one wins
    walls[::7, 2, :2] = cones[::7, :2]  # a wall starting at the apex
    walls[::11, 3] = [-2.0, 0.5, 2.0, 0.5]  # axis-parallel walls
    walls[::11, 4] = [0.5, -2.0, 0.5, 2.0]
    walls[::13, 5] = np.round(walls[::13, 5])  # whole-number end points
    counts = rng.integers(0, m + 1, k)
    sonar = SonarModel()
    out = _echoes_both(
        cones, walls, counts, n_rays, sonar.cone, sonar.max_range, sonar.cos_specular
    )
    assert np.isfinite(out[:, 0]).sum() > 100  # echoes were found
    np.testing.assert_array_equal(out[:, 0], out[:, 1])


@nb.njit
def _indexes_both(poses, sensors, ny, nx, n_bins, x0, y0, inv_res):
    out = np.empty((poses.shape[0], sensors.shape[0], 2), dtype=np.int64)
    bins = n_bins / (2.0 * math.pi)
    for j in range(poses.shape[0]):
        x, y, th = poses[j, 0], poses[j, 1], poses[j, 2]
        c = math.cos(th)
        s = math.sin(th)
        for i in range(sensors.shape[0]):
            row, col, b = table_bin(x, y, th, c, s, sensors, i, ny, nx, n_bins, x0, y0,
                                    inv_res)  # fmt: skip
            out[j, i, 0] = (row * nx + col) * n_bins + b
            out[j, i, 1] = _flat_index(
                x + c * sensors[i, 0] - s * sensors[i, 1],
                y + s * sensors[i, 0] + c * sensors[i, 1],
                (th + sensors[i, 2]) * bins, ny, nx, n_bins, x0, y0, inv_res,
            )  # fmt: skip
    return out


def test_flat_index_equals_table_bin():
    """Inside, outside and on the edges of the grid, headings over several turns."""
    rng = np.random.default_rng(0)
    n = 20000
    poses = np.column_stack(
        [rng.uniform(-3, 12, n), rng.uniform(-3, 9, n), rng.uniform(-7, 13, n)]
    )
    poses[::9, :2] = np.round(poses[::9, :2] * 20) / 20  # on cell boundaries
    poses[::17, 2] = np.round(poses[::17, 2] / (2 * np.pi / 72)) * (2 * np.pi / 72)
    sensors = SonarModel().sensors
    out = _indexes_both(poses, sensors, 120, 180, 72, 0.0, 0.0, 20.0)
    np.testing.assert_array_equal(out[..., 0], out[..., 1])
