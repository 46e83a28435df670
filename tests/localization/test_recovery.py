"""Recovery from a kidnapping: augmented MCL's added particles and the mode estimate."""

import numpy as np
import pytest

from robotlib.localization import (
    MCL,
    AugmentedInjection,
    BeamSensorModel,
    expected_readings,
    mode_estimate,
)
from robotlib.localization.paper import estimate
from tests.worlds import door_corridor


@pytest.fixture(scope="module")
def world():
    return door_corridor()


def _cloud(rng, centre, n, std=0.1):
    return np.asarray(centre, float) + rng.standard_normal((n, 3)) * std


def test_mode_estimate_is_the_heavier_place_not_the_middle():
    rng = np.random.default_rng(0)
    here, there = _cloud(rng, (2.0, 2.0, 0.5), 600), _cloud(rng, (9.0, 4.0, -2.0), 400)
    p = np.vstack([here, there])
    w = np.ones(len(p))
    mode, mean = mode_estimate(p, w), estimate(p, w)
    assert np.hypot(*(mode[:2] - (2.0, 2.0))) < 0.05 and abs(mode[2] - 0.5) < 0.05
    assert np.hypot(*(mean[:2] - (2.0, 2.0))) > 2.5  # the mean: between the two
    w[600:] = 2.0  # the other place weighs more
    assert np.hypot(*(mode_estimate(p, w)[:2] - (9.0, 4.0))) < 0.05


def test_mode_estimate_of_one_cloud_is_its_mean():
    rng = np.random.default_rng(1)
    p = _cloud(rng, (3.0, 1.0, 3.1), 500)  # headings across the +-pi cut
    w = rng.random(500)
    np.testing.assert_allclose(mode_estimate(p, w), estimate(p, w), atol=1e-9)


class NeverResample:
    def indexes(self, mcl):
        return None


def _filter(world, injection):
    pose = np.array([2.0, 1.0, 0.0])
    mcl = MCL(
        world, BeamSensorModel(world, fast=True), resampling=NeverResample(),
        n=300, rng=3, init=pose, injection=injection,
    )  # fmt: skip
    here, far = expected_readings(world, np.array([pose, [5.0, 2.0, np.pi]]))
    mcl.step(pose, pose, here)  # the averages start at a scan that fits
    assert mcl.info.injected == 0
    return mcl, pose, far


def test_added_particles_come_on_a_step_that_does_not_resample(world):
    """A kidnapped filter's weights stay even; the particles come all the same."""
    inj = AugmentedInjection(alpha_fast=1.0, grow=2000, share=0.2)
    mcl, pose, far = _filter(world, inj)
    mcl.step(pose, pose, far)  # a scan from elsewhere: the likelihood drops
    k = mcl.info.injected
    assert mcl.info.resampled is False
    assert k == int(inj.probability * 2000) > 1000 and mcl.n == 300 + k
    assert mcl.weights.sum() == pytest.approx(1.0)
    assert mcl.weights[300:].sum() == pytest.approx(0.2)


def test_replacing_waits_for_a_resampling(world):
    inj = AugmentedInjection(alpha_fast=1.0)  # Thrun's: replace
    mcl, pose, far = _filter(world, inj)
    mcl.step(pose, pose, far)
    assert inj.probability > 0.5 and mcl.info.injected == 0 and mcl.n == 300


def test_estimator_must_be_known(world):
    with pytest.raises(ValueError, match="estimator"):
        MCL(world, BeamSensorModel(world, fast=True), estimator="median")
