"""The MCL pieces against hand-computed cases and the NumPy references."""

import math

import numpy as np
import pytest

from robotlib.localization import (
    MCL,
    BeamParameters,
    BeamSensorModel,
    LikelihoodFieldSensorModel,
    cone_table,
    expected_readings,
    kld_bound,
    kld_resample,
    multinomial_resample,
    odometry_increment,
    paper,
    resampling,
    residual_resample,
    sample_motion_odometry,
    stratified_resample,
    systematic_resample,
)
from robotlib.localization._kernels.kld import kld_bound as kld_bound_kernel
from robotlib.localization.motion import move_particles
from robotlib.sensing import SonarModel, expected_ranges
from tests import naive_mcl as naive
from tests.worlds import door_corridor


@pytest.fixture(scope="module")
def world():
    """A 6 m x 2 m corridor with one door and a box, start at the west end."""
    return door_corridor()


def test_odometry_increment_hand_cases():
    assert odometry_increment((0, 0, 0), (1, 0, 0)) == pytest.approx((0, 1, 0))
    r1, t, r2 = odometry_increment((1, 1, 0), (1, 2, math.pi / 2))
    assert (r1, t, r2) == pytest.approx((math.pi / 2, 1, 0))
    assert odometry_increment((0, 0, 0), (0, 0, 0.3)) == pytest.approx((0, 0, 0.3))
    # backwards: negative translation, no half turns
    assert odometry_increment((0, 0, 0), (-0.5, 0, 0)) == pytest.approx((0, -0.5, 0))


def test_motion_matches_reference_and_composes():
    rng = np.random.default_rng(1)
    p = rng.uniform(-3, 3, (500, 3))
    normals = rng.standard_normal((500, 3))
    out = move_particles(p, (0.2, 0.5, -0.1), (0.01, 0.02, 0.03), normals)
    ref = naive.sample_odometry(p, 0.2, 0.5, -0.1, (0.01, 0.02, 0.03), normals)
    np.testing.assert_allclose(out, ref, atol=1e-12)
    # no noise: a particle at the odometry pose lands on the new odometry pose
    prev, now = np.array([1.0, 2.0, 0.3]), np.array([1.4, 2.3, 0.9])
    moved = sample_motion_odometry(prev[None], prev, now, (0, 0, 0, 0), rng)
    np.testing.assert_allclose(moved[0], now, atol=1e-12)


def test_motion_noise_statistics():
    p = np.zeros((20000, 3))
    moved = sample_motion_odometry(p, (0, 0, 0), (1, 0, 0), (0, 0.01, 0.04, 0), 3)
    # trans std = sqrt(0.04) = 0.2, rot std = sqrt(0.01) = 0.1 (rot1 and rot2)
    assert np.std(np.hypot(moved[:, 0], moved[:, 1])) == pytest.approx(0.2, rel=0.05)
    assert np.std(moved[:, 2]) == pytest.approx(0.1 * math.sqrt(2), rel=0.05)


def test_expected_exact_matches_sonar_module(world):
    poses = world.sample_free_poses(200, 0)
    sonar = SonarModel()
    np.testing.assert_allclose(
        expected_readings(world, poses, sonar),
        expected_ranges(world.sensed_obstacles, poses, sonar),
        atol=1e-12,
    )


def test_cone_table_entries_are_exact_cones(world):
    table = cone_table(world)
    one = SonarModel(sensors=[[0.0, 0.0, 0.0]])
    rng = np.random.default_rng(2)
    ny, nx, nb = table.table.shape
    for _ in range(40):
        i, j, b = rng.integers(ny), rng.integers(nx), rng.integers(nb)
        cx = table.origin[0] + (j + 0.5) * table.resolution
        cy = table.origin[1] + (i + 0.5) * table.resolution
        ref = expected_ranges(world, [cx, cy, b * 2 * math.pi / nb], one)[0, 0]
        assert table.table[i, j, b] == round(ref * 1000)


def test_fast_path_agrees_within_quantisation(world):
    poses = world.sample_free_poses(400, 3)
    exact = expected_readings(world, poses)
    fast = expected_readings(world, poses, table=cone_table(world))
    diff = np.abs(fast - exact)
    assert np.median(diff) < 0.02
    assert np.mean(diff < 0.1) > 0.9


def test_cone_table_is_reused_and_sized(world):
    t1 = cone_table(world)
    assert cone_table(world) is t1
    assert t1.table.dtype == np.uint16 and t1.nbytes == t1.table.size * 2


def test_innovation_weights_hand_computed():
    z = np.array([1.0, 2.0])
    zhat = np.array([[1.0, 2.0], [2.0, 2.0], [1.0, 1.0]])
    # d = 0, (1/1 + 0)/2 = 0.5, (0 + 1/2)/2 = 0.25
    w = np.array([1 + 1 / 3, math.exp(-0.5) + 1 / 3, math.exp(-0.25) + 1 / 3])
    np.testing.assert_allclose(paper.innovation_weights(z, zhat), w / w.sum())
    np.testing.assert_allclose(
        paper.innovation_weights(z, zhat), naive.paper_weights(z, zhat)
    )


def test_innovation_weight_is_weak():
    """A perfect particle outweighs one 70% off on every sonar by only ~2x."""
    z = np.full(8, 2.0)
    zhat = np.vstack([z, np.tile(1.7 * z, (299, 1))])
    w = paper.innovation_weights(z, zhat)
    ratio = w[0] / w[1]
    assert ratio == pytest.approx((1 + 1 / 300) / (math.exp(-0.7) + 1 / 300))
    assert ratio < 2.1


@pytest.mark.parametrize("exponent", [1.0, 0.2])
def test_beam_loglik_matches_reference(world, exponent):
    rng = np.random.default_rng(4)
    zhat = rng.uniform(0.1, 5.0, (50, 8))
    z = np.concatenate([rng.uniform(0.1, 4.9, 7), [5.0]])
    q = BeamParameters(exponent=exponent)
    out = BeamSensorModel(world, params=q).scan_log_likelihood(z, zhat) / exponent
    params = (q.z_hit, q.z_short, q.z_max, q.z_rand, q.sigma_hit, q.lambda_short)
    np.testing.assert_allclose(out, naive.beam_loglik(z, zhat, 5.0, params))


def test_beam_model_prefers_true_pose(world):
    pose = np.array([1.5, 1.0, 0.3])
    z = expected_readings(world, pose[None])[0]
    for fast in (False, True):
        model = BeamSensorModel(world, fast=fast)
        ll = model.log_likelihood(np.array([pose, pose + [0.5, 0.3, 0.4]]), z)
        assert ll[0] > ll[1]


def test_likelihood_field_exact_and_fast_match_reference(world):
    poses = world.sample_free_poses(100, 5)
    z = expected_readings(world, poses[:1])[0]
    exact = LikelihoodFieldSensorModel(world, fast=False)
    ref = naive.field_loglik(world, poses, exact.sonar.sensors, z, 5.0, 0.9, 0.1, 0.15)
    np.testing.assert_allclose(exact.log_likelihood(poses, z), ref, atol=1e-9)
    fast = LikelihoodFieldSensorModel(world, fast=True)
    assert np.corrcoef(fast.log_likelihood(poses, z), ref)[0, 1] > 0.95


class _Fixed:
    """A sensor model that returns given log-likelihoods."""

    def __init__(self, ll):
        self.ll = ll

    def log_likelihood(self, particles, z):
        return self.ll


def test_update_matches_reference(world):
    rng = np.random.default_rng(6)
    w0 = rng.random(100)
    w0 /= w0.sum()
    ll = rng.normal(-20, 5, 100)
    mcl = MCL(world, _Fixed(ll), n=100, rng=0)
    mcl.set_particles(mcl.particles, w0)
    log_mean = mcl.update(np.ones(8))
    ref_w, ref_mean, ref_ess = naive.update_weights(w0, ll)
    np.testing.assert_allclose(mcl.weights, ref_w)
    assert log_mean == pytest.approx(ref_mean)
    assert mcl.ess == pytest.approx(ref_ess)


def test_estimate_uses_circular_mean():
    p = np.array([[0.0, 0.0, math.pi - 0.1], [2.0, 4.0, -math.pi + 0.1]])
    est = paper.estimate(p, np.array([1.0, 1.0]))
    assert est[:2] == pytest.approx([1.0, 2.0])
    assert abs(abs(est[2]) - math.pi) < 1e-9
    est = paper.estimate(p, np.array([3.0, 1.0]))
    np.testing.assert_allclose(est, naive.pose_mean(p, np.array([3.0, 1.0])))
    rng = np.random.default_rng(12)
    p, w = rng.uniform(-3, 3, (1000, 3)), rng.random(1000)
    np.testing.assert_allclose(paper.estimate(p, w), naive.pose_mean(p, w), atol=1e-12)


def test_dispersion_index_and_resize_hand_computed():
    p = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]] * 5)
    # var_x = 1, var_y = 0; map 3 m x 4 m -> diagonal 5
    ip = paper.dispersion_index(p, (3.0, 4.0))
    assert ip == pytest.approx(0.2)
    assert paper.resize(300, ip, 1.0, floor=10) == int(300 * math.exp(-0.2)) == 245
    assert paper.resize(300, ip, 1.0, floor=280) == 280
    assert paper.resize(300, 0.0, 5.0) == 300
    assert paper.resize(40, 0.5, 1.0, floor=50) == 40  # never grows


def test_resamplers_match_searchsorted_reference():
    rng = np.random.default_rng(7)
    w = rng.random(64)
    positions = np.sort(rng.random(64))
    ref = naive.resample_positions(w, positions)
    np.testing.assert_array_equal(resampling._search(w, positions), ref)
    np.testing.assert_array_equal(
        systematic_resample(w, np.random.default_rng(3)),
        naive.resample_positions(w, (np.arange(64) + u_of(3)) / 64),
    )


def u_of(seed):
    """The first uniform a generator of ``seed`` draws."""
    return np.random.default_rng(seed).random()


def test_systematic_keeps_floor_or_ceil_copies():
    w = np.array([0.5, 0.25, 0.125, 0.0625, 0.0625])
    for seed in range(20):
        counts = np.bincount(systematic_resample(w, seed, 16), minlength=5)
        assert np.all(np.abs(counts - 16 * w) < 1)


def test_residual_keeps_integer_parts():
    w = np.array([0.55, 0.3, 0.15])
    counts = np.bincount(residual_resample(w, 0, 10), minlength=3)
    assert np.all(counts >= np.floor(10 * w)) and counts.sum() == 10


@pytest.mark.parametrize(
    "resampler", [multinomial_resample, stratified_resample, systematic_resample]
)
def test_resampling_is_unbiased(resampler):
    w = np.array([0.1, 0.2, 0.3, 0.4])
    rng = np.random.default_rng(8)
    counts = sum(np.bincount(resampler(w, rng, 100), minlength=4) for _ in range(400))
    np.testing.assert_allclose(counts / 40000, w, atol=0.01)


def test_resampling_variance_ordering():
    """Multinomial varies most, stratified less, systematic least."""
    w = np.array([0.1, 0.2, 0.3, 0.4])
    rng = np.random.default_rng(9)
    var = {}
    for f in (multinomial_resample, stratified_resample, systematic_resample):
        var[f] = np.var([np.sum(f(w, rng, 100) == 3) for _ in range(500)])
    assert var[multinomial_resample] > var[stratified_resample]
    assert var[stratified_resample] >= var[systematic_resample]
    assert var[multinomial_resample] == pytest.approx(100 * 0.4 * 0.6, rel=0.2)


def test_kld_bound_hand_computed():
    z = 2.3263478740408408  # 1 - delta = 0.99
    assert kld_bound_kernel(1, 0.05, z) == 1.0
    assert kld_bound_kernel(10, 0.05, z) == pytest.approx(naive.kld_bound(10, 0.05, z))
    # k = 2: 1/(2 eps) (1 - 2/9 + sqrt(2/9) z)^3
    a = 2 / 9
    assert kld_bound(2, 0.05, 0.01) == math.ceil(10 * (1 - a + math.sqrt(a) * z) ** 3)
    assert kld_bound(100) > kld_bound(10)


def test_kld_resample_adapts_to_spread(world):
    peaked = np.tile([[1.0, 1.0, 0.0]], (1000, 1))
    idx = kld_resample(peaked, np.ones(1000), world.bounds, 0, n_min=50, n_max=5000)
    assert len(idx) == 50
    spread = world.sample_free_poses(5000, 1)
    idx = kld_resample(spread, np.ones(5000), world.bounds, 0, n_min=50, n_max=5000)
    assert len(idx) > 1000


def test_check_particles_regenerates_with_small_weight(world):
    p = np.array([[1.0, 1.0, 0.0], [1.0, 2.5, 0.0], [-5.0, 1.0, 0.0], [5.0, 1.0, 1.0]])
    w = np.full(4, 0.25)
    out, w2, k = paper.check_particles(world, p, w, 0, regen_weight=0.1)
    assert k == 2
    assert np.all(paper.admissible(world, out))
    np.testing.assert_array_equal(out[[0, 3]], p[[0, 3]])
    assert w2[1] == pytest.approx(0.1 * w2[0]) and w2.sum() == pytest.approx(1)


def test_uniform_particles_cover_free_space(world):
    p, w = paper.uniform_particles(world, 2000, 0)
    assert np.all(paper.admissible(world, p))
    assert w.sum() == pytest.approx(1)
    assert p[:, 0].min() < 1.0 and p[:, 0].max() > 5.0


def test_kld_resample_matches_reference(world):
    from statistics import NormalDist

    rng = np.random.default_rng(5)
    for n, spread, n_min in ((2000, 0.1, 10), (2000, 3.0, 10), (500, 3.0, 300)):
        p = np.column_stack(
            [1.0 + spread * rng.random(n), 1.0 + spread / 3 * rng.random(n),
             rng.uniform(-np.pi, np.pi, n)]
        )  # fmt: skip
        w = rng.random(n)
        got = kld_resample(p, w, world.bounds, 7, n_min=n_min, n_max=5000)
        uniforms = np.random.default_rng(7).random(5000)
        z = NormalDist().inv_cdf(0.99)
        ref = naive.kld_draw(
            p, w, uniforms, world.bounds, 0.5, math.radians(15.0), 0.05, z, n_min
        )
        np.testing.assert_array_equal(got, ref)
