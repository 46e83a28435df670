"""Cone-table builders and the exact path's wall lists against every-wall kernels.

The map that matters is MobileSim-like: DATA points on a 20 mm grid (each a
small cross of two segments) under cells whose centres sit 25 mm off that
grid, so that rays along multiples of 45 degrees pass exactly through the
crosses' end points. There a few ulps in a cell's centre change readings by
decimetres, so a reference must compute the very cells the builders do.
"""

import math

import numpy as np
import pytest

from robotlib.experiments import bench_large_map
from robotlib.experiments.bench_mcl import square_world
from robotlib.localization import ConeTable, expected_readings
from robotlib.localization import _kernels as lk
from robotlib.localization.cones import _sweep_builds
from robotlib.sensing import SonarModel
from robotlib.sensing import _kernels as sk
from robotlib.world import World, load_world
from robotlib.world.index import INDEX_MIN_SEGMENTS


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


def model(sonar, resolution, ray_step):
    return (
        resolution, 72, ray_step, sonar.n_rays, sonar.cone, sonar.max_range,
        sonar.min_range, sonar.cos_specular,
    )  # fmt: skip


def every_wall(world, sonar, resolution, ray_step, shape, origin):
    ny, nx = shape
    rows, cols = np.divmod(np.arange(ny * nx), nx)
    out = np.empty((ny * nx, 72), dtype=np.uint16)
    lk.cone_table_cells(
        np.ascontiguousarray(world.obstacles), *origin, resolution, rows, cols, 72,
        ray_step, sonar.n_rays, sonar.cone, sonar.max_range, sonar.min_range,
        sonar.cos_specular, out,
    )  # fmt: skip
    return out.reshape(ny, nx, 72)


@pytest.mark.parametrize(
    ("sonar", "resolution", "ray_step"),
    [(SonarModel(), 0.05, 1), (SonarModel(n_rays=5), 0.1, 0)],
    ids=["shared-rays", "whole-cones"],
)
def test_both_builders_equal_the_every_wall_kernel_on_a_point_grid(
    grid_map, sonar, resolution, ray_step
):
    world = load_world(grid_map)
    table = ConeTable(world, sonar, resolution)  # dense: strips or the index
    assert not _sweep_builds(world, sonar, ray_step)
    ny, nx, _ = table.table.shape
    ref = every_wall(world, sonar, resolution, ray_step, (ny, nx), table.origin)
    np.testing.assert_array_equal(table.table, ref)
    swept = np.empty_like(ref)
    lk.build_cone_table(
        np.ascontiguousarray(world.obstacles), *table.origin,
        *model(sonar, resolution, ray_step), 16, swept,
    )  # fmt: skip
    np.testing.assert_array_equal(swept, ref)


def test_the_point_grid_is_sensitive_to_a_cells_last_bits(grid_map):
    """Rows built from a shifted origin (the old bench's reference) differ here."""
    world = load_world(grid_map)
    sonar = SonarModel()
    table = ConeTable(world, sonar, 0.05)
    x0, y0 = table.origin
    differ = 0
    for i in (10, 27, 31, 44):  # origin + i * res, then + 0.5 * res: not the cell's
        row = np.empty((1, table.table.shape[1], 72), dtype=np.uint16)
        lk.build_cone_table(
            np.ascontiguousarray(world.obstacles), x0, y0 + i * 0.05,
            *model(sonar, 0.05, 1), 16, row,
        )  # fmt: skip
        differ += np.count_nonzero(row[0] != table.table[i])
    assert differ > 0


def test_bench_large_map_compares_the_builders_cells(grid_map):
    r = bench_large_map.bench_maps(grid_map, resolution=0.05, sample=60)
    assert r["reference_entries"] == 60 * 72
    assert r["table_matches_reference"], r
    assert r["reference_differing"] == 0


def test_bench_large_map_refuses_a_missing_map_clearly(tmp_path, capsys):
    args = type("Args", (), {"map": str(tmp_path / "missing.map")})()
    args.resolution, args.sample = 0.05, 40
    assert bench_large_map.run(args) == 2
    err = capsys.readouterr().err
    assert "missing.map" in err and "Traceback" not in err


def test_large_maps_take_the_indexed_builders_small_ones_the_sweep(grid_map):
    sonar = SonarModel()
    assert not _sweep_builds(load_world(grid_map), sonar, 1)  # 1,320 crosses, 9 m2
    assert not _sweep_builds(square_world(50.0), sonar, 1)  # 532 walls: strips
    assert not _sweep_builds(square_world(50.0), sonar, 0)  # whole cones: indexed
    small = square_world(12.0)
    assert len(small.obstacles) < INDEX_MIN_SEGMENTS and _sweep_builds(small, sonar, 1)
    building = load_world("building")  # 308 walls: a lab's world keeps the sweep
    assert _sweep_builds(building, sonar, 1) and not _sweep_builds(building, sonar, 0)


@pytest.mark.parametrize("which", ["grid", "building"])
def test_exact_path_heading_sectors_equal_every_wall(grid_map, which):
    """expected_readings (walls per block and heading sector) equals the full cast."""
    world = load_world(grid_map) if which == "grid" else square_world(12.0)
    sonar = SonarModel()
    rng = np.random.default_rng(5)
    xmin, ymin, xmax, ymax = world.bounds
    n = 400
    poses = np.column_stack(
        [
            rng.uniform(xmin, xmax, n),
            rng.uniform(ymin, ymax, n),
            rng.uniform(-math.pi, math.pi, n),
        ]
    )
    # headings on the sector edges (16 sectors) for the front sensors
    edges = np.arange(16) * (2 * math.pi / 16)
    poses[:64, 2] = np.repeat(edges, 4) - np.tile(sonar.sensors[:4, 2], 16)
    got = expected_readings(world, poses, sonar)
    ref = np.empty_like(got)
    sk.expected_scan(
        poses, sonar.sensors, np.ascontiguousarray(world.obstacles), sonar.n_rays,
        sonar.cone, sonar.max_range, sonar.min_range, sonar.cos_specular, ref,
    )  # fmt: skip
    np.testing.assert_array_equal(got, ref)


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


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_sweep_equals_the_every_wall_kernel_on_random_walls(seed):
    walls = random_walls(seed)
    sonar = SonarModel(max_range=3.0)
    shape, origin = (40, 40), (0.0, 0.0)
    ref = every_wall(_World(walls), sonar, 0.1, 1, shape, origin)
    for block in (1, 5, 16):
        out = np.empty(shape + (72,), dtype=np.uint16)
        lk.build_cone_table(walls, *origin, *model(sonar, 0.1, 1), block, out)
        np.testing.assert_array_equal(out, ref)


class _World:
    def __init__(self, walls):
        self.obstacles = np.ascontiguousarray(walls)


def near_parallel_walls(rng, n=24):
    """Walls within 1e-9 .. 1e-5 rad of a direction bin, through the grid."""
    b = rng.integers(0, 72, n)
    a = b * (2 * math.pi / 72) + rng.choice([-1, 1], n) * 10.0 ** rng.uniform(-9, -5, n)
    p = rng.uniform(0.5, 3.5, (n, 2))
    length = rng.uniform(0.3, 3.0, n)
    d = np.column_stack([np.cos(a), np.sin(a)])
    return np.column_stack([p, p + length[:, None] * d])


@pytest.mark.parametrize("seed", [0, 1])
def test_strip_rays_equal_the_every_wall_kernel_on_random_walls(seed):
    """The strips builder (`table_strips`) on 300 walls, some nearly parallel."""
    rng = np.random.default_rng(seed + 10)
    walls = np.concatenate([random_walls(seed, 300), near_parallel_walls(rng)])
    world = World(walls, bounds=(0.0, 0.0, 4.0, 4.0))
    shape, origin = (36, 40), (0.0, 0.0)  # not square: rows and columns apart
    for ray_step, n_rays in ((1, 1), (3, 7)):  # single rays; the Pioneer's cones
        sonar = SonarModel(max_range=3.0, n_rays=n_rays)
        ref = every_wall(world, sonar, 0.1, ray_step, shape, origin)
        assert len(np.unique(ref)) > 200  # hits at many ranges, not a blank table
        out = np.empty(shape + (72,), dtype=np.uint16)
        lk.build_cone_table_strips(
            world.obstacles, *origin, *model(sonar, 0.1, ray_step), out
        )
        np.testing.assert_array_equal(out, ref)


def test_disk_cache_gives_the_same_table_and_rebuilds_when_unsure(
    tmp_path, monkeypatch
):
    from robotlib.localization import cones

    monkeypatch.setattr(cones, "DISK_MIN_SECONDS", 0.0)
    monkeypatch.setenv("ROBOTLIB_TABLE_CACHE", str(tmp_path))
    world = square_world(8.0)
    built = ConeTable(world, resolution=0.1)
    assert not built.from_disk
    read = ConeTable(world, resolution=0.1)  # waits for the file being written
    assert read.from_disk and not read.table.flags.writeable
    assert len(list(tmp_path.glob("*.npy"))) == 1
    np.testing.assert_array_equal(read.table, built.table)
    # another grid, sonar or wall: another key
    assert not ConeTable(world, resolution=0.2).from_disk
    assert not ConeTable(world, SonarModel(max_range=3.0), resolution=0.1).from_disk
    moved = type(world)(world.segments + [0.0, 0.0, 0.0, 1e-9], bounds=world.bounds)
    assert not ConeTable(moved, resolution=0.1).from_disk
    # a truncated or foreign file is not trusted
    for f in tmp_path.glob("*.npy"):
        f.write_bytes(f.read_bytes()[:-2])
    again = ConeTable(world, resolution=0.1)
    assert not again.from_disk
    np.testing.assert_array_equal(again.table, built.table)
    # off: never read
    monkeypatch.setenv("ROBOTLIB_TABLE_CACHE", "off")
    assert cones.table_cache_dir() is None
    assert not ConeTable(world, resolution=0.1).from_disk


def test_disk_cache_that_cannot_be_written_is_left_alone(tmp_path, monkeypatch):
    from robotlib.localization import cones

    monkeypatch.setattr(cones, "DISK_MIN_SECONDS", 0.0)
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    monkeypatch.setenv("ROBOTLIB_TABLE_CACHE", str(blocker / "tables"))
    table = ConeTable(square_world(8.0), resolution=0.1)
    assert not table.from_disk and table.table.any()


@pytest.mark.parametrize("n_bins", [9, 40])
def test_strip_rays_pair_opposite_bins_and_work_alone_for_odd_counts(n_bins):
    """Even counts share strips between bins b and b + n/2; odd ones cannot."""
    walls = random_walls(3, 200)
    walls = np.concatenate([walls, [[1.0, 0.2, 1.0, 3.8], [0.2, 2.0, 3.8, 2.0]]])
    sonar = SonarModel(max_range=3.0, n_rays=3)
    shape, origin = (40, 40), (0.0, 0.0)
    ny, nx = shape
    rows, cols = np.divmod(np.arange(ny * nx), nx)
    ref = np.empty((ny * nx, n_bins), dtype=np.uint16)
    lk.cone_table_cells(
        walls, *origin, 0.1, rows, cols, n_bins, 1, sonar.n_rays, sonar.cone,
        sonar.max_range, sonar.min_range, sonar.cos_specular, ref,
    )  # fmt: skip
    out = np.empty(shape + (n_bins,), dtype=np.uint16)
    lk.build_cone_table_strips(
        walls, *origin, 0.1, n_bins, 1, sonar.n_rays, sonar.cone, sonar.max_range,
        sonar.min_range, sonar.cos_specular, out,
    )  # fmt: skip
    assert len(np.unique(ref)) > 100
    np.testing.assert_array_equal(out, ref.reshape(shape + (n_bins,)))
