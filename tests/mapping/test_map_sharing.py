"""Cheap copies of FastSLAM's maps: the box kernels against NumPy, and the
tracked copies against whole copies, bit for bit."""

import math

import numpy as np
import pytest

from robotlib.mapping import FastSLAMSettings, GridFastSLAM, record_drive
from robotlib.mapping import _kernels as kern
from robotlib.mapping import _kernels_copy as _copy
from robotlib.mapping.sharing import EMPTY_BOX, MapDiff
from tests import naive_mapping as naive

ORIGIN, RES, SHAPE = (-0.5, -0.3), 0.05, (60, 80)


def test_laser_box_matches_numpy_and_holds_every_cell_a_scan_writes():
    rng = np.random.default_rng(1)
    angles = np.linspace(-math.pi / 2, math.pi / 2, 37)
    for _ in range(40):
        lpose = np.array([rng.uniform(-1, 4), rng.uniform(-1, 3), rng.uniform(-3, 3)])
        z = np.where(rng.random(37) < 0.2, 4.0, rng.uniform(0.05, 3.9, 37))
        box = np.empty((1, 4), dtype=np.int64)
        _copy.laser_boxes(*ORIGIN, RES, *SHAPE, lpose[None], angles, z, 4.0, box)
        want = naive.laser_box(lpose, angles, z, 4.0, ORIGIN, RES, SHAPE)
        assert tuple(box[0]) == want
        L = np.zeros(SHAPE, np.float32)
        kern.laser_scan_update(L, *ORIGIN, RES, lpose, angles, z, 4.0, 0.9, -0.4, -6, 6)
        i, j = np.nonzero(L)
        i0, i1, j0, j1 = box[0]
        assert np.all((i >= i0) & (i <= i1) & (j >= j0) & (j <= j1))


def test_disc_box_matches_numpy():
    poses = np.array([[0.3, 0.2, 1.0], [10.0, 10.0, 0.0], [3.9, -2.0, 0.0]])
    boxes = np.empty((3, 4), dtype=np.int64)
    _copy.disc_boxes(*ORIGIN, RES, *SHAPE, poses, 0.7, boxes)
    for p, b in zip(poses, boxes, strict=True):
        want = naive.points_box(
            [p[0] - 0.7, p[0] + 0.7], [p[1] - 0.7, p[1] + 0.7], ORIGIN, RES, SHAPE
        )
        assert tuple(b) == want
    assert boxes[1, 0] > boxes[1, 1]  # off the grid: empty


def test_map_diff_boxes_follow_writes_and_resampling():
    d = MapDiff(3)
    d.wrote(np.array([[1, 2, 1, 2], EMPTY_BOX, [5, 6, 0, 0]]))
    assert tuple(d.boxes[0, 1]) == (1, 2, 1, 2)
    assert tuple(d.boxes[0, 2]) == (1, 6, 0, 2)
    maps = np.arange(3, dtype=np.float32)[:, None, None] * np.ones((3, 8, 4), "f4")
    cells = d.resample(maps, [0, 0, 2])  # slot 1 takes particle 0's map
    assert cells == 4  # only the 2 x 2 box where maps 0 and 1 may differ
    assert np.all(maps[1, 1:3, 1:3] == 0) and maps[1, 0, 0] == 1
    assert d.boxes[0, 1, 0] > d.boxes[0, 1, 1]  # now the same map
    assert tuple(d.boxes[1, 2]) == (1, 6, 0, 2)
    with pytest.raises(ValueError, match="copied over"):
        d.resample(maps, [0, 2, 1])


@pytest.mark.parametrize("sensor", ["laser", "sonar"])
def test_fastslam_copies_less_and_gives_the_same_maps_as_whole_copies(sensor):
    log = record_drive("loop", [(8.0, 1.5), (12.0, 1.5)], seed=2, every=2)
    runs = []
    for whole in (False, True):
        f = GridFastSLAM.for_world(
            log.world, 0.05 if sensor == "laser" else 0.1, start=log.odometry[0],
            n_particles=8, sensor=sensor,
            settings=FastSLAMSettings(resample_below=0.9), rng=3,
        )  # fmt: skip
        scans = log.laser if sensor == "laser" else log.sonar
        for t in range(len(log)):
            if whole:
                f._diff_maps = None  # forget where maps differ: whole copies
            f.step(log.odometry[t], scans[t])
        runs.append(f)
    a, b = runs
    assert a.resampled > 5
    np.testing.assert_array_equal(a.maps, b.maps)
    np.testing.assert_array_equal(a.best_path(), b.best_path())
    assert a.copied < 0.5 * b.copied


@pytest.mark.parametrize("sigma", [0.1, 0.15, 0.3])
def test_cone_weight_table_matches_the_gaussian_of_the_angle(sigma):
    half = math.radians(15)
    table = kern.cone_weight_table(half, sigma)
    t = np.linspace(-math.tan(half), math.tan(half), 2001)
    got = np.array([kern._table_weight(table, math.tan(half), v) for v in t])
    want = np.exp(-(np.arctan(t) ** 2) / (2 * sigma**2))
    np.testing.assert_allclose(got, want, rtol=0, atol=3e-8)


@pytest.mark.parametrize(
    ("half_deg", "sigma", "used"),
    [(15, 0.15, True), (15, 0.3, True), (5, 0.1, True), (15, 0.1, False),
     (30, 0.15, False), (15, 0.0, False)],
)  # fmt: skip
def test_cone_weight_poly_matches_the_gaussian_where_it_is_used(half_deg, sigma, used):
    half = math.radians(half_deg)
    poly = kern.cone_weight_poly(half, sigma)
    assert (poly[0] > 0) == used
    if not used:  # the kernels fall back on the table
        p, table = kern.cone_weights(half, sigma)
        assert p[0] == 0 and (sigma == 0 or table.shape == (kern.WEIGHT_PIECES, 4))
        return
    t = np.linspace(-math.tan(half), math.tan(half), 2001)
    got = np.polynomial.polynomial.polyval(poly[0] * t * t - 1.0, poly[1:])
    want = np.exp(-(np.arctan(t) ** 2) / (2 * sigma**2))
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-8)


def test_window_loglik_sums_the_beam_model_over_the_window():
    from robotlib.mapping import _kernels_window as kw
    from robotlib.sensing import SonarModel

    rng = np.random.default_rng(5)
    sonar = SonarModel()
    Ls = rng.uniform(-4, 4, (3, *SHAPE)).astype(np.float32)
    wins = np.stack(
        [np.column_stack([rng.uniform(0, 3, 4), rng.uniform(0, 2, 4),
                          rng.uniform(-3, 3, 4)]) for _ in range(3)]
    )  # fmt: skip
    scans = rng.uniform(0.3, 5.0, (4, 8))
    scans[1, 2] = 5.0
    for kernel, centre in (
        (kw.window_loglik_many, False), (kw.window_loglik_many_parallel, False),
        (kw.window_loglik_many, True),
    ):  # fmt: skip
        out = np.empty(3)
        kernel(
            Ls, *ORIGIN, RES, wins, sonar.sensors, scans, sonar.cone / 2, 5.0, 5,
            0.15, 0.2, 0.5, 0.5, out, centre,
        )  # fmt: skip
        for n in range(3):
            want = sum(
                naive.sonar_beam_loglik(
                    Ls[n],
                    ORIGIN,
                    RES,
                    wins[n, k],
                    sonar.sensors,
                    scans[k],
                    sonar.cone / 2,
                    5.0,
                    5,
                    0.15,
                    0.2,
                    0.5,
                    0.5,
                    centre,
                )  # fmt: skip
                for k in range(4)
            )
            assert out[n] == pytest.approx(want, rel=1e-9)


def test_windowed_sonar_fastslam_is_seeded_and_maps_the_window():
    log = record_drive("loop", [(8.0, 1.5), (12.0, 1.5)], seed=2, every=2)
    paths, maps = [], []
    for _ in range(2):
        f = GridFastSLAM.for_world(
            log.world, 0.1, start=log.odometry[0], n_particles=6, sensor="sonar",
            settings=FastSLAMSettings(window=5, temperature=0.006), rng=4,
        )  # fmt: skip
        for t in range(len(log)):
            f.step(log.odometry[t], log.sonar[t])
        paths.append(f.best_path())
        maps.append(f.best_map().logodds)
    np.testing.assert_array_equal(paths[0], paths[1])
    np.testing.assert_array_equal(maps[0], maps[1])
    assert f._win.shape == (6, 5, 3)
    # the best map holds the window's records: not the bare map
    assert not np.array_equal(maps[0], f.maps[f.best()])
