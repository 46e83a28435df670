import math
from dataclasses import replace

import numpy as np
import pytest

from robotlib.mapping import (
    SONAR_SETTINGS,
    FastSLAMSettings,
    GridFastSLAM,
    apply_arc,
    arc_increment,
    record_drive,
    resample_maps,
    run_fastslam,
)
from robotlib.mapping.ekfslam import (
    _expected,
    chi2_band,
    ekf_add_landmark,
    ekf_predict,
    ekf_update,
    run_ekfslam,
)
from robotlib.sim import OdometryNoise

LEG = [(12.0, 1.5), (19.5, 1.5), (19.5, 6.0)]
"""A short leg of the loop world: 18 m east, a corner, 4.5 m north."""


@pytest.fixture(scope="module")
def leg_log():
    return record_drive("loop", LEG, seed=4, every=2)


def test_arc_increment_inverts_apply_arc():
    rng = np.random.default_rng(0)
    for _ in range(50):
        p = np.array([rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-3, 3)])
        ds, dth = rng.uniform(-0.3, 0.3), rng.uniform(-0.5, 0.5)
        q = apply_arc(p, ds, dth)[0]
        got = arc_increment(p, q)
        assert got == pytest.approx((ds, dth), abs=1e-12)


def test_resample_maps_copies_survivors_over_the_dead_in_place():
    maps = np.arange(5, dtype=np.float32)[:, None, None] * np.ones((5, 2, 3), "f4")
    idx = np.array([0, 0, 0, 3, 4])
    parents, _ = resample_maps(maps, idx)
    assert sorted(parents.tolist()) == sorted(idx.tolist())
    for k in range(5):
        assert np.all(maps[k] == parents[k])
    assert parents[0] == 0 and parents[3] == 3 and parents[4] == 4


def test_laser_fastslam_beats_odometry_and_is_reproducible(leg_log):
    a = run_fastslam(leg_log, 10, "laser", rng=7)
    b = run_fastslam(leg_log, 10, "laser", rng=7)
    np.testing.assert_array_equal(a.path, b.path)
    np.testing.assert_array_equal(a.map.logodds, b.map.logodds)
    assert a.path.shape == (len(leg_log), 3)
    assert a.rms < 0.5 * a.odometry_rms
    assert a.rms < 0.15
    assert a.score.f1 > 0.9
    c = run_fastslam(leg_log, 10, "laser", rng=8)
    assert not np.array_equal(a.path, c.path)


def test_sonar_fastslam_runs_seeded(leg_log):
    a = run_fastslam(leg_log.every(2), 8, "sonar", rng=1)
    b = run_fastslam(leg_log.every(2), 8, "sonar", rng=1)
    np.testing.assert_array_equal(a.path, b.path)
    assert a.map.shape == leg_log.world.occupancy_grid(0.1).shape
    assert np.isfinite(a.rms) and a.filter.n == 8


def test_fastslam_rejects_bad_sensors():
    with pytest.raises(ValueError, match="sensor"):
        GridFastSLAM((10, 10), (0, 0), 0.1, (0, 0, 0), sensor="radar")
    with pytest.raises(TypeError, match="FastSLAMSettings"):
        GridFastSLAM((10, 10), (0, 0), 0.1, (0, 0, 0), settings={"temperature": 1})
    with pytest.raises(ValueError, match="sonar_likelihood"):
        FastSLAMSettings(sonar_likelihood="cone")
    with pytest.raises(ValueError, match="beam_step"):
        FastSLAMSettings(beam_step=0)
    s = FastSLAMSettings(temperature=1, match_step=(1, 2), sonar_walls=[0, 3])
    assert isinstance(s.temperature, float) and s.match_step == (1.0, 2.0)
    assert s.sonar_walls == (0, 3)
    sonar = GridFastSLAM((10, 10), (0, 0), 0.1, (0, 0, 0), sensor="sonar", settings=s)
    assert not sonar.match and sonar.window == 0  # scan matching: the laser's


def _numeric_jacobian(f, x, eps=1e-6):
    x = np.asarray(x, float)
    cols = []
    for i in range(len(x)):
        d = np.zeros_like(x)
        d[i] = eps
        cols.append((f(x + d) - f(x - d)) / (2 * eps))
    return np.array(cols).T


def test_ekf_jacobians_match_numerical_ones():
    mu = np.array([1.0, 2.0, 0.4, 4.0, 3.0, -1.0, 5.0])
    _, H = _expected(mu, 1)
    num = _numeric_jacobian(lambda m: _expected(m, 1)[0], mu)
    np.testing.assert_allclose(H, num, atol=1e-6)
    # the prediction's state Jacobian, read off P = G P G^T with zero noise
    P = np.eye(7)
    _, P2 = ekf_predict(mu, P, 0.3, 0.2, OdometryNoise.none())

    def move(m):
        return ekf_predict(m, np.eye(7), 0.3, 0.2, OdometryNoise.none())[0]

    G = _numeric_jacobian(move, mu)
    np.testing.assert_allclose(P2, G @ G.T, atol=1e-6)


def test_ekf_update_and_new_landmark_shrink_uncertainty():
    R = np.diag([0.05**2, math.radians(2) ** 2])
    mu, P = np.zeros(3), np.diag([0.1, 0.1, 0.01])
    mu, P = ekf_add_landmark(mu, P, (2.0, 0.5), R)
    assert mu.shape == (5,) and P.shape == (5, 5)
    np.testing.assert_allclose(mu[3:], [2 * math.cos(0.5), 2 * math.sin(0.5)])
    before = np.trace(P[:3, :3])
    mu2, P2 = ekf_update(mu, P, (2.0, 0.5), 0, R)
    assert np.trace(P2) < np.trace(P) and np.trace(P2[:3, :3]) <= before
    np.testing.assert_allclose(P2, P2.T)
    assert np.all(np.linalg.eigvalsh(P2) > 0)


def test_ekf_slam_is_consistent_and_reproducible():
    nees, rms, odo = [], [], []
    for seed in range(4):
        log = record_drive("loop", LEG, seed=seed, every=1, laser=False)
        r = run_ekfslam(log, rng=seed)
        nees.append(r.nees[1:].mean())
        rms.append(r.rms)
        odo.append(r.odometry_rms)
    again = run_ekfslam(log, rng=3)
    np.testing.assert_array_equal(again.path, r.path)
    lo, hi = chi2_band(3 * 4)
    assert lo / 4 < np.mean(nees) < hi / 4
    assert np.mean(rms) < np.mean(odo)
    unknown = run_ekfslam(log, rng=3, known=False)
    assert unknown.rms < 2 * r.rms + 0.2


def test_chi2_band_is_near_the_tables():
    assert chi2_band(3)[1] == pytest.approx(9.35, abs=0.1)
    lo, hi = chi2_band(60)
    assert lo == pytest.approx(40.48, abs=0.1) and hi == pytest.approx(83.30, abs=0.1)


def test_sonar_walls_mark_arcs_of_the_chosen_sonars_only():
    from tests import naive_mapping as naive

    f = GridFastSLAM(
        (50, 70), (0.0, 0.0), 0.1, (2.0, 2.5, 0.3), n_particles=3, sensor="sonar",
        settings=FastSLAMSettings(sonar_walls=(0, 3, 4, 7)),
    )  # fmt: skip
    f.particles = f.particles + np.array([[0.0, 0.0, 0.0], [0.3, -0.2, 0.1],
                                          [-0.1, 0.4, -0.2]])  # fmt: skip
    rng = np.random.default_rng(3)
    z = rng.uniform(0.4, 3.0, 8)
    z[5] = f.sonar.max_range
    for _ in range(2):
        f.update_maps(z)
    m, s = f.settings.sonar_model, f.sonar
    walls, others = [0, 3, 4, 7], [1, 2, 5, 6]
    for n in range(3):
        want = np.zeros((50, 70))
        for _ in range(2):
            for k, l_occ in ((walls, m.l_occ), (others, 0.0)):
                want = naive.sonar_scan(
                    want, f.origin, 0.1, f.particles[n], s.sensors[k], z[k],
                    s.cone / 2, s.max_range, m.thickness, l_occ, m.l_free,
                    m.sigma, m.max_weight, m.l_min, m.l_max,
                )  # fmt: skip
        np.testing.assert_allclose(f.maps[n], want, atol=1e-5)
    # the other sonars only free their cones: with every sonar marking walls,
    # more cells are occupied
    g = GridFastSLAM((50, 70), (0.0, 0.0), 0.1, (2.0, 2.5, 0.3), n_particles=1,
                     sensor="sonar")  # fmt: skip
    g.update_maps(z)
    assert (g.maps[0] > 0).sum() > (f.maps[0] > 0).sum() > 0


def test_sonar_fastslam_with_wall_sonars_is_seeded(leg_log):
    log = leg_log.every(2)
    a = run_fastslam(log, 8, "sonar", rng=1, settings=SONAR_SETTINGS)
    b = run_fastslam(log, 8, "sonar", rng=1, settings=SONAR_SETTINGS)
    np.testing.assert_array_equal(a.path, b.path)
    np.testing.assert_array_equal(a.map.logodds, b.map.logodds)
    c = run_fastslam(
        log, 8, "sonar", rng=1, settings=replace(SONAR_SETTINGS, sonar_walls=None)
    )
    assert not np.array_equal(a.map.logodds, c.map.logodds)


def test_map_sonar_with_wall_sonars_matches_the_reference():
    from robotlib.mapping import map_sonar
    from robotlib.world import World
    from tests import naive_mapping as naive

    room = World([[0, 0, 6, 0], [6, 0, 6, 4], [6, 4, 0, 4], [0, 4, 0, 0]],
                 bounds=(-0.5, -0.5, 6.5, 4.5), start=(1, 2, 0))  # fmt: skip
    rng = np.random.default_rng(5)
    poses = np.column_stack([rng.uniform(1, 5, 4), rng.uniform(1, 3, 4),
                             rng.uniform(-3, 3, 4)])  # fmt: skip
    scans = rng.uniform(0.3, 5.0, (4, 8))
    g = map_sonar(room, poses, scans, 0.1, walls=[1, 6])
    f = GridFastSLAM((1, 1), (0, 0), 0.1, (0, 0, 0), n_particles=1, sensor="sonar")
    m, s = f.settings.sonar_model, f.sonar
    want = np.zeros(g.shape)
    for p, z in zip(poses, scans, strict=True):
        for k, l_occ in (([1, 6], m.l_occ), ([0, 2, 3, 4, 5, 7], 0.0)):
            want = naive.sonar_scan(
                want, g.origin, 0.1, p, s.sensors[k], z[k], s.cone / 2, s.max_range,
                m.thickness, l_occ, m.l_free, m.sigma, m.max_weight, m.l_min,
                m.l_max,
            )  # fmt: skip
    np.testing.assert_allclose(g.logodds, want, atol=1e-5)
