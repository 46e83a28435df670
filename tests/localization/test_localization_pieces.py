"""The MCL pieces against hand-computed cases and the NumPy references."""

import math

import numpy as np
import pytest

from robotlib.localization import (
    BeamParameters,
    BeamSensorModel,
    LikelihoodFieldSensorModel,
    PaperSensorModel,
    _kernels,
    cone_table,
    expected_readings,
    kld_bound,
    kld_resample,
    multinomial_resample,
    odometry_increment,
    paper,
    residual_resample,
    sample_motion_odometry,
    stratified_resample,
    systematic_resample,
)
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


def test_motion_kernel_matches_numpy_and_compose():
    rng = np.random.default_rng(1)
    p = rng.uniform(-3, 3, (500, 3))
    normals = rng.standard_normal((500, 3))
    for kernel in (_kernels.sample_odometry, _kernels.sample_odometry_parallel):
        out = np.empty_like(p)
        kernel(p, 0.2, 0.5, -0.1, 0.01, 0.02, 0.03, normals, out)
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
        expected_ranges(world, poses, sonar),
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


def test_beam_loglik_matches_reference():
    rng = np.random.default_rng(4)
    zhat = rng.uniform(0.1, 5.0, (50, 8))
    z = np.concatenate([rng.uniform(0.1, 4.9, 7), [5.0]])
    q = BeamParameters()
    out = np.empty(50)
    _kernels.beam_loglik(
        z,
        zhat,
        5.0,
        q.z_hit,
        q.z_short,
        q.z_max,
        q.z_rand,
        q.sigma_hit,
        q.lambda_short,
        out,
    )
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


def test_update_weights_matches_reference():
    rng = np.random.default_rng(6)
    w0 = rng.random(100)
    w0 /= w0.sum()
    ll = rng.normal(-20, 5, 100)
    out = np.empty(100)
    log_mean, ess = _kernels.update_weights(w0, ll, out)
    ref_w, ref_mean, ref_ess = naive.update_weights(w0, ll)
    np.testing.assert_allclose(out, ref_w)
    assert log_mean == pytest.approx(ref_mean)
    assert ess == pytest.approx(ref_ess)
    # the parallel form gives the same bits (its sums are serial)
    out2 = np.empty(100)
    assert _kernels.update_weights_parallel(w0, ll, out2) == (log_mean, ess)
    np.testing.assert_array_equal(out2, out)


def test_estimate_uses_circular_mean():
    p = np.array([[0.0, 0.0, math.pi - 0.1], [2.0, 4.0, -math.pi + 0.1]])
    est = paper.estimate(p, np.array([1.0, 1.0]))
    assert est[:2] == pytest.approx([1.0, 2.0])
    assert abs(abs(est[2]) - math.pi) < 1e-9
    est = paper.estimate(p, np.array([3.0, 1.0]))
    np.testing.assert_allclose(est, naive.pose_mean(p, np.array([3.0, 1.0])))
    rng = np.random.default_rng(12)
    p, w = rng.uniform(-3, 3, (1000, 3)), rng.random(1000)
    serial = _kernels.weighted_pose_mean(p, w)
    np.testing.assert_allclose(serial, naive.pose_mean(p, w), atol=1e-12)
    np.testing.assert_array_equal(_kernels.weighted_pose_mean_parallel(p, w), serial)


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
    a = np.empty(64, dtype=np.int64)
    b = np.empty(64, dtype=np.int64)
    _kernels.search_indexes(_kernels.cumulative(w), positions, a)
    _kernels.sorted_indexes(_kernels.cumulative(w), positions, b)
    ref = naive.resample_positions(w, positions)
    np.testing.assert_array_equal(a, ref)
    np.testing.assert_array_equal(b, ref)


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
    assert _kernels.kld_bound(1, 0.05, z) == 1.0
    assert _kernels.kld_bound(10, 0.05, z) == pytest.approx(
        naive.kld_bound(10, 0.05, z)
    )
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


def test_cone_table_by_blocks_equals_one_block(world):
    """Pruning walls per block of cells leaves the table unchanged."""
    table = cone_table(world)
    s = table.sonar
    whole = np.empty_like(table.table)
    _kernels.build_cone_table(
        np.ascontiguousarray(world.obstacles),
        table.origin[0],
        table.origin[1],
        table.resolution,
        table.n_bins,
        1,
        int(s.n_rays),
        float(s.cone),
        float(s.max_range),
        float(s.min_range),
        s.cos_specular,
        1 << 20,
        whole,
    )
    np.testing.assert_array_equal(whole, table.table)
    # and small blocks (walls pruned hard: 3 m range) agree with one block too
    short = SonarModel(max_range=3.0)
    a = np.empty((30, 60, 72), dtype=np.uint16)
    b = np.empty_like(a)
    for block, out in ((4, a), (1 << 20, b)):
        _kernels.build_cone_table(
            np.ascontiguousarray(world.obstacles), 0.0, 0.0, 0.1, 72, 1, 7,
            float(short.cone), 3.0, 0.1, short.cos_specular, block, out,
        )  # fmt: skip
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("exponent", [1.0, 0.2])
def test_fused_table_models_match_lookup_then_model(world, exponent):
    poses = world.sample_free_poses(300, 11)
    z = expected_readings(world, poses[:1])[0]
    z[3] = 5.0  # a max reading
    beam = BeamSensorModel(world, fast=True, params=BeamParameters(exponent=exponent))
    q = beam.params
    zhat = beam.expected(poses)
    ref = np.empty(len(poses))
    _kernels.beam_loglik(
        z, zhat, 5.0, q.z_hit, q.z_short, q.z_max, q.z_rand, q.sigma_hit,
        q.lambda_short, ref,
    )  # fmt: skip
    np.testing.assert_allclose(
        beam.log_likelihood(poses, z), exponent * ref, atol=1e-12
    )
    t = beam.table
    for kernel in (_kernels.beam_table_loglik, _kernels.beam_table_loglik_parallel):
        out = np.empty(len(poses))
        kernel(
            poses, t.sonar.sensors, t.table, t.origin[0], t.origin[1],
            1 / t.resolution, z, np.exp(-q.lambda_short * z), z >= 5.0 - 1e-3,
            *beam._norms, q.z_max, q.z_rand / 5.0, 1 / q.sigma_hit, exponent, out,
        )  # fmt: skip
        np.testing.assert_allclose(out, exponent * ref, atol=1e-12)
    # many particles: one model table per scan, then lookups; the same numbers
    model = (
        z, np.exp(-q.lambda_short * z), z >= 5.0 - 1e-3, *beam._norms, q.z_max,
        q.z_rand / 5.0, 1 / q.sigma_hit,
    )  # fmt: skip
    lut = np.empty((8, len(beam._norms[0])))
    _kernels.beam_scan_lut(*model, lut)
    via_lut = np.empty(len(poses))
    _kernels.lut_table_loglik_parallel(
        poses, t.sonar.sensors, t.table, t.origin[0], t.origin[1],
        1 / t.resolution, lut, exponent, via_lut,
    )  # fmt: skip
    np.testing.assert_array_equal(via_lut, out)
    paper_model = PaperSensorModel(world, fast=True)
    for kernel in (_kernels.paper_table_loglik, _kernels.paper_table_loglik_parallel):
        out = np.empty(len(poses))
        kernel(
            poses, t.sonar.sensors, t.table, t.origin[0], t.origin[1],
            1 / t.resolution, z, 1 / len(poses), out,
        )  # fmt: skip
        np.testing.assert_allclose(
            out, np.log(naive.paper_weights_unnormalised(z, zhat)), atol=1e-12
        )
    np.testing.assert_array_equal(paper_model.log_likelihood(poses, z), out)
