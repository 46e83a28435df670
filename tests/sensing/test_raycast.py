import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from robotlib import load_world
from robotlib.sensing import cast_rays, cast_rays_grid
from robotlib.world import World
from tests import naive

BOX = World([[0, 0, 4, 0], [4, 0, 4, 3], [4, 3, 0, 3], [0, 3, 0, 0]], start=(1, 1, 0))


def test_rays_in_a_box_hit_the_walls_at_known_ranges():
    r = cast_rays(BOX, [1.0, 1.0, 0.0], [0.0, math.pi / 2, math.pi, -math.pi / 2])
    np.testing.assert_allclose(r[0], [3.0, 2.0, 1.0, 1.0])
    diag = cast_rays(BOX, [1.0, 1.0, 0.0], [math.atan2(2.0, 3.0)])
    assert diag[0, 0] == pytest.approx(math.hypot(3.0, 2.0))


def test_rays_that_hit_nothing_report_max_range():
    open_world = World([[10, 10, 11, 10]], bounds=(-20, -20, 20, 20))
    np.testing.assert_array_equal(
        cast_rays(open_world, [0, 0, 0], [0.0, 1.0], 5.0), 5.0
    )


def test_segment_caster_matches_numpy_reference_in_the_corridor():
    world = load_world("corridor")
    rng = np.random.default_rng(3)
    poses = world.sample_free_poses(40, rng)
    angles = np.linspace(-math.pi, math.pi, 17)
    fast = cast_rays(world, poses, angles, 5.0)
    ref = naive.cast_rays(world.obstacles, poses, angles, 5.0)
    np.testing.assert_allclose(fast, ref, rtol=0, atol=1e-9)


segments = st.lists(
    st.tuples(*[st.floats(-5, 5, allow_nan=False) for _ in range(4)]).filter(
        lambda s: math.hypot(s[2] - s[0], s[3] - s[1]) > 1e-3
    ),
    min_size=1,
    max_size=8,
)


@settings(max_examples=60, deadline=None)
@given(
    segments,
    st.tuples(st.floats(-4, 4), st.floats(-4, 4), st.floats(-math.pi, math.pi)),
)
def test_segment_caster_matches_reference_on_random_geometry(segs, pose):
    segs = np.array(segs)
    pose = np.array(pose)
    assume(World(segs, bounds=(-9, -9, 9, 9)).distance_to_walls(pose[:2]) > 1e-3)
    angles = np.linspace(-3, 3, 7)
    fast = cast_rays(segs, pose, angles, 6.0)
    ref = naive.cast_rays(segs, np.array([pose]), angles, 6.0)
    # A ray through a segment's very end point may go either way.
    ends = np.concatenate([segs[:, :2], segs[:, 2:]]) - pose[:2]
    for r, a in enumerate(pose[2] + angles):
        d = np.array([math.cos(a), math.sin(a)])
        through_end = np.abs(ends[:, 0] * d[1] - ends[:, 1] * d[0]) < 1e-6
        if not through_end.any():
            assert fast[0, r] == pytest.approx(ref[0, r], abs=1e-7)
    assert np.all((fast >= 0) & (fast <= 6.0))


@pytest.mark.slow
def test_grid_caster_matches_marching_reference():
    world = load_world("office")
    grid = world.occupancy_grid(0.05)
    rng = np.random.default_rng(7)
    poses = world.sample_free_poses(25, rng)
    angles = np.linspace(-math.pi, math.pi, 13)
    fast = cast_rays_grid(grid, poses, angles, 5.0)
    step = 0.002
    for k, pose in enumerate(poses):
        for r, a in enumerate(angles):
            ref = naive.cast_ray_grid_marching(
                grid.data, grid.origin, grid.resolution, pose, a, 5.0, step
            )
            assert fast[k, r] == pytest.approx(ref, abs=step + 1e-9)


def test_grid_ranges_are_within_a_cell_of_the_exact_ranges():
    world = load_world("maze")
    grid = world.occupancy_grid(0.02)
    poses = world.sample_free_poses(30, rng=11)
    angles = np.linspace(-math.pi, math.pi, 24, endpoint=False)
    exact = cast_rays(world, poses, angles, 5.0)
    coarse = cast_rays_grid(grid, poses, angles, 5.0)
    # A wall's cells start before the wall itself: never a longer range, and
    # typically within a cell or so (rays that graze a wall fall short by more).
    assert np.all(coarse <= exact + 1e-9)
    assert np.median(exact - coarse) <= 1.5 * grid.resolution


def test_grid_caster_from_an_occupied_cell_or_outside_is_zero():
    grid = BOX.occupancy_grid(0.1)
    r = cast_rays_grid(grid, [[0.01, 0.01, 0.0], [-1.0, 1.0, 0.0]], [0.0])
    np.testing.assert_array_equal(r, 0.0)


def test_bad_shapes_are_rejected():
    with pytest.raises(ValueError, match="poses"):
        cast_rays(BOX, [1.0, 2.0], [0.0])
    with pytest.raises(ValueError, match="segments"):
        cast_rays(np.zeros((2, 3)), [0, 0, 0], [0.0])


def test_grid_field_is_the_centre_distance_transform_less_a_diagonal():
    from robotlib.sensing import grid_field
    from robotlib.world import Grid

    occ = np.random.default_rng(1).random((23, 31)) < 0.05
    field = grid_field(Grid(occ, (0.0, 0.0), 1.0))
    padded = np.pad(occ, 1, constant_values=True)
    np.testing.assert_array_equal(field < 0, padded)
    # Brute force: distances between centres to occupied (or border) cells.
    ii, jj = np.nonzero(padded)
    for i, j in zip(*np.nonzero(~padded), strict=True):
        d = np.sqrt((ii - i) ** 2 + (jj - j) ** 2).min()
        assert field[i, j] == pytest.approx(max(d - math.sqrt(2), 0.0))
