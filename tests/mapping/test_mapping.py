import math

import numpy as np
import pytest

from robotlib.mapping import (
    InverseSonarModel,
    OccupancyGrid,
    inverse_sonar_model,
    map_score,
    record_drive,
    trajectory_rms,
)
from robotlib.mapping import _kernels as kern
from robotlib.robot import Robot
from robotlib.sensing import SonarModel, cast_rays
from robotlib.sensing.laser import (
    LaserModel,
    expected_laser,
    laser_poses,
    simulate_laser,
)
from robotlib.sim import SimRobot, Simulator
from robotlib.world import World
from tests import naive_mapping as naive
from tests.worlds import door_corridor

ROOM = World(
    [[0, 0, 6, 0], [6, 0, 6, 4], [6, 4, 0, 4], [0, 4, 0, 0], [2, 1, 3, 1]],
    bounds=(-0.5, -0.5, 6.5, 4.5),
    start=(1, 2, 0),
)


# -- laser ------------------------------------------------------------------
def test_laser_matches_the_exact_caster_at_its_mount():
    rng = np.random.default_rng(0)
    poses = np.column_stack(
        [rng.uniform(0.5, 5.5, 20), rng.uniform(0.5, 3.5, 20), rng.uniform(-3, 3, 20)]
    )
    laser = LaserModel()
    got = expected_laser(ROOM, poses, laser)
    lp = laser_poses(poses, laser)
    assert np.allclose(
        lp[:, :2] - poses[:, :2],
        0.018 * np.column_stack([np.cos(poses[:, 2]), np.sin(poses[:, 2])]),
    )
    want = cast_rays(ROOM, lp, laser.angles, laser.max_range)
    assert got.shape == (20, 181)
    np.testing.assert_array_equal(got, want)
    assert laser.angles[0] == -math.pi / 2 and laser.angles[-1] == math.pi / 2


@pytest.mark.slow
def test_laser_on_a_grid_is_near_the_exact_caster():
    laser = LaserModel(max_range=4.0)
    poses = [[1.0, 2.0, 0.3], [4.5, 3.0, -2.0]]
    exact = expected_laser(ROOM, poses, laser)
    grid = expected_laser(ROOM.occupancy_grid(0.02), poses, laser)
    hit = exact < laser.max_range
    err = np.abs(grid - exact)[hit]
    # within a cell but where a beam grazes a wall (the cell edge lies further)
    assert np.median(err) < 0.02 and np.quantile(err, 0.9) < 0.02 * 3


def test_laser_noise_is_seeded_and_unbiased():
    laser = LaserModel()
    pose = [3.0, 2.0, 0.0]
    a = simulate_laser(ROOM, np.tile(pose, (400, 1)), laser, rng=5)
    b = simulate_laser(ROOM, np.tile(pose, (400, 1)), laser, rng=5)
    np.testing.assert_array_equal(a, b)
    truth = expected_laser(ROOM, pose, laser)[0]
    err = a - truth
    assert abs(err.mean()) < 1e-3
    assert 0.004 < err.std() < 0.0065  # 5 mm noise, 10 mm rounding
    far = LaserModel(max_range=1.0)
    z = simulate_laser(ROOM, pose, far, rng=1)[0]
    assert np.all(z <= 1.0) and np.any(z == 1.0)


def test_readlaser_leaves_sonar_and_odometry_bit_for_bit():
    def run(with_laser):
        r = SimRobot(Simulator(door_corridor(), seed=3))
        r.setvel(0.3)
        r.setrotvel(0.1)
        out, scans = [], []
        for t in range(30):
            if t % 3 == 0:  # one poll either way
                if with_laser:
                    scans.append(r.readlaser())
                else:
                    r.ismovedone()
            out.append(np.concatenate([r.readsonar(), r.pose(), r.true_pose()]))
        return np.array(out), scans

    plain, _ = run(False)
    laser, scans = run(True)
    np.testing.assert_array_equal(plain, laser)
    assert len(scans) == 10 and scans[0].shape == (181,)
    again, scans2 = run(True)
    np.testing.assert_array_equal(np.array(scans), np.array(scans2))


def test_a_backend_without_a_laser_says_so():
    class NoLaser(Robot):
        def _send(self, command, value=None):
            pass

        def _update(self):
            raise AssertionError("must not poll")

        def _close(self):
            pass

    with pytest.raises(NotImplementedError, match="NoLaser has no laser"):
        NoLaser().readlaser()


# -- kernels against the references -------------------------------------------
SONAR_ARGS = dict(thickness=0.1, l_occ=0.9, l_free=-0.35, max_weight=0.3)


@pytest.mark.parametrize("sigma", [0.0, 0.1, 0.15])  # none, table, polynomial
def test_sonar_cone_kernel_matches_the_reference(sigma):
    rng = np.random.default_rng(1)
    shape, origin, res = (60, 80), (-0.5, -0.3), 0.05
    for _ in range(30):
        sx, sy = rng.uniform(-0.5, 3.5), rng.uniform(-0.3, 2.7)
        sth = rng.uniform(-math.pi, math.pi)
        z = rng.choice([rng.uniform(0.1, 2.5), 5.0])
        L = np.zeros(shape, np.float32)
        kern.sonar_cone_update(
            L,
            *origin,
            res,
            sx,
            sy,
            sth,
            z,
            math.radians(15),
            5.0,
            SONAR_ARGS["thickness"],
            SONAR_ARGS["l_occ"],
            SONAR_ARGS["l_free"],
            sigma,
            SONAR_ARGS["max_weight"],
            -6.0,
            6.0,
        )
        want = naive.sonar_cone_increments(
            shape,
            origin,
            res,
            sx,
            sy,
            sth,
            z,
            math.radians(15),
            5.0,
            sigma=sigma,
            **SONAR_ARGS,
        )
        np.testing.assert_allclose(L, want, atol=1e-6)


def test_sonar_ring_update_and_numpy_model_match_the_reference():
    sonar = SonarModel()
    model = InverseSonarModel()
    g = OccupancyGrid.for_world(ROOM, 0.1)
    rng = np.random.default_rng(2)
    ref = g.logodds.astype(float)
    for _ in range(5):
        pose = np.array([rng.uniform(1, 5), rng.uniform(1, 3), rng.uniform(-3, 3)])
        z = rng.uniform(0.3, 5.0, 8)
        z[rng.random(8) < 0.3] = 5.0
        g.update_sonar(pose, z, sonar, model)
        ref = naive.sonar_scan(
            ref,
            g.origin,
            0.1,
            pose,
            sonar.sensors,
            z,
            sonar.cone / 2,
            5.0,
            model.thickness,
            model.l_occ,
            model.l_free,
            model.sigma,
            model.max_weight,
            model.l_min,
            model.l_max,
        )
    np.testing.assert_allclose(g.logodds, ref, atol=1e-5)
    # the NumPy inverse model, cell by cell, for one reading
    cells = np.stack(naive.cell_centres(g.shape, g.origin, 0.1), axis=-1)
    inc = inverse_sonar_model(cells, (2.0, 2.0, 0.4), 1.7, sonar, model)
    want = naive.sonar_cone_increments(
        g.shape,
        g.origin,
        0.1,
        2.0,
        2.0,
        0.4,
        1.7,
        sonar.cone / 2,
        5.0,
        sigma=model.sigma,
        **SONAR_ARGS,
    )
    np.testing.assert_allclose(inc, want, atol=1e-12)
    assert inc.max() > 0 > inc.min()


def test_laser_kernel_matches_the_reference():
    rng = np.random.default_rng(3)
    shape, origin, res = (50, 70), (-0.5, -0.5), 0.05
    L = np.zeros(shape, np.float32)
    ref = np.zeros(shape)
    angles = np.linspace(-math.pi / 2, math.pi / 2, 37)
    for _ in range(6):
        lp = np.array([rng.uniform(0, 3), rng.uniform(0, 2), rng.uniform(-3, 3)])
        z = rng.uniform(0.05, 3.0, len(angles))
        z[rng.random(len(z)) < 0.2] = 2.5  # max range
        kern.laser_scan_update(
            L, *origin, res, lp, angles, z, 2.5, 0.9, -0.4, -6.0, 6.0
        )
        ref = naive.laser_scan(ref, origin, res, lp, angles, z, 2.5, 0.9, -0.4, -6, 6)
    np.testing.assert_allclose(L, ref, atol=1e-5)


@pytest.mark.slow
def test_many_particle_kernels_match_single_map_kernels_and_references():
    rng = np.random.default_rng(4)
    shape, origin, res = (40, 60), (-0.5, -0.5), 0.1
    n = 5
    Ls = rng.normal(0, 2, (n, *shape)).astype(np.float32)
    poses = np.column_stack(
        [rng.uniform(1, 4, n), rng.uniform(1, 2.5, n), rng.uniform(-3, 3, n)]
    )
    angles = np.linspace(-math.pi / 2, math.pi / 2, 19)
    z = rng.uniform(0.2, 3.0, 19)
    z[3] = 4.0
    out = np.empty(n)
    kern.laser_loglik_many(Ls, *origin, res, poses, angles, z, 4.0, 0.05, out)
    for k in range(n):
        want = naive.laser_loglik(Ls[k], origin, res, poses[k], angles, z, 4.0, 0.05)
        assert out[k] == pytest.approx(want, rel=1e-9)
    sonar = SonarModel()
    zs = rng.uniform(0.3, 5.0, 8)
    zs[0] = 5.0
    kern.sonar_loglik_many(
        Ls, *origin, res, poses, sonar.sensors, zs, sonar.cone / 2, 5.0, 5, 0.05, out
    )
    for k in range(n):
        want = naive.sonar_loglik(
            Ls[k],
            origin,
            res,
            poses[k],
            sonar.sensors,
            zs,
            sonar.cone / 2,
            5.0,
            5,
            0.05,
        )
        assert out[k] == pytest.approx(want, rel=1e-9)
    for c_unknown, centre in ((0.0, False), (0.5, False), (0.0, True), (0.5, True)):
        kern.sonar_beam_loglik_many(
            Ls, *origin, res, poses, sonar.sensors, zs, sonar.cone / 2, 5.0, 5,
            0.15, 0.2, 0.5, c_unknown, out, centre,
        )  # fmt: skip
        for k in range(n):
            want = naive.sonar_beam_loglik(
                Ls[k], origin, res, poses[k], sonar.sensors, zs, sonar.cone / 2,
                5.0, 5, 0.15, 0.2, 0.5, c_unknown, centre,
            )  # fmt: skip
            assert out[k] == pytest.approx(want, rel=1e-9)
    many = Ls.copy()
    kern.laser_update_many(many, *origin, res, poses, angles, z, 4.0, 0.9, -0.4, -6, 6)
    kern.sonar_update_many(
        many,
        *origin,
        res,
        poses,
        sonar.sensors,
        zs,
        sonar.cone / 2,
        5.0,
        0.1,
        0.9,
        -0.35,
        0.15,
        0.3,
        -6.0,
        6.0,
    )
    for k in range(n):
        one = Ls[k].copy()
        kern.laser_scan_update(
            one, *origin, res, poses[k], angles, z, 4.0, 0.9, -0.4, -6, 6
        )
        kern.sonar_scan_update(
            one,
            *origin,
            res,
            poses[k],
            sonar.sensors,
            zs,
            sonar.cone / 2,
            5.0,
            0.1,
            0.9,
            -0.35,
            0.15,
            0.3,
            -6,
            6,
        )
        np.testing.assert_array_equal(many[k], one)
    src, dst = np.array([0, 0, 2]), np.array([1, 3, 4])
    kern.copy_maps(many, src, dst)
    np.testing.assert_array_equal(many[3], many[0])
    np.testing.assert_array_equal(many[4], many[2])


# -- metrics --------------------------------------------------------------------
def test_metrics_on_hand_made_maps():
    res = 0.1
    truth = ROOM.occupancy_grid(res).data
    perfect = np.where(truth, 3.0, -3.0)
    s = map_score(perfect, ROOM, res)
    assert s.f1 == 1.0 and s.precision == 1.0 and s.recall == 1.0
    assert s.mean_distance < res
    assert map_score(np.zeros(truth.shape), ROOM, res).f1 == 0.0
    # everything free: explored walls, none found
    assert map_score(np.full(truth.shape, -1.0), ROOM, res).recall == 0.0
    # everything occupied: all walls found, poor precision
    s = map_score(np.full(truth.shape, 1.0), ROOM, res)
    assert s.recall == 1.0 and s.precision < 0.4
    # a wall drawn one cell off still counts; three cells off does not
    shifted = np.roll(perfect, 1, axis=1)
    assert map_score(shifted, ROOM, res).f1 > 0.95
    assert map_score(np.roll(perfect, 3, axis=0), ROOM, res).f1 < 0.5
    with pytest.raises(ValueError, match="shape"):
        map_score(perfect[1:], ROOM, res)
    assert trajectory_rms([[0, 0, 0], [1, 1, 0]], [[0, 1, 0], [1, 1, 3]]) == (
        pytest.approx(math.sqrt(0.5))
    )


def test_known_pose_maps_of_a_seeded_drive():
    route = [(4.5, 1.0), (4.5, 1.5), (1.0, 1.5), (1.0, 1.0)]
    log = record_drive(door_corridor(), route, seed=2, every=2)
    assert len(log) > 20 and log.laser.shape == (len(log), 181)
    w = log.world
    from robotlib.mapping import map_laser, map_sonar

    laser = map_score(map_laser(w, log.truth, log.laser, 0.05), w, 0.05)
    sonar = map_score(map_sonar(w, log.truth, log.sonar, 0.1), w, 0.1)
    assert laser.f1 > 0.9
    assert sonar.f1 > 0.6
    again = record_drive(door_corridor(), route, seed=2, every=2)
    np.testing.assert_array_equal(again.sonar, log.sonar)
    np.testing.assert_array_equal(again.laser, log.laser)


def test_scan_fitting_kernel_matches_the_reference():
    rng = np.random.default_rng(8)
    shape, origin, res = (40, 60), (-0.5, -0.5), 0.1
    n = 4
    Ls = np.maximum(rng.normal(0, 2, (n, *shape)), 0).astype(np.float32)
    poses = np.column_stack(
        [rng.uniform(1, 4, n), rng.uniform(1, 2.5, n), rng.uniform(-3, 3, n)]
    )
    mount = np.array([0.16, 0.01, 0.02])
    angles = np.linspace(-math.pi / 2, math.pi / 2, 23)
    z = rng.uniform(0.2, 2.0, 23)
    z[[2, 9]] = 4.0  # no return
    out = np.empty((n, 3))
    kern.match_laser_many(
        Ls, *origin, res, poses, mount, angles, z, 4.0, 0.05, 0.03, 3, 0.0, 0.0, out
    )
    for k in range(n):
        want = naive.match_laser(
            Ls[k], origin, res, poses[k], mount, angles, z, 4.0, (0.05, 0.03), 3
        )
        np.testing.assert_allclose(out[k], want, atol=1e-9)
        assert not np.allclose(out[k], poses[k])  # it moved
    # with a prior: the reference's rule
    held = np.empty((n, 3))
    kern.match_laser_many(
        Ls, *origin, res, poses, mount, angles, z, 4.0, 0.05, 0.03, 3, 400.0, 100.0,
        held,
    )  # fmt: skip
    for k in range(n):
        want = naive.match_laser(
            Ls[k], origin, res, poses[k], mount, angles, z, 4.0, (0.05, 0.03), 3,
            prior=(400.0, 100.0),
        )  # fmt: skip
        np.testing.assert_allclose(held[k], want, atol=1e-9)
    assert not np.allclose(held, out)  # the prior changed the fits
    pinned = np.empty((n, 3))  # a prior no fit outweighs: nothing moves
    kern.match_laser_many(
        Ls, *origin, res, poses, mount, angles, z, 4.0, 0.05, 0.03, 3, 1e9, 1e9,
        pinned,
    )  # fmt: skip
    np.testing.assert_array_equal(pinned, poses)


def test_sonar_beam_range_to_cell_centres_is_unbiased_on_a_mapped_wall():
    # a wall one cell thick whose cell centres lie 1.0 m ahead of a sonar at the
    # origin facing +x: an echo at 1.0 m is where the inverse model put the wall
    res, origin = 0.1, (-0.05, -1.05)
    L = np.zeros((21, 21), dtype=np.float32)
    L[:, 10] = 4.0  # column 10: centres at x = 1.0
    sensors = np.zeros((1, 3))
    args = (sensors, np.array([1.0]), math.radians(1.0), 5.0, 5, 0.05, 0.0, 2.0, 0.0)
    entry = kern.sonar_beam_loglik(L, *origin, res, 0.0, 0.0, 0.0, *args, False)
    centre = kern.sonar_beam_loglik(L, *origin, res, 0.0, 0.0, 0.0, *args, True)
    assert centre == pytest.approx(0.0, abs=1e-3)  # zhat = 1.0 (cos 1 deg off)
    assert entry < -0.3  # the ray enters the cell 5 cm short: zhat = 0.95 m
    for c in (False, True):
        want = naive.sonar_beam_loglik(
            L, origin, res, (0.0, 0.0, 0.0), *args[:-1], 0.0, c
        )
        assert kern.sonar_beam_loglik(
            L, *origin, res, 0.0, 0.0, 0.0, *args, c
        ) == pytest.approx(want, rel=1e-9)
