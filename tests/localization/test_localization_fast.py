"""The fast MCL step: fused kernels, culled cone casts, chunked noise (same numbers)."""

import math

import numba
import numpy as np
import pytest

from robotlib.localization import (
    MCL,
    BeamParameters,
    BeamSensorModel,
    KLDResampling,
    PaperSensorModel,
    ThresholdResampling,
    _kernels,
    expected_readings,
    systematic_resample,
)
from robotlib.localization._kernels import chunked
from robotlib.localization.motion import NORMALS_CHUNK, standard_normals
from robotlib.sensing import SonarModel
from robotlib.sensing import _kernels as _raycast
from robotlib.world import load_world
from tests import naive_mcl as naive
from tests.worlds import door_corridor


@pytest.fixture(scope="module")
def world():
    """A 6 m x 2 m corridor with a door, a box and a slanted wall."""
    return door_corridor(extra=[(1.0, 1.6, 1.8, 1.9)])


def _full_cast(world, poses, sonar):
    out = np.empty((len(poses), len(sonar.sensors)))
    _raycast.expected_scan(
        poses, sonar.sensors, np.ascontiguousarray(world.obstacles),
        int(sonar.n_rays), float(sonar.cone), float(sonar.max_range),
        float(sonar.min_range), sonar.cos_specular, out,
    )  # fmt: skip
    return out


@pytest.mark.parametrize("name", ["corridor", "office"])
def test_block_cast_equals_full_cast(name):
    """Casting each cone against its nearby walls gives the very same readings."""
    world = load_world(name)
    poses = world.sample_free_poses(150, 1)
    xmin, ymin, xmax, ymax = world.bounds
    outside = [[xmin - 0.5, ymin + 1, 0.3], [xmax + 0.1, ymax - 1, 2.5]]
    poses = np.vstack([poses, outside])  # sensors off the block grid
    sonar = SonarModel()
    full = _full_cast(world, poses, sonar)
    np.testing.assert_array_equal(
        expected_readings(world, poses[:40], sonar), full[:40]
    )
    np.testing.assert_array_equal(expected_readings(world, poses, sonar), full)


@pytest.mark.parametrize(
    "sonar",
    [SonarModel(n_rays=1), SonarModel(cone=math.radians(200.0), n_rays=9),
     SonarModel(max_range=1.5, min_range=0.05)],
)  # fmt: skip
def test_block_cast_equals_full_cast_other_sonars(world, sonar):
    poses = world.sample_free_poses(100, 2)
    np.testing.assert_array_equal(
        expected_readings(world, poses, sonar), _full_cast(world, poses, sonar)
    )


def test_cone_walls_keeps_every_wall_a_ray_meets(world):
    """No wall that a ray of the cone meets within range is culled."""
    segs = np.ascontiguousarray(world.obstacles)
    rng = np.random.default_rng(3)
    cone, max_range, margin = math.radians(30.0), 2.5, 1e-6
    near = np.empty_like(segs)
    h = cone / 2 + margin
    for _ in range(300):
        sx, sy = rng.uniform(-0.2, 6.2), rng.uniform(-0.2, 3.2)
        sth = rng.uniform(-math.pi, math.pi)
        k = _raycast.cone_walls(
            sx, sy, math.cos(sth), math.sin(sth), math.cos(h), math.sin(h), segs,
            max_range, near,
        )  # fmt: skip
        kept = {tuple(w) for w in near[:k]}
        for a in sth + np.linspace(-cone / 2, cone / 2, 9):
            for seg in segs:
                if naive.ray_hit(sx, sy, a, seg) < max_range:
                    assert tuple(seg) in kept
        assert [tuple(w) for w in near[:k]] == [
            w for w in map(tuple, segs) if w in kept
        ]


def _models(world):
    return {
        "paper": PaperSensorModel(world, fast=True),
        "beam": BeamSensorModel(world, fast=True, params=BeamParameters(exponent=0.2)),
    }


@pytest.mark.parametrize("n", [300, 5000])
@pytest.mark.parametrize("kind", ["paper", "beam"])
def test_fused_step_equals_the_kernels_in_turn(world, kind, n):
    """One fused call = move, weigh, normalise, estimate: the same bits."""
    model = _models(world)[kind]
    rng = np.random.default_rng(4)
    p = world.sample_free_poses(n, 5)
    p[:50] = world.sample_free_poses(1, 6)  # some at the true pose: a peaked update
    w = rng.random(n)
    w /= w.sum()
    z = expected_readings(world, np.array([[1.5, 1.0, 0.2]]))[0]
    z[2] = 5.0
    motion = (0.1, 0.3, -0.05, 0.02, 0.03, 0.01)
    noise = rng.standard_normal((n, 3))
    moved, w2, log_mean, ess, est = model._step(p, w, motion, noise, z)
    ref = naive.fused_step(p, w, motion, noise, lambda q: model.log_likelihood(q, z))
    np.testing.assert_allclose(moved, ref[0], atol=1e-12)
    np.testing.assert_allclose(w2, ref[1], rtol=1e-12)
    assert log_mean == pytest.approx(ref[2], rel=1e-12)
    assert ess == pytest.approx(ref[3], rel=1e-12)
    np.testing.assert_allclose(est, ref[4], atol=1e-12)
    # and bit for bit what MCL.predict, update, estimate compute
    out = np.empty_like(p)
    _kernels.sample_odometry(p, *motion, noise, out)
    np.testing.assert_array_equal(moved, out)
    ll = model.log_likelihood(out, z)
    w3 = np.empty(n)
    assert _kernels.update_weights(w, ll, w3) == (log_mean, ess)
    np.testing.assert_array_equal(w2, w3)
    np.testing.assert_array_equal(est, _kernels.weighted_pose_mean(out, w3))


def test_beam_skip_leaves_the_likelihood_unchanged(world):
    """Leaving out hit terms below 2^-60 p_rand changes no bit."""
    model = _models(world)["beam"]
    p = world.sample_free_poses(2000, 7)
    z = np.array([0.2, 4.9, 1.0, 3.0, 0.5, 2.2, 5.0, 0.15])
    motion = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    noise = np.zeros((len(p), 3))
    w = np.full(len(p), 1 / len(p))
    m = model._model(z)
    table, where = model._where()
    skip = model._u2_skip
    assert 80 < skip < 120  # |z - zhat| > ~1.45 m with sigma 0.15 m
    u = (z - model.expected(p)) / 0.15
    assert np.mean(u[:, z < 5.0] ** 2 >= skip) > 0.1  # many terms are left out
    outs = []
    for u2 in (skip, math.inf):
        ow = np.empty(len(p))
        _kernels.beam_table_step(
            p, noise, motion, model.sonar.sensors, table, where, *m[:5],
            (*m[5:], 0.2, u2), w, np.empty_like(p), ow,
        )  # fmt: skip
        outs.append(ow)
    np.testing.assert_array_equal(outs[0], outs[1])
    assert _kernels.beam_skip(2.0, 0.0) == math.inf


def _run(world, make, steps=4, seed=1):
    mcl = make(world, seed)
    odo = [np.array([1.0, 1.0, 0.0]) + k * np.array([0.3, 0.0, 0.05]) for k in range(5)]
    z = expected_readings(world, np.array([[1.5, 1.0, 0.2]]))[0]
    ests = [mcl.step(odo[k], odo[k + 1], z).copy() for k in range(steps)]
    return np.array(ests), mcl.particles, mcl.weights


def _stepwise(world, make, steps=4, seed=1):
    """The same run with `predict`, `update`, `estimate`, `resample` in turn."""
    mcl = make(world, seed)
    odo = [np.array([1.0, 1.0, 0.0]) + k * np.array([0.3, 0.0, 0.05]) for k in range(5)]
    z = expected_readings(world, np.array([[1.5, 1.0, 0.2]]))[0]
    ests = []
    for k in range(steps):
        mcl.predict(odo[k], odo[k + 1])
        mcl.update(z)
        ests.append(mcl.estimate())
        mcl.resample()
    return np.array(ests), mcl.particles, mcl.weights


@pytest.mark.parametrize(
    "make",
    [
        lambda w, s: MCL.paper(w, n=300, fast=True, rng=s),
        lambda w, s: MCL(w, _models(w)["beam"], n=300, rng=s),
        lambda w, s: MCL(
            w, _models(w)["beam"], resampling=KLDResampling(n_max=6000), n=6000, rng=s
        ),
        lambda w, s: MCL(
            w,
            _models(w)["paper"],
            resampling=ThresholdResampling("systematic", 1.0),
            n=3 * NORMALS_CHUNK,
            rng=s,
        ),  # fmt: skip
    ],
    ids=["paper", "beam", "beam-kld-lut", "paper-chunked-noise"],
)
def test_mcl_step_equals_its_parts(world, make):
    for a, b in zip(_run(world, make), _stepwise(world, make), strict=True):
        np.testing.assert_array_equal(a, b)


def test_systematic_gather_matches_resampler():
    rng = np.random.default_rng(8)
    p = rng.uniform(-3, 3, (500, 3))
    w = rng.random(500) ** 4
    for n in (500, 123):
        u = np.random.default_rng(9).random()
        out = np.empty((n, 3))
        _kernels.systematic_gather(p, w, u, out)
        idx = systematic_resample(w, np.random.default_rng(9), n)
        np.testing.assert_array_equal(out, p[idx])
        np.testing.assert_array_equal(out, naive.systematic_gather(p, w, u, n))


def test_gather_in_pieces_matches_the_serial_walk():
    """`stepping._gather`'s pieces give `systematic_gather`'s rows, however cut."""
    from robotlib.localization import stepping

    rng = np.random.default_rng(4)
    p = rng.uniform(-3, 3, (997, 3))
    w = rng.random(997) ** 6
    w[100:400] = 0.0  # runs of empty weights: the walk's steps over them
    w[500] = 50.0  # one particle holding many positions, split between pieces
    for u in (0.0, 0.5, 0.999):
        ref = naive.systematic_gather(p, w, u, len(p))
        q = np.empty(len(p))
        chunked.cumulate(w, q)
        for pieces in (1, 2, 7, 997):
            out = np.full((len(p), 3), np.nan)
            for lo, hi in stepping.spans(len(p), pieces):
                chunked.gather_rows(p, q, u, lo, hi, out)
            np.testing.assert_array_equal(out, ref)
        new_p, new_w = np.empty((len(p), 3)), np.empty(len(p))
        stepping._gather(p, w, u, new_p, new_w)
        np.testing.assert_array_equal(new_p, ref)
        assert np.all(new_w == 1.0 / len(p))
    for w in (np.zeros(997), np.full(997, np.nan)):  # NaN quotients: all row 0
        ref = np.empty((len(p), 3))
        _kernels.systematic_gather(p, w, 0.5, ref)
        new_p, new_w = np.empty((len(p), 3)), np.empty(len(p))
        for pieces in (1, 3):
            q = np.empty(len(p))
            chunked.cumulate(w, q)
            for lo, hi in stepping.spans(len(p), pieces):
                chunked.gather_rows(p, q, 0.5, lo, hi, new_p)
            np.testing.assert_array_equal(new_p, ref)


def test_standard_normals_depend_on_rng_and_n_only():
    small = standard_normals(np.random.default_rng(1), 100)
    np.testing.assert_array_equal(
        small, np.random.default_rng(1).standard_normal((100, 3))
    )
    n = 2 * NORMALS_CHUNK + 17
    threads = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = standard_normals(np.random.default_rng(2), n)
    finally:
        numba.set_num_threads(threads)
    many = standard_normals(np.random.default_rng(2), n)
    np.testing.assert_array_equal(one, many)
    assert not np.array_equal(many, standard_normals(np.random.default_rng(3), n))
    # the chunks are distinct streams of standard normals
    c = NORMALS_CHUNK
    assert not np.array_equal(many[:17], many[c : c + 17])
    assert abs(many.mean()) < 0.01 and many.std() == pytest.approx(1.0, abs=0.01)
    rows = many.reshape(-1)
    assert abs(np.corrcoef(rows[:-1], rows[1:])[0, 1]) < 0.01


def test_large_filter_is_reproducible_whatever_the_threads(world):
    """Chunked noise over threads: the same run with 1 thread and with all."""

    def make(w, s):
        return MCL(w, _models(w)["beam"], n=3 * NORMALS_CHUNK, rng=s)

    threads = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = _run(world, make, steps=2)
    finally:
        numba.set_num_threads(threads)
    for a, b in zip(one, _run(world, make, steps=2), strict=True):
        np.testing.assert_array_equal(a, b)


def test_step_accepts_particles_set_from_outside(world):
    """Particles assigned as a strided view step like their contiguous copy."""
    results = []
    for strided in (False, True):
        mcl = MCL(world, _models(world)["beam"], n=200, rng=5)
        p = np.asfortranarray(world.sample_free_poses(200, 6))
        mcl.particles = p if strided else np.ascontiguousarray(p)
        mcl.weights = np.full(400, 1 / 200)[::2] if strided else np.full(200, 1 / 200)
        z = expected_readings(world, np.array([[1.5, 1.0, 0.2]]))[0]
        results.append(mcl.step([1, 1, 0], [1.3, 1, 0.05], z).copy())
        results.append(mcl.particles.copy())
    np.testing.assert_array_equal(results[0], results[2])
    np.testing.assert_array_equal(results[1], results[3])


@pytest.mark.parametrize(
    "make",
    [
        lambda w: MCL.paper(w, n=300, fast=True, rng=3),
        lambda w: MCL.paper(w, n=300, fast=False, rng=3),
        lambda w: MCL(w, _models(w)["beam"], n=300, rng=3),
    ],
    ids=["paper-fast", "paper-exact", "beam"],
)
def test_a_refused_scan_changes_nothing(world, make):
    """A NaN or misshapen scan raises before any draw or move: the next step is
    the one the filter would have taken without it.

    Twice: the first step checks the scan before its call; from the second
    on, the fast paths' set is the filter's own and their one call checks
    the readings itself. With refused odometry as well, the scan's error.
    """
    mcl, twin = make(world), make(world)
    odo0, odo1 = np.zeros(3), np.array([0.2, 0.0, 0.05])
    z = np.full(8, 2.0)
    for _ in range(2):
        for bad in (np.r_[z[:7], np.nan], z[:7], -z, np.r_[0.0, z[1:]]):
            message = "shape" if len(bad) != 8 else "positive"
            for odo in (odo0, [0.0, 0.0]):
                with pytest.raises(ValueError, match=message):
                    mcl.step(odo, odo1, bad)
        est = mcl.step(odo0, odo1, z)
        np.testing.assert_array_equal(est, twin.step(odo0, odo1, z))
        np.testing.assert_array_equal(mcl.particles, twin.particles)
        np.testing.assert_array_equal(mcl.weights, twin.weights)
        assert mcl.rng.bit_generator.state == twin.rng.bit_generator.state


def test_step_follows_models_replaced_between_steps(world):
    """A policy, motion model, generator or set replaced between steps is the
    one the next step uses: the same numbers as the parts in turn."""
    from robotlib.localization import OdometryMotionModel

    a, b = (MCL(world, _models(world)["beam"], n=300, rng=2) for _ in range(2))
    odo = [np.array([1.0, 1.0, 0.0]) + k * np.array([0.2, 0.0, 0.05]) for k in range(8)]
    z = expected_readings(world, np.array([[1.5, 1.0, 0.2]]))[0]
    changes = [
        {},
        {"resampling": ThresholdResampling("systematic", 1.0)},
        {"motion": OdometryMotionModel((0.01, 0.02, 0.03, 0.001))},
        {"rng": 9},
        {"particles": 11},
        {"resampling": KLDResampling(n_min=100, n_max=300)},
        {"sensor": _models(world)["paper"]},
    ]
    for k, change in enumerate(changes):
        for mcl in (a, b):
            for name, value in change.items():
                if name == "rng":
                    value = np.random.default_rng(value)
                if name == "particles":
                    mcl.set_particles(world.sample_free_poses(300, value))
                else:
                    setattr(mcl, name, value)
        est = a.step(odo[k], odo[k + 1], z)
        b.predict(odo[k], odo[k + 1])
        b.update(z)
        np.testing.assert_array_equal(est, b.estimate())
        b.resample()
        np.testing.assert_array_equal(a.particles, b.particles)
        np.testing.assert_array_equal(a.weights, b.weights)


@pytest.mark.parametrize("kind", ["paper", "beam"])
def test_one_call_step_refuses_a_scan_before_drawing(world, kind):
    """`chunked.beam_small` / `paper_small` return (nan, -1) for a reading not
    positive, having drawn and written nothing."""
    model = _models(world)[kind]
    mcl = MCL(world, model, resampling=ThresholdResampling("systematic", 1.0), n=50)
    words = mcl._pcg_words()[0]
    state = words.copy()
    p, w = mcl.particles, mcl.weights
    out = [np.full(s, 7.0) for s in ((50, 3), (50, 3), 50, (50, 3), 50, 3)]
    for bad in (np.nan, 0.0, -1.0):
        z = np.r_[np.full(7, 2.0), bad]
        args = (words, True, p, w, out[0])
        if kind == "beam":
            q = model.params
            sensors, table, where, (beam, _) = model._consts(q)
            res = chunked.beam_small(
                *args, sensors, table, z, np.exp(-q.lambda_short * z),
                *model._norms, 0.1, 0.2, 0.0, 0.01, 0.01, 0.01, *where, *beam, 0.0,
                *out[1:],
            )  # fmt: skip
        else:
            sensors, table, where, _ = model._consts()
            res = chunked.paper_small(
                *args, sensors, table, z, 0.1, 0.2, 0.0, 0.01, 0.01, 0.01, *where,
                1 / 50, 0.0, *out[1:],
            )  # fmt: skip
        assert math.isnan(res[0]) and res[1] == -1.0
        np.testing.assert_array_equal(words, state)
        assert all(np.all(a == 7.0) for a in out)
        with pytest.raises(ValueError, match="positive"):
            model._small(p, w, (0.1, 0.2, 0.0, 0.01, 0.01, 0.01), out[0], z, 0.0,
                         None, words)  # fmt: skip
        np.testing.assert_array_equal(words, state)
