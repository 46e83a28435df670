"""The cone table against plain references: its builder, its lookup, its disk cache.

The builder must give, bit for bit, what `tests.naive_mcl.cone_table_cell`
(every ray against every wall, in NumPy) gives at each cell's centre. The
map that matters most is MobileSim-like: DATA points on a 20 mm grid (each a
small cross of two segments) under cells whose centres sit 25 mm off that
grid, so rays along multiples of 45 degrees pass exactly through the
crosses' end points, where a few ulps change a reading by decimetres.
"""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robotlib.experiments import bench_large_map
from robotlib.experiments.bench_mcl import square_world
from robotlib.localization import ConeTable, cone_table, cones, expected_readings
from robotlib.localization._kernels import cone_table as kernels
from robotlib.sensing import SonarModel, expected_ranges
from robotlib.world import World, load_world
from tests import naive_mcl as naive


@pytest.fixture(autouse=True)
def no_disk_cache(monkeypatch):
    """No test reads or writes a cone table on disk unless it says where."""
    monkeypatch.setenv("ROBOTLIB_TABLE_CACHE", "off")


def reference(world, table, cells=None):
    """`naive_mcl.cone_table_cell` for the table's cells (all, or ``cells``)."""
    ny, nx, n_bins = table.table.shape
    s = table.sonar
    offsets = cones.ray_offsets(s, n_bins)
    cells = np.ndindex(ny, nx) if cells is None else cells
    out = {}
    for i, j in cells:
        cx = table.origin[0] + (j + 0.5) * table.resolution
        cy = table.origin[1] + (i + 0.5) * table.resolution
        out[i, j] = naive.cone_table_cell(
            world.sensed_obstacles, cx, cy, n_bins, offsets, s.max_range, s.min_range,
            s.cos_specular,
        )  # fmt: skip
    return out


def assert_matches(world, table, cells=None):
    ref = reference(world, table, cells)
    got = {ij: table.table[ij] for ij in ref}
    bad = [ij for ij in ref if not np.array_equal(got[ij], ref[ij])]
    assert not bad, (bad[:5], got[bad[0]], ref[bad[0]])


def point_grid_map(x0=-4780, y0=-2700, side=3000, step=20) -> str:
    """A 3 m room of DATA points every 20 mm, an inner wall, columbia's origin."""
    pts = set()
    for k in range(0, side + 1, step):
        pts |= {(x0 + k, y0), (x0 + k, y0 + side), (x0, y0 + k), (x0 + side, y0 + k)}
    for k in range(0, 1200, step):
        pts.add((x0 + 1500, y0 + 900 + k))
    lines = ["2D-Map", f"MinPos: {x0} {y0}", f"MaxPos: {x0 + side} {y0 + side}"]
    lines += [f"NumPoints: {len(pts)}", "Resolution: 20", "DATA"]
    lines += [f"{x} {y}" for x, y in sorted(pts)]
    return "\n".join(lines) + "\n"


@pytest.fixture(scope="module")
def grid_map(tmp_path_factory):
    path = tmp_path_factory.mktemp("maps") / "grid.map"
    path.write_text(point_grid_map(), encoding="ascii")
    return path


@pytest.mark.slow
def test_the_point_grid_table_equals_every_ray_against_every_wall(grid_map):
    world = load_world(grid_map)
    table = ConeTable(world)
    ny, nx, _ = table.table.shape
    rng = np.random.default_rng(1)
    diagonal = [(k, k) for k in range(0, min(ny, nx), 3)]  # rays through crosses
    cells = diagonal + [tuple(c) for c in rng.integers(0, (ny, nx), (150, 2))]
    assert_matches(world, table, cells)


def test_the_point_grid_tells_a_cells_last_bits_apart(grid_map):
    """Centres a few ulps off the table's (another sum) read otherwise here."""
    world = load_world(grid_map)
    table = ConeTable(world)
    s, (x0, y0), res = table.sonar, table.origin, table.resolution
    offsets = cones.ray_offsets(s, 72)
    differ = 0
    for k in range(0, 60, 3):
        cx, cy = x0 + k * res + 0.5 * res, y0 + k * res + 0.5 * res
        ref = naive.cone_table_cell(
            world.sensed_obstacles, cx, cy, 72, offsets, s.max_range, s.min_range,
            s.cos_specular,
        )  # fmt: skip
        differ += np.count_nonzero(ref != table.table[k, k])
    assert differ > 0


@pytest.mark.slow
def test_bench_large_map_checks_every_sampled_cell_of_the_point_grid(grid_map):
    r = bench_large_map.bench_maps(grid_map, resolution=0.05, sample=400)
    assert r["reference_entries"] == 400 * 72
    assert r["table_matches_reference"], r
    assert r["reference_differing"] == 0


def test_bench_large_map_refuses_a_missing_map_clearly(tmp_path, capsys):
    args = type("Args", (), {"map": str(tmp_path / "missing.map")})()
    args.resolution, args.sample = 0.05, 40
    assert bench_large_map.run(args) == 2
    err = capsys.readouterr().err
    assert "missing.map" in err and "Traceback" not in err


def random_walls(seed, n=60):
    """Random walls: short, long, zero-length, through cell centres, repeated."""
    rng = np.random.default_rng(seed)
    a = rng.uniform(0.0, 4.0, (n, 2))
    walls = np.column_stack([a, a + rng.normal(0.0, 0.8, (n, 2))])
    walls[:5, 2:] = walls[:5, :2]  # zero length
    walls[5:10] = np.round(walls[5:10] / 0.05) * 0.05 + 0.025  # ends on cell centres
    walls[10:13] = walls[20:23]  # the same wall twice: the lower index wins
    walls[13, :] = [0.025, 0.025, 3.975, 3.975]  # a diagonal through centres
    walls[14, :] = [1.0, 0.5, 1.0, 3.5]  # axis-aligned, as a map's points' crosses
    walls[15, :] = [0.5, 2.0, 3.5, 2.0]
    return walls


def near_parallel_walls(rng, n=24):
    """Walls within 1e-9 .. 1e-5 rad of a direction bin, through the grid."""
    b = rng.integers(0, 72, n)
    a = b * (2 * math.pi / 72) + rng.choice([-1, 1], n) * 10.0 ** rng.uniform(-9, -5, n)
    p = rng.uniform(0.5, 3.5, (n, 2))
    length = rng.uniform(0.3, 3.0, n)
    d = np.column_stack([np.cos(a), np.sin(a)])
    return np.column_stack([p, p + length[:, None] * d])


@pytest.mark.parametrize("seed", [0, 1])
def test_random_walls_with_nearly_parallel_ones_equal_the_reference(seed):
    rng = np.random.default_rng(seed + 10)
    walls = np.concatenate([random_walls(seed, 300), near_parallel_walls(rng)])
    world = World(walls, bounds=(0.0, 0.0, 4.0, 3.6))  # not square
    for n_rays in (1, 7):  # single rays; the Pioneer's cones
        table = ConeTable(world, SonarModel(max_range=3.0, n_rays=n_rays), 0.1)
        assert len(np.unique(table.table)) > 200  # many ranges, not a blank table
        assert_matches(world, table)


@pytest.mark.parametrize("n_bins", [9, 40])
def test_odd_bin_counts_work_alone_and_even_ones_pair_opposite_bins(n_bins):
    walls = np.concatenate([random_walls(3, 200), [[1.0, 0.2, 1.0, 3.8]]])
    world = World(walls, bounds=(0.0, 0.0, 4.0, 4.0))
    table = ConeTable(world, SonarModel(max_range=3.0, n_rays=3), 0.2, n_bins)
    assert_matches(world, table)


coordinate = st.one_of(
    st.integers(-4, 44).map(lambda k: k * 0.05),  # on cell edges and centres
    st.floats(-0.2, 2.2, allow_nan=False),
)


@settings(max_examples=60, deadline=None)  # the first example may compile
@given(
    walls=st.lists(st.tuples(*[coordinate] * 4), min_size=1, max_size=12),
    n_bins=st.sampled_from([8, 9, 36, 72]),
    n_rays=st.sampled_from([1, 3, 5, 7]),
    specular=st.sampled_from([None, 0.5, 1.2]),
    max_range=st.sampled_from([0.7, 5.0]),
)
def test_small_worlds_equal_the_reference(walls, n_bins, n_rays, specular, max_range):
    world = World(walls, bounds=(0.0, 0.0, 2.0, 1.6))
    sonar = SonarModel(
        n_rays=n_rays, specular_angle=specular, max_range=max_range, min_range=0.1
    )
    assert_matches(world, ConeTable(world, sonar, 0.2, n_bins))


def test_cones_off_the_bins_take_each_ray_to_its_nearest_bin():
    """5 rays over 30 degrees are 7.5 degrees apart: bins -3, -2, 0, 2, 3 of 5."""
    five = SonarModel(n_rays=5)
    assert cones.ray_offsets(five, 72).tolist() == [-3, -2, 0, 2, 3]
    assert cones.ray_offsets(SonarModel(), 72).tolist() == [-3, -2, -1, 0, 1, 2, 3]
    assert cones.ray_offsets(SonarModel(), 36).tolist() == [-2, -1, 0, 1, 2]
    assert cones.ray_offsets(SonarModel.single_ray(), 72).tolist() == [0]
    world = World(random_walls(4, 40), bounds=(0.0, 0.0, 4.0, 4.0))
    table = ConeTable(world, five, 0.25)
    assert_matches(world, table)
    # the Pioneer's cones on their bins: the table reads as the exact cast
    pioneer = ConeTable(world, SonarModel(), 0.25)
    centres = [
        (pioneer.origin[0] + (j + 0.5) * 0.25, pioneer.origin[1] + (i + 0.5) * 0.25)
        for i, j in [(3, 4), (8, 9), (12, 2)]
    ]
    poses = np.array([(x, y, b * 2 * math.pi / 72) for x, y in centres
                      for b in range(0, 72, 5)])  # fmt: skip
    one = SonarModel(sensors=[[0.0, 0.0, 0.0]])
    exact = expected_ranges(world.sensed_obstacles, poses, one)
    looked = ConeTable(world, one, 0.25).lookup(poses)
    np.testing.assert_allclose(looked, exact, atol=0.0006)


def test_lookup_equals_the_numpy_reference_serial_and_threaded():
    world = load_world("office")
    table = cone_table(world, resolution=0.1)
    rng = np.random.default_rng(2)
    x0, y0, x1, y1 = world.bounds
    n = 5000  # above PARALLEL_MIN: the threaded kernel
    particles = np.column_stack([
        rng.uniform(x0 - 1.0, x1 + 1.0, n),  # some off the grid: clamped
        rng.uniform(y0 - 1.0, y1 + 1.0, n),
        rng.uniform(-10.0, 10.0, n),  # any heading
    ])  # fmt: skip
    ref = naive.table_lookup(table.table, *table.origin, table.resolution,
                             particles, table.sonar.sensors)  # fmt: skip
    np.testing.assert_array_equal(table.lookup(particles), ref)
    np.testing.assert_array_equal(table.lookup(particles[:100]), ref[:100])
    np.testing.assert_array_equal(
        expected_readings(world, particles[:10], table=table), ref[:10]
    )


def test_exact_path_is_the_simulators_cast():
    """What the filter expects is what the simulator casts: end faces included."""
    world = load_world("corridor")
    poses = world.sample_free_poses(200, rng=3)
    np.testing.assert_array_equal(
        expected_readings(world, poses), expected_ranges(world.sensed_obstacles, poses)
    )
    with pytest.raises(ValueError, match="shape"):
        expected_readings(world, poses[:, :2])


def test_table_is_read_only_reused_per_world_and_sized():
    world = square_world(8.0)
    t = cone_table(world, resolution=0.2)
    assert cone_table(world, resolution=0.2) is t
    assert cone_table(world, resolution=0.25) is not t
    assert cone_table(world, SonarModel(max_range=3.0), resolution=0.2) is not t
    assert not t.table.flags.writeable and t.table.flags.c_contiguous
    assert t.table.shape == (40, 40, 72) and t.nbytes == 40 * 40 * 72 * 2
    assert t.n_bins == 72 and t.resolution == 0.2 and t.origin == (0.0, 0.0)
    assert not t.from_disk and t.build_seconds >= 0.0
    assert t.table.min() >= 100 and t.table.max() <= 5000  # min and max range, mm


def test_a_table_too_large_says_so_and_what_to_do():
    world = square_world(50.0)
    with pytest.raises(MemoryError, match=r"resolution=0\.\d+ fits.*fast=False"):
        ConeTable(world, max_bytes=10_000_000)
    assert cones.MAX_TABLE_BYTES == 1 << 30


@pytest.mark.parametrize(
    "kwargs",
    [{"resolution": 0.0}, {"n_bins": 2}, {"n_bins": 7.5},
     {"sonar": SonarModel(max_range=70.0)}],
)  # fmt: skip
def test_bad_arguments_are_refused_clearly(kwargs):
    with pytest.raises(ValueError, match="n_bins|max_range"):
        ConeTable(square_world(8.0), **kwargs)


@pytest.fixture
def disk(tmp_path, monkeypatch):
    """A disk cache of its own that keeps every table."""
    monkeypatch.setenv("ROBOTLIB_TABLE_CACHE", str(tmp_path))
    monkeypatch.setattr(cones, "DISK_MIN_SECONDS", 0.0)
    return tmp_path


def test_disk_cache_round_trip_keyed_by_walls_grid_and_model(disk):
    world = square_world(8.0)
    built = ConeTable(world, resolution=0.1)
    assert not built.from_disk and len(list(disk.glob("*.npy"))) == 1
    read = ConeTable(world, resolution=0.1)
    assert read.from_disk and not read.table.flags.writeable
    np.testing.assert_array_equal(read.table, built.table)
    assert not ConeTable(world, resolution=0.2).from_disk
    assert not ConeTable(world, SonarModel(max_range=3.0), resolution=0.1).from_disk
    assert not ConeTable(world, SonarModel(n_rays=5), resolution=0.1).from_disk
    moved = World(world.obstacles + [0.0, 0.0, 0.0, 1e-9], bounds=world.bounds)
    assert not ConeTable(moved, resolution=0.1).from_disk
    assert not list(disk.glob("*.tmp"))  # written whole, then renamed


def test_a_damaged_or_foreign_file_is_rebuilt(disk):
    world = square_world(8.0)
    built = ConeTable(world, resolution=0.1)
    (path,) = disk.glob("*.npy")
    for damage in (path.read_bytes()[:-2], b"not a table", b""):
        path.write_bytes(damage)
        again = ConeTable(world, resolution=0.1)
        assert not again.from_disk
        np.testing.assert_array_equal(again.table, built.table)
    np.save(path, np.zeros((3, 3), dtype=np.uint16))  # another shape
    assert not ConeTable(world, resolution=0.1).from_disk
    assert ConeTable(world, resolution=0.1).from_disk  # rewritten meanwhile


def test_a_cache_that_cannot_be_written_or_is_off_is_left_alone(tmp_path, monkeypatch):
    monkeypatch.setattr(cones, "DISK_MIN_SECONDS", 0.0)
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    monkeypatch.setenv("ROBOTLIB_TABLE_CACHE", str(blocker / "tables"))
    world = square_world(8.0)
    table = ConeTable(world, resolution=0.1)
    assert not table.from_disk and table.table.any()
    assert not ConeTable(world, resolution=0.1).from_disk
    for off in ("off", "0", ""):
        monkeypatch.setenv("ROBOTLIB_TABLE_CACHE", off)
        assert cones.table_cache_dir() is None


def test_default_cache_dir_follows_numba_and_xdg(tmp_path, monkeypatch):
    monkeypatch.delenv("ROBOTLIB_TABLE_CACHE")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba"))
    assert cones.table_cache_dir() == tmp_path / "numba" / "robotlib-tables"
    monkeypatch.delenv("NUMBA_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cones.table_cache_dir() == tmp_path / "xdg" / "robotlib" / "cone-tables"


def test_the_builder_refuses_a_table_it_cannot_fill_in_place():
    walls = np.array([[0.0, 1.0, 2.0, 1.0]])
    table = np.empty((4, 72, 4), dtype=np.uint16).transpose(0, 2, 1)
    with pytest.raises(ValueError, match="C-contiguous"):
        kernels.build_cone_table(walls, 0.0, 0.0, 0.5, [0], 5.0, 0.1, -1.0, table)
