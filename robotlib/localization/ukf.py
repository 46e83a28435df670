"""UKF localization: the EKF's Gaussian belief, without Jacobians.

The belief is a mean ``mu = (x, y, theta)`` and a covariance ``P`` (3, 3),
as in the EKF. Instead of linearising, the unscented transform pushes
``2 n + 1`` sigma points (`sigma_points`, the scaled points of Julier and
Uhlmann with Wan and van der Merwe's weights) through the motion or the
measurement model and takes the weighted mean and covariance of what comes
out (Probabilistic Robotics, table 7.4):

- `ukf_predict`: the odometry motion model of `robotlib.localization.motion`
  on the pose augmented with the increment's noise ``(rot1, trans, rot2)``
  (``n = 6``);
- `ukf_landmark_update`: range and bearing to landmarks of known identity;
- `ukf_laser_update`: a subset of laser beams against the map's walls, each
  sigma point's ranges cast exactly (`robotlib.sensing.laser.expected_laser`):
  a beam past a corner for some of the points shows as a large predicted
  spread instead of a huge finite-difference slope.

Angles (the heading, bearings) are averaged on the circle and their
differences wrapped. Like the EKF, the belief is unimodal: no global
localization, no recovery from a kidnapping without identities.

Imports numpy, scipy's chi-square quantile, the world's angle wrap, the
laser model, the motion model and the EKF's update and map cost; never
plots.
"""

from __future__ import annotations

import math

import numpy as np

from ..sensing.laser import LaserModel, expected_laser
from ..world import wrap_angle
from .ekf import _accepted, _belief, _laser_inputs, _update
from .motion import DEFAULT_ALPHAS, noise_std, odometry_increment

__all__ = [
    "sigma_points",
    "ukf_predict",
    "ukf_update",
    "ukf_landmark_update",
    "ukf_laser_update",
]

ALPHA, BETA = 1.0, 2.0
"""The unscented transform's spread and weights (``alpha = 1`` with ``kappa =
3 - n``: points at ``sqrt(3)`` standard deviations, which matches a
Gaussian's fourth moment; ``beta = 2``: optimal for a Gaussian)."""


def sigma_points(
    mu, P, alpha: float = ALPHA, beta: float = BETA, kappa: float | None = None
):
    """Return the scaled sigma points of a Gaussian and their weights.

    Parameters
    ----------
    mu : array_like, shape (n,)
    P : array_like, shape (n, n)
        Symmetric positive semi-definite.
    alpha, beta : float
    kappa : float, optional
        ``lambda = alpha**2 (n + kappa) - n``; the points are ``mu`` and
        ``mu +- columns of sqrt((n + lambda) P)`` (default ``3 - n``).

    Returns
    -------
    X : numpy.ndarray, shape (2 n + 1, n)
    wm, wc : numpy.ndarray, shape (2 n + 1,)
        Weights of the mean and of the covariance.
    """
    mu = np.asarray(mu, dtype=float)
    n = len(mu)
    kappa = 3.0 - n if kappa is None else float(kappa)
    lam = alpha**2 * (n + kappa) - n
    if n + lam <= 0:
        raise ValueError("alpha and kappa must make n + lambda positive")
    P = 0.5 * (np.asarray(P, dtype=float) + np.asarray(P, dtype=float).T)
    w, V = np.linalg.eigh((n + lam) * P)  # a square root that tolerates a rank loss
    if w.min() < -1e-9 * max(1.0, abs(w.max())):
        raise ValueError("P must be positive semi-definite")
    S = V * np.sqrt(np.clip(w, 0.0, None))
    X = np.vstack([mu, mu + S.T, mu - S.T])
    wm = np.full(2 * n + 1, 0.5 / (n + lam))
    wm[0] = lam / (n + lam)
    wc = wm.copy()
    wc[0] += 1.0 - alpha**2 + beta
    return X, wm, wc


def _mean(Y, wm, angular):
    """Weighted mean of the rows of ``Y``, the ``angular`` columns on the circle."""
    m = wm @ Y
    for j in angular:
        m[j] = math.atan2(float(wm @ np.sin(Y[:, j])), float(wm @ np.cos(Y[:, j])))
    return m


def _deviations(Y, m, angular):
    D = Y - m
    for j in angular:
        D[:, j] = wrap_angle(D[:, j])
    return D


def ukf_predict(mu, P, odo_prev, odo_now, alphas=DEFAULT_ALPHAS):
    """Predict the belief through one odometry increment (unscented).

    Parameters
    ----------
    mu : array_like, shape (3,)
        Mean pose, m and rad.
    P : array_like, shape (3, 3)
        Its covariance.
    odo_prev, odo_now : array_like, shape (3,)
        Successive odometry poses.
    alphas : tuple of float
        The motion model's ``alpha1..alpha4``.

    Returns
    -------
    mu, P : numpy.ndarray, shapes (3,) and (3, 3)
    """
    mu, P = _belief(mu, P)
    inc = np.asarray(odometry_increment(odo_prev, odo_now), dtype=float)
    std = np.asarray(noise_std(alphas, *inc), dtype=float)
    Pa = np.zeros((6, 6))
    Pa[:3, :3], Pa[3:, 3:] = P, np.diag(np.square(std))
    X, wm, wc = sigma_points(np.concatenate([mu, inc]), Pa)
    h = X[:, 2] + X[:, 3]
    Y = np.column_stack(
        [
            X[:, 0] + X[:, 4] * np.cos(h),
            X[:, 1] + X[:, 4] * np.sin(h),
            wrap_angle(h + X[:, 5]),
        ]
    )
    m = _mean(Y, wm, (2,))
    D = _deviations(Y, m, (2,))
    P = (D * wc[:, None]).T @ D
    return m, 0.5 * (P + P.T)


def ukf_update(mu, P, measure, z, R, angular=(), select=None):
    """Update the belief with a reading through the unscented transform.

    Parameters
    ----------
    mu, P : array_like, shapes (3,) and (3, 3)
        The belief.
    measure : callable
        ``measure(poses (K, 3)) -> (K, m)``: the expected reading at each pose.
    z : array_like, shape (m,)
        The reading.
    R : array_like, shape (m, m)
        Its noise covariance.
    angular : sequence of int
        Components of the reading that are angles (averaged on the circle,
        innovations wrapped).
    select : callable, optional
        ``select(Z (2n+1, m), zhat (m,), nu (m,), S (m, m)) -> bool mask (m,)``:
        the components to use (a gate); None uses them all.

    Returns
    -------
    mu, P : numpy.ndarray
    nis : float
        The used innovation's normalised squared size (0 when none is used).
    used : int
        Components used.
    """
    mu, P = _belief(mu, P)
    z = np.asarray(z, dtype=float).reshape(-1)
    R = np.asarray(R, dtype=float).reshape(len(z), len(z))
    X, wm, wc = sigma_points(mu, P)
    Z = np.asarray(measure(X), dtype=float).reshape(len(X), len(z))
    zhat = _mean(Z, wm, angular)
    DZ, DX = _deviations(Z, zhat, angular), _deviations(X, mu, (2,))
    S = (DZ * wc[:, None]).T @ DZ + R
    C = (DX * wc[:, None]).T @ DZ
    nu = z - zhat
    for j in angular:
        nu[j] = wrap_angle(nu[j])
    ok = (
        np.ones(len(z), dtype=bool)
        if select is None
        else np.asarray(select(Z, zhat, nu, S))
    )
    if not ok.any():
        return mu, P, 0.0, 0
    S, C, nu = S[np.ix_(ok, ok)], C[:, ok], nu[ok]
    K = np.linalg.solve(S, C.T).T
    mu = mu + K @ nu
    mu[2] = wrap_angle(mu[2])
    P = P - K @ S @ K.T
    nis = float(nu @ np.linalg.solve(S, nu))
    return mu, 0.5 * (P + P.T), nis, int(ok.sum())


def ukf_landmark_update(mu, P, z, landmarks, range_std: float, bearing_std: float):
    """Update the belief with range-bearing readings of known landmarks.

    The arguments and results are those of
    `robotlib.localization.ekf.landmark_update`: ``z`` (k, 2) ranges (m) and
    bearings (rad), ``landmarks`` (k, 2); returns ``mu, P, nis``.
    """
    mu, P = _belief(mu, P)
    z = np.asarray(z, dtype=float).reshape(-1, 2)
    lm = np.asarray(landmarks, dtype=float).reshape(-1, 2)
    if len(z) != len(lm):
        raise ValueError(f"{len(z)} readings but {len(lm)} landmarks")
    if len(z) == 0:
        return mu, P, 0.0

    def measure(X):
        dx = lm[None, :, 0] - X[:, None, 0]
        dy = lm[None, :, 1] - X[:, None, 1]
        b = wrap_angle(np.arctan2(dy, dx) - X[:, None, 2])
        return np.stack([np.hypot(dx, dy), b], axis=2).reshape(len(X), -1)

    R = np.diag(np.tile([range_std**2, bearing_std**2], len(z)))
    angular = tuple(range(1, 2 * len(z), 2))
    mu, P, nis, _ = ukf_update(mu, P, measure, z.ravel(), R, angular)
    return mu, P, nis


def ukf_laser_update(
    mu,
    P,
    scan,
    walls,
    model: LaserModel | None = None,
    beams=None,
    sigma: float | None = None,
    gate: float = 2.0,
    iterations: int = 10,
    refuse: float = 1e-3,
):
    """Update the belief with laser beams against the map's walls (unscented).

    The arguments and results are those of
    `robotlib.localization.ekf.laser_update`, and so is the cause of their
    care: a range is far from linear over a prior's few centimetres. One
    unscented step spreads its sigma points over the prior and, at the
    sensor's 5.8 mm, trusts a fit through points that reach other walls.
    This is the iterated posterior linearisation (Garcia-Fernandez, Svensson,
    Morelande and Sarkka 2015): at each iterate the sigma points of the
    current posterior give a linear fit of the ranges, ``z ~ A x + b``, and
    its residual covariance ``Omega`` (the nonlinearity over that spread);
    the prior is updated with the fit, its noise ``sigma**2 + Omega``, and
    the result is the next iterate, until it moves less than 1 um or 1 urad.
    A beam is used only if it and its expectation at every sigma point are
    echoes (below the maximum range) and its innovation is within ``gate``
    predicted standard deviations. The update is refused (the prior kept) as
    the EKF's is: no beam left, a worse fit of the map than the prior's mean,
    or an NIS beyond the chi-square's ``refuse`` tail.
    """
    mu, P, model, zb, beams, sigma = _laser_inputs(
        mu, P, scan, model, beams, sigma, iterations
    )
    x, Px, fit, cap = mu, P, None, None
    for _ in range(iterations):
        X, wm, wc = sigma_points(x, Px)
        Z = expected_laser(walls, X, model)[:, beams]
        zhat = wm @ Z
        DZ, DX = Z - zhat, _deviations(X, x, (2,))
        A = np.linalg.solve(Px, (DX * wc[:, None]).T @ DZ).T  # (beams, 3)
        omega = (DZ * wc[:, None]).T @ DZ - A @ Px @ A.T
        off = mu - x
        off[2] = wrap_angle(off[2])
        nu = zb - zhat - A @ off
        R = omega + np.eye(len(beams)) * sigma**2
        spread = np.sqrt(np.einsum("bi,ij,bj->b", A, P, A) + np.diag(R))
        echo = (Z < model.max_range).all(axis=0) & (zb < model.max_range)
        if cap is None:  # the robust cost's cut: the gate about the prior
            cap = np.where(echo, gate * spread, 0.0)
        ok = echo & (np.abs(nu) <= gate * spread)
        if not ok.any():  # no beam agrees with this iterate: it went astray
            return mu, P, 0.0, 0
        fit = _update(mu, P, nu[ok], A[ok], R[np.ix_(ok, ok)])
        step = fit[0] - x
        step[2] = wrap_angle(step[2])
        x, Px = fit[0], fit[1]
        if np.abs(step).max() < 1e-6:
            break
    used = int(ok.sum())
    return _accepted(
        fit, used, mu, P, walls, zb, model, beams, sigma, cap, iterations > 1, refuse
    )
