"""Tests of robotlib.world (World, grids, free space) and robotlib.world.geometry,
and of the worlds shipped in worlds/."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robotlib.world import World, load_world, world_names
from robotlib.world.geometry import compose, relative, wrap_angle

RES = 0.1  # coarse grids keep these tests fast


# --------------------------------------------------------------------------
# plain NumPy references


def ref_distance(xy, segments):
    """Distance from each point (K, 2) to the nearest segment (M, 4), in NumPy."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    seg = np.asarray(segments, dtype=float).reshape(-1, 4)
    if len(seg) == 0:
        return np.full(len(xy), np.inf)
    p = xy[:, None, :]
    a, b = seg[None, :, :2], seg[None, :, 2:]
    ab = b - a
    len2 = np.sum(ab * ab, axis=-1)
    t = np.where(
        len2 > 0, np.sum((p - a) * ab, axis=-1) / np.where(len2 > 0, len2, 1), 0
    )
    t = np.clip(t, 0.0, 1.0)
    closest = a + t[..., None] * ab
    return np.sqrt(np.sum((closest - p) ** 2, axis=-1)).min(axis=1)


def ref_is_free(world, xy, radius):
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    xmin, ymin, xmax, ymax = world.bounds
    inside = (
        (xy[:, 0] - radius >= xmin)
        & (xy[:, 0] + radius <= xmax)
        & (xy[:, 1] - radius >= ymin)
        & (xy[:, 1] + radius <= ymax)
    )
    return inside & (ref_distance(xy, world.obstacles) > radius)


def ref_flood(free, i0, j0):
    """4-connected component of ``free`` containing (i0, j0), by BFS."""
    out = np.zeros_like(free, dtype=bool)
    if not free[i0, j0]:
        return out
    todo = [(i0, j0)]
    out[i0, j0] = True
    while todo:
        i, j = todo.pop()
        for a, b in ((i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1)):
            if 0 <= a < free.shape[0] and 0 <= b < free.shape[1]:
                if free[a, b] and not out[a, b]:
                    out[a, b] = True
                    todo.append((a, b))
    return out


def room_world():
    """A closed 4 m x 3 m room inside larger bounds, with a pillar and a point."""
    walls = [
        [0, 0, 4, 0],
        [4, 0, 4, 3],
        [4, 3, 0, 3],
        [0, 3, 0, 0],
        [2.0, 1.2, 2.4, 1.6],  # a diagonal pillar
    ]
    return World(walls, bounds=(-2, -2, 6, 5), start=(1, 1, 0), points=[[3.0, 2.5]])


# --------------------------------------------------------------------------
# World basics


def test_world_validates_and_freezes():
    w = room_world()
    assert not w.segments.flags.writeable
    with pytest.raises(ValueError):
        World([[0, 0, 1]])
    with pytest.raises(ValueError):
        World([[0, 0, 1, np.nan]])
    with pytest.raises(ValueError):
        World([[0, 0, 1, 1]], bounds=(1, 0, 0, 1))
    assert World([[0, 0, 1, 1]]) == World([[0, 0, 1, 1]])
    assert World([[0, 0, 1, 1]]) != World([[0, 0, 1, 2]])


def test_default_bounds_and_start():
    w = World([[0, 0, 2, 1]])
    assert w.bounds == (-0.5, -0.5, 2.5, 1.5)
    assert w.start == (1.0, 0.5, 0.0)


def test_obstacles_include_point_crosses():
    w = room_world()
    assert len(w.obstacles) == len(w.segments) + 2
    assert w.distance_to_walls([3.0, 2.5]) == pytest.approx(0.0)


def test_distance_to_walls_matches_reference():
    rng = np.random.default_rng(0)
    w = room_world()
    xy = rng.uniform([-2, -2], [6, 5], size=(500, 2))
    np.testing.assert_allclose(
        w.distance_to_walls(xy), ref_distance(xy, w.obstacles), rtol=0, atol=1e-12
    )
    assert w.distance_to_walls(xy.reshape(50, 10, 2)).shape == (50, 10)


@pytest.mark.parametrize("radius", [0.0, 0.1, 0.25, 0.6])
def test_is_free_matches_reference(radius):
    rng = np.random.default_rng(1)
    w = room_world()
    xy = rng.uniform([-2.5, -2.5], [6.5, 5.5], size=(2000, 2))
    # leave out points within a hair of the threshold, where rounding may differ
    d = ref_distance(xy, w.obstacles)
    xy = xy[np.abs(d - radius) > 1e-9]
    got = w.is_free(xy, radius)
    np.testing.assert_array_equal(got, ref_is_free(w, xy, radius))
    assert got.any() and not got.all()


def test_is_free_examples():
    w = room_world()
    assert w.is_free((1.0, 1.0))
    assert not w.is_free((0.2, 1.0))  # the disc touches the west wall
    assert w.is_free((0.3, 1.0))
    assert not w.is_free((-1.9, 0.0))  # the disc leaves the bounds
    assert not w.is_free((3.0, 2.5), radius=0.0)  # on the point obstacle


def test_distance_field_matches_reference_at_cells():
    w = room_world()
    grid = w.distance_field(RES)
    ny, nx = grid.shape
    assert (ny, nx) == (70, 80)
    assert grid.origin == (-2.0, -2.0)
    for i, j in [(0, 0), (20, 20), (35, 41), (69, 79), (45, 44), (21, 60)]:
        centre = (-2.0 + (j + 0.5) * RES, -2.0 + (i + 0.5) * RES)
        assert grid.data[i, j] == pytest.approx(ref_distance([centre], w.obstacles)[0])
    assert w.distance_field(RES) is grid  # cached


def test_grid_cell_of_and_extent():
    grid = room_world().distance_field(RES)
    assert grid.extent == pytest.approx((-2.0, 6.0, -2.0, 5.0))
    i, j = grid.cell_of(np.array([[-1.95, -1.95], [0.05, 1.05]]))
    np.testing.assert_array_equal(i, [0, 30])
    np.testing.assert_array_equal(j, [0, 20])


def _crossed_cells(occ, seg, n=20001):
    """Cells the segment passes through, each with the length of its chord, m."""
    t = np.linspace(0, 1, n)[:, None]
    a, b = np.array(seg[:2]), np.array(seg[2:])
    i, j = occ.cell_of(a + t * (b - a))
    step = np.hypot(*(b - a)) / (n - 1)
    cells, counts = np.unique(np.column_stack([i, j]), axis=0, return_counts=True)
    return cells, counts * step


def _occupancy_checks(seg, res=RES):
    w = World([seg], bounds=(0, 0, 4, 3))
    occ = w.occupancy_grid(res)
    # every cell the segment runs through for more than a sliver is marked ...
    cells, chord = _crossed_cells(occ, seg)
    long = cells[chord > 0.3 * res]
    assert occ.data[long[:, 0], long[:, 1]].all()
    # ... and nothing far from it
    d = ref_distance(occ.centres().reshape(-1, 2), [seg]).reshape(occ.shape)
    assert not occ.data[d > 1.5 * res].any()
    return occ


def test_occupancy_grid_marks_cells_clipped_at_a_corner():
    seg = [0.33, 0.21, 3.61, 2.74]
    occ = World([seg], bounds=(0, 0, 4, 3)).occupancy_grid(RES)
    cells, _ = _crossed_cells(occ, seg)
    assert occ.data[cells[:, 0], cells[:, 1]].all()


def test_occupancy_grid_horizontal_wall():
    occ = _occupancy_checks([0.52, 1.23, 3.47, 1.23])
    rows = np.flatnonzero(occ.data.any(axis=1))
    np.testing.assert_array_equal(rows, [12])
    np.testing.assert_array_equal(np.flatnonzero(occ.data[12]), np.arange(5, 35))


def test_occupancy_grid_diagonal_wall():
    occ = _occupancy_checks([0.33, 0.21, 3.61, 2.74])
    # a marked cell in every column and every row the wall spans
    np.testing.assert_array_equal(
        np.flatnonzero(occ.data.any(axis=0)), np.arange(3, 37)
    )
    np.testing.assert_array_equal(
        np.flatnonzero(occ.data.any(axis=1)), np.arange(2, 28)
    )


def test_occupancy_grid_empty_world():
    occ = World(np.zeros((0, 4)), bounds=(0, 0, 1, 1)).occupancy_grid(RES)
    assert occ.shape == (10, 10) and not occ.data.any()


def test_free_space_is_the_room_reachable_from_the_start():
    w = room_world()
    free = w.free_space(RES)
    centres = free.centres()
    # connected to the start, and the same as a reference flood fill
    candidate = ref_is_free(w, centres.reshape(-1, 2), 0.25).reshape(free.shape)
    candidate &= w.distance_field(RES).data > 0.25
    i0, j0 = free.cell_of(np.array(w.start[:2]))
    np.testing.assert_array_equal(free.data, ref_flood(candidate, int(i0), int(j0)))
    # nothing outside the closed room, though there is free space out there
    x, y = centres[..., 0], centres[..., 1]
    outside = (x < 0) | (x > 4) | (y < 0) | (y > 3)
    assert candidate[outside].any()
    assert not free.data[outside].any()
    # the room's inside, away from the walls and the pillar, is admissible
    assert free.data[(x > 0.4) & (x < 1.6) & (y > 0.4) & (y < 2.6)].all()


def test_free_space_with_blocked_start_is_every_free_cell():
    w = World(room_world().segments, bounds=(-2, -2, 6, 5), start=(0.0, 1.0, 0.0))
    free = w.free_space(RES)
    candidate = w.is_free(free.centres(), 0.25) & (w.distance_field(RES).data > 0.25)
    np.testing.assert_array_equal(free.data, candidate)


def test_sample_free_poses_reproducible_and_in_the_room():
    w = room_world()
    a = w.sample_free_poses(500, rng=42, resolution=RES)
    b = w.sample_free_poses(500, rng=np.random.default_rng(42), resolution=RES)
    c = w.sample_free_poses(500, rng=43, resolution=RES)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    assert a.shape == (500, 3)
    assert np.all((a[:, 0] > 0) & (a[:, 0] < 4) & (a[:, 1] > 0) & (a[:, 1] < 3))
    assert np.all((a[:, 2] > -np.pi) & (a[:, 2] <= np.pi))
    # free up to the half-diagonal of a cell (what sampling within cells allows)
    assert w.is_free(a[:, :2], 0.25 - RES / math.sqrt(2)).all()
    # and uniform-ish: both halves of the room get poses
    assert 0.3 < np.mean(a[:, 0] < 2.0) < 0.7


def test_sample_free_poses_are_all_free():
    w = room_world()
    a = w.sample_free_poses(5000, rng=0, resolution=RES)
    assert w.is_free(a[:, :2], 0.25).all()


def test_sample_free_poses_without_free_space_raises():
    w = World([[0, 0, 1, 0]], bounds=(0, -0.1, 1, 0.1))
    with pytest.raises(ValueError, match="free space"):
        w.sample_free_poses(3, rng=0)


@pytest.mark.parametrize("shape", [(1, 1), (1, 9), (13, 17), (40, 3), (3, 70000)])
def test_free_cells_give_flatnonzero_at_the_ranks(shape):
    from robotlib.world.model import _free_cells, _nth_true

    rng = np.random.default_rng(shape[0] * 100 + shape[1])
    mask = rng.random(shape) < 0.4
    mask[shape[0] // 2] = False  # an empty row
    mask.flat[-1] = True  # and at least one True cell
    starts, cols = _free_cells(mask)
    assert cols.dtype == (np.uint16 if shape[1] <= 65536 else np.int64)
    assert not starts.flags.writeable and not cols.flags.writeable
    flat = np.flatnonzero(mask)
    for ranks in (
        rng.integers(0, len(flat), size=50),
        np.arange(len(flat))[::-1],
        np.zeros(0, dtype=np.int64),
    ):
        got = _nth_true(starts, cols, shape[1], ranks)
        assert got.dtype == np.int64
        np.testing.assert_array_equal(got, flat[ranks])


def test_sample_free_poses_draws_as_from_the_list_of_free_cells():
    """The same poses, bit for bit, as indexing the list of every free cell."""
    w = room_world()
    grid, rng = w.free_space(RES), np.random.default_rng(5)
    cells = np.flatnonzero(grid.data)
    want, todo = np.empty((700, 3)), np.arange(700)
    while len(todo):  # the redraws (the world stops after 20: never reached here)
        k = len(todo)
        i, j = np.divmod(cells[rng.integers(0, len(cells), size=k)], grid.shape[1])
        u = rng.random((k, 3))
        want[todo, 0] = grid.origin[0] + (j + u[:, 0]) * grid.resolution
        want[todo, 1] = grid.origin[1] + (i + u[:, 1]) * grid.resolution
        want[todo, 2] = np.pi - 2.0 * np.pi * u[:, 2]
        todo = todo[~w.is_free(want[todo, :2])]
    np.testing.assert_array_equal(w.sample_free_poses(700, rng=5, resolution=RES), want)


# --------------------------------------------------------------------------
# geometry

angles = st.floats(-50.0, 50.0, allow_nan=False)
coords = st.floats(-100.0, 100.0, allow_nan=False)
poses = st.tuples(coords, coords, angles)


@settings(max_examples=100, deadline=None)
@given(st.floats(-1e6, 1e6, allow_nan=False))
def test_wrap_angle_range_and_equivalence(theta):
    w = wrap_angle(theta)
    assert -math.pi < w <= math.pi
    assert math.isclose(math.sin(w), math.sin(theta), abs_tol=1e-9)
    assert math.isclose(math.cos(w), math.cos(theta), abs_tol=1e-9)
    wa = wrap_angle(np.array([theta, theta]))
    assert wa.shape == (2,)
    assert np.all((wa > -np.pi) & (wa <= np.pi))
    assert math.isclose(math.remainder(float(wa[0]) - w, 2 * math.pi), 0, abs_tol=1e-9)


def test_wrap_angle_edges():
    assert wrap_angle(math.pi) == math.pi
    assert wrap_angle(-math.pi) == math.pi
    assert wrap_angle(3 * math.pi) == pytest.approx(math.pi)
    np.testing.assert_array_equal(wrap_angle(np.array([-np.pi, np.pi])), [np.pi, np.pi])
    assert wrap_angle(0.5) == 0.5


@settings(max_examples=100, deadline=None)
@given(poses, poses)
def test_compose_relative_inverse(p, q):
    d = relative(p, q)
    back = compose(p, d)
    np.testing.assert_allclose(back[:2], q[:2], atol=1e-9)
    assert math.isclose(math.remainder(back[2] - q[2], 2 * math.pi), 0, abs_tol=1e-9)
    assert -math.pi < back[2] <= math.pi
    assert -math.pi < d[2] <= math.pi
    # relative(p, compose(p, d)) == d (up to wrapping)
    d2 = relative(p, compose(p, d))
    np.testing.assert_allclose(d2[:2], d[:2], atol=1e-9)
    # distances are frame-independent
    assert math.isclose(
        math.hypot(d[0], d[1]),
        math.hypot(q[0] - p[0], q[1] - p[1]),
        rel_tol=1e-12,
        abs_tol=1e-9,
    )


def test_compose_examples_and_broadcasting():
    np.testing.assert_allclose(
        compose([1, 2, math.pi / 2], [1, 0, 0]), [1, 3, math.pi / 2]
    )
    np.testing.assert_allclose(compose([0, 0, 0], [1, 2, 3]), [1, 2, 3])
    many = compose(np.zeros((5, 3)), [1.0, 0.0, 4.0])
    assert many.shape == (5, 3)
    assert np.all(many[:, 2] == pytest.approx(4.0 - 2 * math.pi))
    np.testing.assert_allclose(
        relative([1, 1, math.pi], [0, 1, math.pi]), [1, 0, 0], atol=1e-12
    )


# --------------------------------------------------------------------------
# the shipped worlds

SHIPPED = [
    "arena",
    "building",
    "corridor",
    "corridor2",
    "corridor_periodic",
    "maze",
    "office",
]


def test_world_names_lists_the_shipped_worlds():
    assert set(SHIPPED) <= set(world_names())


@pytest.fixture(scope="module", params=SHIPPED)
def shipped(request):
    return load_world(request.param)


def test_shipped_world_loads_with_free_start(shipped):
    w = shipped
    assert w.name in SHIPPED and w.source is not None
    assert len(w.segments) > 0
    assert w.is_free(w.start[:2])
    assert w.distance_to_walls(w.start[:2]) >= 0.6
    assert -math.pi < w.start[2] <= math.pi


def test_shipped_world_is_closed_and_reachable(shipped):
    w = shipped
    # the interior: where a small disc (larger than half a cell, so it cannot
    # slip between the cells either side of a wall) gets from the start
    interior = w.free_space(RES, radius=0.06).data
    edge = interior[0].any() or interior[-1].any() or interior[:, 0].any()
    assert not (edge or interior[:, -1].any()), "the walls leave a way out"
    # the robot reaches nearly all of the interior it fits in: no door too narrow
    roomy = interior & (w.distance_field(RES).data > 0.25)
    reach = w.free_space(RES).data
    assert (reach & ~roomy).sum() == 0
    assert reach.sum() >= 0.97 * roomy.sum()
    # and it is a fair part of the world
    assert reach.sum() * RES**2 > 0.2 * w.size[0] * w.size[1]


def _wall_samples(w, step=0.05):
    out = []
    for x1, y1, x2, y2 in w.segments:
        n = max(2, int(math.hypot(x2 - x1, y2 - y1) / step) + 1)
        t = np.linspace(0, 1, n)[:, None]
        out.append(np.array([x1, y1]) + t * np.array([x2 - x1, y2 - y1]))
    return np.concatenate(out)


@pytest.mark.parametrize("name", ["corridor", "corridor2", "corridor_periodic"])
def test_corridor_is_not_symmetric(name):
    w = load_world(name)
    pts = _wall_samples(w)
    b = w.bounds
    seg = w.segments
    centres = [
        ((b[0] + b[2]) / 2, (b[1] + b[3]) / 2),
        (
            (seg[:, [0, 2]].min() + seg[:, [0, 2]].max()) / 2,
            (seg[:, [1, 3]].min() + seg[:, [1, 3]].max()) / 2,
        ),
    ]
    for cx, cy in centres:
        for sx, sy in [(-1, -1), (-1, 1), (1, -1)]:  # 180 deg turn, two mirrors
            moved = np.column_stack(
                [cx + sx * (pts[:, 0] - cx), cy + sy * (pts[:, 1] - cy)]
            )
            off = ref_distance(moved, seg) > 0.2
            # metres of wall that land nowhere near a wall
            assert off.sum() * 0.05 > 2.0, (cx, cy, sx, sy)


@pytest.mark.parametrize(
    "name, middle", [("corridor", 10.1), ("corridor_periodic", 4.5)]
)
def test_corridor_shape_and_aliasing(name, middle):
    w = load_world(name)
    x, y, th = w.start
    assert th == 0.0
    # a ~2 m wide corridor along x: clear 0.9 m to either side, walls within 1.1 m
    assert 1.8 <= 2 * w.distance_to_walls([x, y]) <= 2.2
    # the robot can drive from the start to the far end
    free = w.free_space(RES)
    far = np.array([w.segments[:, [0, 2]].max() - 1.0, y])
    i, j = free.cell_of(far)
    assert free.data[i, j]
    assert far[0] - x >= 25.0
    # doors: along the corridor's centre line, the side walls open ~1 m at a time
    xs = np.arange(x, far[0], 0.02)
    for side in (-1.0, 1.0):
        probe = np.column_stack([xs, np.full_like(xs, y + side * 1.0)])
        gap = w.distance_to_walls(probe) > 0.3
        starts = np.flatnonzero(np.diff(gap.astype(int)) == 1)
        assert len(starts) >= 5  # several doors on each side
    # aliasing: in the periodic part, a pose one door period (4 m) along sees
    # the same walls around it
    a = np.array([x + middle, y])
    b = a + [4.0, 0.0]
    ring = np.column_stack(
        [
            np.cos(np.linspace(0, 2 * np.pi, 16, endpoint=False)),
            np.sin(np.linspace(0, 2 * np.pi, 16, endpoint=False)),
        ]
    )
    for r in (0.8, 1.2, 2.0):
        np.testing.assert_allclose(
            w.distance_to_walls(b + r * ring),
            w.distance_to_walls(a + r * ring),
            atol=1e-9,
        )


def _drive_east_mismatch(w, steps):
    """How well the best other straight drive explains the start's first scans.

    Noise-free scans every 0.5 m along the centre line from the start, heading
    east, against the same drive from every other start 5 cm apart on the
    centre line, heading east (at least 1 m away) or west. Returns, per scan
    count ``k`` (1..steps), the smallest summed mean |dz| (m) of the first
    ``k`` scans over all those other drives.
    """
    from robotlib.sensing import expected_ranges

    x0, y0, _ = w.start
    k = np.arange(steps) * 0.5
    truth = expected_ranges(w, np.column_stack([x0 + k, np.full(steps, y0), 0 * k]))
    best = np.full(steps, np.inf)
    xmax = w.segments[:, [0, 2]].max()
    for heading, sign in ((0.0, 1.0), (math.pi, -1.0)):
        starts = np.arange(w.segments[:, [0, 2]].min() + 0.3, xmax - 0.3, 0.05)
        if heading == 0.0:
            starts = starts[np.abs(starts - x0) >= 1.0]
        xs = starts[:, None] + sign * k[None, :]
        poses = np.column_stack(
            [xs.ravel(), np.full(xs.size, y0), np.full(xs.size, heading)]
        )
        z = expected_ranges(w, poses).reshape(len(starts), steps, -1)
        d = np.abs(z - truth[None]).mean(axis=2)
        d[(xs < w.segments[:, [0, 2]].min() + 0.3) | (xs > xmax - 0.3)] = 5.0
        best = np.minimum(best, np.cumsum(d, axis=1).min(axis=0))
    return best


def test_corridor_start_is_unique_and_periodic_one_is_not():
    """Corridor: the first scan is aliased, the first ~8 m of scans are not."""
    new = _drive_east_mismatch(load_world("corridor"), 17)
    assert new[0] < 0.05  # one scan near the west end looks like another place
    assert new[-1] > 1.0  # 17 scans (8 m) fit no other drive, either way round
    old = _drive_east_mismatch(load_world("corridor_periodic"), 12)
    assert old[-1] < 0.05  # the periodic corridor: 5.5 m on, still ambiguous


def test_corridor2_bends():
    w = load_world("corridor2")
    free = w.free_space(RES)
    top = np.array([18.9, 13.0])  # the end of the L's northern leg
    i, j = free.cell_of(top)
    assert free.data[i, j]


def test_office_map_has_points_and_box():
    w = load_world("office")
    assert len(w.points) > 10
    assert w.size == pytest.approx((21.0, 16.0))
    free = w.free_space(RES)
    i, j = free.cell_of(np.array([[7.5, 3.0], [7.5, 1.5]]))
    assert not free.data[i[0], j[0]]  # inside the Sim.BoxObstacle
    assert free.data[i[1], j[1]]  # beside it, in the same room
