"""`MCL.step`: the fused kernels against the NumPy path, and the filter's contract.

The fused step on a cone table (`robotlib.localization._kernels.steps`)
must compute what `predict`, `update` and `estimate` compute in NumPy from
the same draws: the NumPy path is the reference (as `tests/naive_mcl.py`).
"""

import numpy as np
import pytest

from robotlib.localization import (
    MCL,
    BeamParameters,
    BeamSensorModel,
    PaperSensorModel,
    ThresholdResampling,
)
from robotlib.localization.motion import PARALLEL_MIN
from tests import naive_mcl as naive
from tests.worlds import door_corridor


@pytest.fixture(scope="module")
def world():
    return door_corridor()


class NumPyOnly:
    """The same model seen through `log_likelihood` alone: no fused kernel."""

    def __init__(self, model):
        self.model = model

    def log_likelihood(self, particles, z):
        return self.model.log_likelihood(particles, z)


def _models(world):
    return {
        "paper": PaperSensorModel(world, fast=True),
        "beam": BeamSensorModel(world, fast=True),
        "beam-tempered": BeamSensorModel(
            world, fast=True, params=BeamParameters(exponent=0.2)
        ),
    }


def _scan(world, pose):
    from robotlib.localization import expected_readings

    z = expected_readings(world, np.asarray(pose, float)[None])[0]
    z[5] = 5.0  # a max-range reading
    return z


@pytest.mark.parametrize("name", ["paper", "beam", "beam-tempered"])
@pytest.mark.parametrize("n", [300, PARALLEL_MIN + 7])
def test_fused_step_is_the_numpy_step(world, name, n):
    model = _models(world)[name]
    fused = MCL(world, model, n=n, rng=4, resampling=ThresholdResampling())
    plain = MCL(world, NumPyOnly(model), n=n, rng=4, resampling=ThresholdResampling())
    assert fused._fused is not None and plain._fused is None
    odo = np.array([1.0, 1.0, 0.0])
    for k in range(3):
        nxt = odo + [0.3, 0.05, 0.1]
        z = _scan(world, [1.3 + 0.3 * k, 1.0, 0.1 * k])
        a = fused.step(odo, nxt, z)
        b = plain.step(odo, nxt, z)
        np.testing.assert_allclose(a, b, atol=1e-9)
        np.testing.assert_allclose(fused.particles, plain.particles, atol=1e-9)
        np.testing.assert_allclose(fused.weights, plain.weights, rtol=1e-9)
        assert fused.info.ess == pytest.approx(plain.info.ess, rel=1e-9)
        assert fused.info.log_mean_likelihood == pytest.approx(
            plain.info.log_mean_likelihood, rel=1e-9
        )
        odo = nxt


@pytest.mark.parametrize("name", ["paper", "beam"])
def test_fused_kernel_matches_reference_and_threads_change_no_bit(world, name):
    model = _models(world)[name]
    serial, threaded = model.fused
    rng = np.random.default_rng(2)
    n = 2000
    p = world.sample_free_poses(n, rng)
    w = rng.random(n)
    w /= w.sum()
    normals = rng.standard_normal((n, 3))
    motion = (0.1, 0.4, -0.05, 0.01, 0.02, 0.01)
    z = _scan(world, [2.0, 1.0, 0.0])
    outs = []
    for kernel in (serial, threaded):
        out = (np.empty((n, 3)), np.empty(n), np.empty(3))
        lm, ess = kernel(p, w, normals, *motion, *model.fused_arguments(z), *out)
        outs.append((*out, lm, ess))
    for a, b in zip(*outs, strict=True):
        np.testing.assert_array_equal(a, b)
    ref = naive.fused_step(
        p, w, motion, normals, lambda moved: model.log_likelihood(moved, z)
    )
    moved, weights, est, log_mean, ess = outs[0]
    np.testing.assert_allclose(moved, ref[0], atol=1e-12)
    np.testing.assert_allclose(weights, ref[1], rtol=1e-9)
    assert log_mean == pytest.approx(ref[2], rel=1e-9)
    assert ess == pytest.approx(ref[3], rel=1e-9)
    np.testing.assert_allclose(est, ref[4], atol=1e-9)


@pytest.mark.parametrize("make", [MCL.best, MCL.paper])
def test_a_refused_scan_changes_nothing(world, make):
    mcl = make(world, rng=3, n=500)
    before = (mcl.particles.copy(), mcl.weights.copy(), mcl.rng.random())
    mcl = make(world, rng=3, n=500)
    odo = np.array([1.0, 1.0, 0.0])
    for bad in (np.full(8, np.nan), -np.ones(8), np.ones(7), np.zeros(8)):
        with pytest.raises(ValueError):
            mcl.step(odo, odo + [0.1, 0, 0], bad)
    np.testing.assert_array_equal(mcl.particles, before[0])
    np.testing.assert_array_equal(mcl.weights, before[1])
    assert mcl.rng.random() == before[2]


@pytest.mark.parametrize("make", [MCL.best, MCL.paper])
def test_the_same_seed_gives_the_same_numbers(world, make):
    runs = []
    for _ in range(2):
        mcl = make(world, rng=8, n=3000)
        odo = np.array([1.0, 1.0, 0.0])
        ests = []
        for k in range(4):
            nxt = odo + [0.25, 0.0, 0.05]
            ests.append(mcl.step(odo, nxt, _scan(world, [1.25 + 0.25 * k, 1, 0])))
            odo = nxt
        runs.append((np.array(ests), mcl.particles.copy(), mcl.weights.copy()))
    for a, b in zip(*runs, strict=True):
        np.testing.assert_array_equal(a, b)


def test_models_replaced_between_steps_are_used(world):
    mcl = MCL(world, BeamSensorModel(world, fast=True), n=300, rng=0)
    assert mcl._fused is not None
    mcl.sensor = NumPyOnly(mcl.sensor)
    assert mcl._fused is None
    odo = np.array([1.0, 1.0, 0.0])
    mcl.step(odo, odo + [0.2, 0, 0], _scan(world, [1.2, 1.0, 0.0]))
    assert mcl.info.n_particles == 300


def test_particles_set_from_outside(world):
    mcl = MCL.best(world, rng=1, n=400)
    p = np.asfortranarray(world.sample_free_poses(400, 1))
    mcl.set_particles(p, np.arange(1, 401))
    assert mcl.weights.sum() == pytest.approx(1)
    odo = np.array([1.0, 1.0, 0.0])
    est = mcl.step(odo, odo + [0.2, 0, 0], _scan(world, [1.2, 1.0, 0.0]))
    assert np.all(np.isfinite(est))
    with pytest.raises(ValueError):
        mcl.set_particles(np.zeros((4, 2)))


class _Constant:
    def __init__(self, value):
        self.value = value

    def log_likelihood(self, particles, z):
        return np.full(len(particles), self.value)


def test_a_model_giving_nan_is_refused_plainly(world):
    mcl = MCL(world, _Constant(np.nan), n=50, rng=0)
    odo = np.array([1.0, 1.0, 0.0])
    with pytest.raises(ValueError, match="NaN"):
        mcl.step(odo, odo + [0.1, 0, 0], np.ones(8))


@pytest.mark.parametrize("fused", [False, True])
def test_a_scan_no_particle_fits_keeps_the_weights(world, fused):
    model = _Constant(-np.inf)
    mcl = MCL(world, model, n=50, rng=0, resampling=ThresholdResampling(threshold=0))
    w = np.random.default_rng(1).random(50)
    mcl.set_particles(mcl.particles, w)
    if fused:  # the kernel's own guard, called directly
        beam = BeamSensorModel(world, fast=True, params=BeamParameters(z_max=0.0))
        serial, _ = beam.fused
        z = np.full(8, 5.0)  # max readings, which z_max = 0 makes impossible
        out = (np.empty((50, 3)), np.empty(50), np.empty(3))
        args = (mcl.particles, mcl.weights, np.zeros((50, 3)), 0, 0, 0, 0, 0, 0)
        log_mean, _ = serial(*args, *beam.fused_arguments(z), *out)
        np.testing.assert_allclose(out[1], mcl.weights)
    else:
        odo = np.array([1.0, 1.0, 0.0])
        mcl.step(odo, odo, np.ones(8))
        np.testing.assert_allclose(mcl.weights, w / w.sum())
        log_mean = mcl.info.log_mean_likelihood
    assert log_mean == -np.inf
