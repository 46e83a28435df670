"""The grid caster against a plain Python walk of the same steps: the same bits.

`robotlib.sensing._kernels.cast_grid` advances all rays of a pose together,
with its scratch packed per ray and the boundary step selected without a
branch; the reference below walks one ray at a time with the documented
rule (jump the cell's clearance, or to the next cell boundary where it is
under one cell; stop in an occupied cell or past the range), in Python
floats, which are the same IEEE doubles.
"""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robotlib.sensing import cast_rays_grid, grid_field
from robotlib.world import Grid, load_world


def _walk(field, x0, y0, resolution, pose, ca, sa, max_range):
    """One pose's ranges, ray by ray, as `_cast_grid_pose` documents them."""
    gx = (pose[0] - x0) / resolution + 1.0
    gy = (pose[1] - y0) / resolution + 1.0
    out = np.zeros(len(ca))
    if not (1.0 <= gx < field.shape[1] - 1 and 1.0 <= gy < field.shape[0] - 1):
        return out
    limit = max_range / resolution
    c0, s0 = math.cos(pose[2]), math.sin(pose[2])
    for r in range(len(ca)):
        dx = c0 * ca[r] - s0 * sa[r]
        dy = s0 * ca[r] + c0 * sa[r]
        inv_dx = 1.0 / dx if dx != 0.0 else math.inf
        inv_dy = 1.0 / dy if dy != 0.0 else math.inf
        t = 0.0
        while True:
            px, py = gx + t * dx, gy + t * dy
            j, i = int(px), int(py)
            c = float(field[i, j])
            if c < 0.0:
                out[r] = t * resolution
                break
            if c < 1.0:
                bx = (j + (1.0 if dx >= 0 else 0.0) - px) * inv_dx
                by = (i + (1.0 if dy >= 0 else 0.0) - py) * inv_dy
                c = min(bx, by) + 1e-9
            t += c
            if t >= limit:
                out[r] = max_range
                break
    return out


def _reference(grid, poses, angles, max_range):
    field = grid_field(grid)
    ca, sa = np.cos(angles), np.sin(angles)
    x0, y0 = grid.origin
    return np.array(
        [_walk(field, x0, y0, grid.resolution, p, ca, sa, max_range) for p in poses]
    )


@pytest.mark.slow
def test_grid_caster_equals_the_walk_in_the_office():
    world = load_world("office")
    grid = world.occupancy_grid(0.05)
    poses = world.sample_free_poses(30, rng=3)
    poses[::7, :2] = np.round(poses[::7, :2] / 0.05) * 0.05  # on cell corners
    angles = np.linspace(-math.pi, math.pi, 64, endpoint=False)  # axis-aligned too
    got = cast_rays_grid(grid, poses, angles, 5.0)
    np.testing.assert_array_equal(got, _reference(grid, poses, angles, 5.0))


@settings(max_examples=40, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(3, 40),
    st.integers(3, 40),
    st.floats(0.0, 0.4),
    st.sampled_from([0.05, 0.1, 0.37]),
    st.integers(1, 70),
)
def test_grid_caster_equals_the_walk_on_random_grids(seed, ny, nx, fill, res, n_rays):
    """Random grids, resolutions, poses (inside, in walls, outside) and fans."""
    rng = np.random.default_rng(seed)
    grid = Grid(rng.random((ny, nx)) < fill, (-1.0, 0.5), res)
    poses = np.column_stack(
        [rng.uniform(-1.5, -0.5 + nx * res, 12), rng.uniform(0.0, 1.0 + ny * res, 12),
         rng.uniform(-7, 7, 12)]
    )  # fmt: skip
    angles = rng.uniform(-math.pi, math.pi, n_rays)
    angles[: n_rays // 3] = np.round(angles[: n_rays // 3] / (math.pi / 2)) * (
        math.pi / 2
    )  # along the axes
    max_range = float(rng.uniform(0.1, 3.0))
    got = cast_rays_grid(grid, poses, angles, max_range)
    np.testing.assert_array_equal(got, _reference(grid, poses, angles, max_range))
