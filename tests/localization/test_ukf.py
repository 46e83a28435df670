"""UKF localization: the unscented transform, agreement with the EKF, consistency."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robotlib.localization.ekf import (
    ekf_predict,
    landmark_update,
    laser_update,
    nees,
    nis_band,
)
from robotlib.localization.ukf import (
    sigma_points,
    ukf_landmark_update,
    ukf_laser_update,
    ukf_predict,
)
from robotlib.mapping.drive import record_drive
from robotlib.mapping.ekfslam import (
    RangeBearingSensor,
    observe_landmarks,
    world_landmarks,
)
from robotlib.sensing.laser import LaserModel, expected_laser
from robotlib.world import load_world


def test_sigma_points_reproduce_the_mean_and_covariance():
    rng = np.random.default_rng(1)
    A = rng.normal(size=(4, 4))
    mu, P = rng.normal(size=4), A @ A.T
    X, wm, wc = sigma_points(mu, P)
    assert X.shape == (9, 4) and wm.sum() == pytest.approx(1.0)
    np.testing.assert_allclose(wm @ X, mu, atol=1e-12)
    D = X - mu
    np.testing.assert_allclose((D * wc[:, None]).T @ D, P, atol=1e-10)
    with pytest.raises(ValueError, match="semi-definite"):
        sigma_points(mu, -P)


def test_ukf_equals_the_ekf_when_the_models_are_nearly_linear():
    """Small uncertainty: the linearisation is exact to first order, so both agree."""
    mu, P = np.array([1.0, 2.0, 0.3]), np.diag([1e-6, 1e-6, 1e-7])
    o0, o1 = np.array([0.0, 0.0, 0.0]), np.array([0.2, 0.05, 0.1])
    alphas = (1e-4, 1e-4, 1e-4, 1e-4)
    me, Pe = ekf_predict(mu, P, o0, o1, alphas)
    mk, Pk = ukf_predict(mu, P, o0, o1, alphas)
    np.testing.assert_allclose(mk, me, atol=1e-6)
    np.testing.assert_allclose(Pk, Pe, rtol=0.02, atol=1e-12)

    lm = np.array([[4.0, 1.0], [2.0, 5.0], [-1.0, 3.0]])
    d = lm - mu[:2]
    z = np.column_stack([np.hypot(*d.T) + 0.01, np.arctan2(d[:, 1], d[:, 0]) - mu[2]])
    me, Pe, ne = landmark_update(mu, P * 100, z, lm, 0.05, 0.03)
    mk, Pk, nk = ukf_landmark_update(mu, P * 100, z, lm, 0.05, 0.03)
    assert np.abs(mk - me).max() < 0.01 * np.abs(me - mu).max()  # the same correction
    np.testing.assert_allclose(Pk, Pe, rtol=1e-3, atol=1e-3 * np.abs(Pe).max())
    assert nk == pytest.approx(ne, rel=1e-2)

    world, model = load_world("office"), LaserModel()
    pose = np.array([3.1, 2.2, 0.4])
    scan = expected_laser(world, pose + [0.003, -0.002, 0.001], model)[0]
    Pl = np.diag([1e-4, 1e-4, 1e-5])
    me, Pe, _, ue = laser_update(pose, Pl, scan, world, model, sigma=0.01)
    mk, Pk, _, uk = ukf_laser_update(pose, Pl, scan, world, model, sigma=0.01)
    assert abs(uk - ue) <= 1  # a beam near a corner may fall to either side
    np.testing.assert_allclose(mk, me, atol=1e-3)
    np.testing.assert_allclose(np.sqrt(np.diag(Pk)), np.sqrt(np.diag(Pe)), rtol=0.1)


def test_predict_matches_a_monte_carlo_of_the_motion_model():
    """A long increment from an uncertain heading (0.3 rad): mean and covariance."""
    rng = np.random.default_rng(0)
    mu0, P0 = np.array([1.0, 2.0, 0.3]), np.diag([0.01, 0.02, 0.1])
    o0, o1 = np.array([0.0, 0.0, 0.0]), np.array([0.8, 0.3, 0.6])
    alphas = (0.002, 0.005, 0.01, 0.0005)
    from robotlib.localization.motion import noise_std, odometry_increment

    inc = odometry_increment(o0, o1)
    std = noise_std(alphas, *inc)
    x = rng.multivariate_normal(mu0, P0, 200_000)
    n = rng.standard_normal((len(x), 3))
    h = x[:, 2] + inc[0] + std[0] * n[:, 0]
    t = inc[1] + std[1] * n[:, 1]
    y = np.column_stack([x[:, 0] + t * np.cos(h), x[:, 1] + t * np.sin(h),
                         h + inc[2] + std[2] * n[:, 2]])  # fmt: skip
    mk, Pk = ukf_predict(mu0, P0, o0, o1, alphas)
    me, Pe = ekf_predict(mu0, P0, o0, o1, alphas)
    m, C = y.mean(axis=0), np.cov(y.T)
    np.testing.assert_allclose(mk, m, atol=3e-3)
    np.testing.assert_allclose(Pk, C, atol=3e-3)
    # the curvature the linearisation drops: the UKF's moments are the nearer
    assert np.linalg.norm(mk - m) < 0.5 * np.linalg.norm(me - m)
    assert np.linalg.norm(Pk - C) < np.linalg.norm(Pe - C)


def _run(log, mu, P, laser, seed):
    rng = np.random.default_rng(seed)
    lms, sensor = world_landmarks(log.world), RangeBearingSensor()
    errs, nees_ = [], []
    for k in range(1, len(log)):
        mu, P = ukf_predict(mu, P, log.odometry[k - 1], log.odometry[k])
        if laser:
            mu, P, _, _ = ukf_laser_update(
                mu, P, log.laser[k], log.world, log.laser_model
            )
        else:
            ids, z = observe_landmarks(lms, log.truth[k], sensor, log.world, rng)
            mu, P, _ = ukf_landmark_update(
                mu, P, z, lms[ids], sensor.range_std, sensor.bearing_std
            )
        errs.append(math.hypot(mu[0] - log.truth[k, 0], mu[1] - log.truth[k, 1]))
        nees_.append(nees(mu, P, log.truth[k]))
    return np.array(errs), np.array(nees_)


@pytest.mark.slow
@pytest.mark.parametrize("laser", [False, True])
def test_ukf_tracks_the_office_and_is_not_overconfident(laser):
    log = record_drive("office", seed=3, every=5, laser=laser).every(2)
    P = np.diag([0.045, 0.045, 0.01])
    errs, ne = _run(log, log.truth[0] + np.array([0.2, -0.2, 0.05]), P, laser, 3)
    assert errs.mean() < 0.10
    assert np.mean(ne <= nis_band(3)[1]) >= 0.9


def test_laser_update_iterates_to_the_truth_where_one_unscented_step_does_not():
    """Office drive 10's first scan from (-0.33, -0.22, -0.08) off the truth.

    One unscented step (at 5 cm per beam, the earlier default, or at the
    sensor's 5.8 mm) ends 0.43 m off, its covariance sure of it; the iterated
    posterior linearisation lands within a centimetre, consistently.
    """
    log = record_drive("office", seed=10, every=5, laser=True)
    truth, scan = log.truth[0], log.laser[0]
    start = truth + np.random.default_rng(10).normal(size=3) * [0.3, 0.3, 0.1]
    P = np.diag([0.09, 0.09, 0.01])
    one, P1, _, _ = ukf_laser_update(
        start, P, scan, log.world, log.laser_model, iterations=1, refuse=0.0
    )
    assert math.hypot(*(one[:2] - truth[:2])) > 0.3
    assert nees(one, P1, truth) > nis_band(3)[1]
    mu, P2, _, used = ukf_laser_update(start, P, scan, log.world, log.laser_model)
    assert math.hypot(*(mu[:2] - truth[:2])) < 0.01 and abs(mu[2] - truth[2]) < 0.005
    assert used >= 10 and nees(mu, P2, truth) < nis_band(3)[1]
    with pytest.raises(ValueError, match="iterations"):
        ukf_laser_update(start, P, scan, log.world, log.laser_model, iterations=0)
