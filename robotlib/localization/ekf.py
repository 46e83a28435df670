"""EKF localization: a Gaussian belief over the pose, on landmarks or the laser.

The belief is a mean ``mu = (x, y, theta)`` and a covariance ``P`` (3, 3).

- `ekf_predict`: the odometry motion model of `robotlib.localization.motion`
  (``rot1, trans, rot2`` with the alphas' variances), linearised: ``P <- G P
  G^T + V M V^T`` with ``G`` the Jacobian wrt the pose and ``V`` wrt the
  increment (Probabilistic Robotics, table 7.2's odometry variant).
- `landmark_update`: range and bearing to point landmarks of known identity
  (the EKF-SLAM sensor of `robotlib.mapping.ekfslam`), all of a scan's
  landmarks stacked in one update.
- `laser_update`: a subset of laser beams against the map's walls, an
  iterated EKF; the expected ranges come from the exact segment caster
  (`robotlib.sensing.laser.expected_laser`), their Jacobian by central
  differences (`laser_jacobian`); beams whose innovation falls outside a
  gate (an obstacle not on the map, a beam past a corner) are left out.
- `nees`, `nis_band`: the normalised estimation error squared against the
  truth and the chi-square band it should stay in, to check consistency.

A Gaussian belief is unimodal: from a start far from the truth the
linearisation points the wrong way and the filter does not recover (no
global localization, no recovery from a kidnapping) where the histogram
filter and MCL do.

Imports numpy, the world's angle wrap, the laser model and the motion
model; never plots.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import chdtri

from ..sensing.laser import LaserModel, expected_laser
from ..world import wrap_angle
from .motion import DEFAULT_ALPHAS, noise_std, odometry_increment

__all__ = [
    "ekf_predict",
    "landmark_update",
    "laser_update",
    "laser_jacobian",
    "laser_sigma",
    "nees",
    "nis_band",
]


def _belief(mu, P):
    mu = np.asarray(mu, dtype=float).reshape(3).copy()
    P = np.asarray(P, dtype=float).reshape(3, 3).copy()
    if not (np.isfinite(mu).all() and np.isfinite(P).all()):
        raise ValueError("mu and P must be finite")
    return mu, P


def ekf_predict(mu, P, odo_prev, odo_now, alphas=DEFAULT_ALPHAS):
    """Predict the belief through one odometry increment.

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
    rot1, trans, rot2 = odometry_increment(odo_prev, odo_now)
    std = noise_std(alphas, rot1, trans, rot2)
    h = mu[2] + rot1
    c, s = math.cos(h), math.sin(h)
    G = np.array([[1.0, 0.0, -trans * s], [0.0, 1.0, trans * c], [0.0, 0.0, 1.0]])
    V = np.array([[-trans * s, c, 0.0], [trans * c, s, 0.0], [1.0, 0.0, 1.0]])
    M = np.diag(np.square(std))
    out = np.array([mu[0] + trans * c, mu[1] + trans * s, wrap_angle(h + rot2)])
    return out, G @ P @ G.T + V @ M @ V.T


def _update(mu, P, innovation, H, R):
    """Apply the Kalman update (Joseph form); return mu, P and the NIS."""
    S = H @ P @ H.T + R
    K = np.linalg.solve(S, H @ P).T
    mu = mu + K @ innovation
    mu[2] = wrap_angle(mu[2])
    A = np.eye(3) - K @ H
    P = A @ P @ A.T + K @ R @ K.T
    nis = float(innovation @ np.linalg.solve(S, innovation))
    return mu, 0.5 * (P + P.T), nis


def landmark_update(mu, P, z, landmarks, range_std: float, bearing_std: float):
    """Update the belief with range-bearing readings of known landmarks.

    Parameters
    ----------
    mu, P : array_like, shapes (3,) and (3, 3)
        The belief.
    z : array_like, shape (k, 2)
        Range (m) and bearing (rad, robot frame) of each landmark seen.
    landmarks : array_like, shape (k, 2)
        Their known positions, m (row i is the landmark of ``z[i]``).
    range_std, bearing_std : float
        The sensor's noise, m and rad.

    Returns
    -------
    mu, P : numpy.ndarray
    nis : float
        The innovation's normalised squared size (chi-square with ``2 k``
        degrees of freedom when consistent; 0 when nothing was seen).
    """
    mu, P = _belief(mu, P)
    z = np.asarray(z, dtype=float).reshape(-1, 2)
    lm = np.asarray(landmarks, dtype=float).reshape(-1, 2)
    if len(z) != len(lm):
        raise ValueError(f"{len(z)} readings but {len(lm)} landmarks")
    if len(z) == 0:
        return mu, P, 0.0
    dx, dy = lm[:, 0] - mu[0], lm[:, 1] - mu[1]
    q = np.maximum(dx * dx + dy * dy, 1e-12)
    r = np.sqrt(q)
    zhat = np.column_stack([r, wrap_angle(np.arctan2(dy, dx) - mu[2])])
    H = np.zeros((2 * len(z), 3))
    H[0::2] = np.column_stack([-dx / r, -dy / r, np.zeros(len(z))])
    H[1::2] = np.column_stack([dy / q, -dx / q, -np.ones(len(z))])
    nu = z - zhat
    nu[:, 1] = wrap_angle(nu[:, 1])
    R = np.diag(np.tile([range_std**2, bearing_std**2], len(z)))
    return _update(mu, P, nu.ravel(), H, R)


def laser_jacobian(walls, pose, model: LaserModel, beams, step: float = 1e-4):
    """Return the expected ranges of some beams at ``pose`` and their Jacobian.

    Parameters
    ----------
    walls : World or array_like (M, 4)
        The map (exact segment casting).
    pose : array_like, shape (3,)
        Robot pose.
    model : LaserModel
    beams : array_like of int, shape (B,)
        The beams used.
    step : float
        Central-difference step, m and rad.

    Returns
    -------
    zhat : numpy.ndarray, shape (B,)
    H : numpy.ndarray, shape (B, 3)
        ``d zhat / d (x, y, theta)``.
    """
    zhat, H, _ = _slopes(walls, pose, model, beams, step)
    return zhat, H


def _slopes(walls, pose, model, beams, step=1e-4, kink=1e-6):
    """`laser_jacobian`, and which beams are smooth within ``step`` of ``pose``.

    A beam whose forward and backward differences disagree by more than
    ``kink`` (m) on some axis passes an edge there: a corner where its
    range jumps, where a central difference gives a huge, meaningless slope
    that would collapse ``P`` along it.
    """
    pose = np.asarray(pose, dtype=float).reshape(3)
    poses = np.repeat(pose[None], 7, axis=0)
    for k in range(3):
        poses[1 + 2 * k, k] += step
        poses[2 + 2 * k, k] -= step
    r = expected_laser(walls, poses, model)[:, beams]
    fwd = np.column_stack([r[1 + 2 * k] - r[0] for k in range(3)])
    bwd = np.column_stack([r[0] - r[2 + 2 * k] for k in range(3)])
    smooth = (np.abs(fwd - bwd) <= kink).all(axis=1) & (r < model.max_range).all(axis=0)
    return r[0], (fwd + bwd) / (2 * step), smooth


def laser_sigma(model: LaserModel) -> float:
    """Return a beam's range error, m: the noise and the rounding's uniform error.

    ``sqrt(noise_std**2 + resolution**2 / 12)``: 5.8 mm for the LMS-200.
    """
    return math.sqrt(model.noise_std**2 + model.resolution**2 / 12.0)


def laser_update(
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
    """Update the belief with laser beams against the map's walls (iterated EKF).

    A range is far from linear in the pose over a prior's few centimetres
    (grazing walls, beams that pass to another wall), so one EKF step
    linearised at ``mu`` overshoots: from a start 0.4 m off it can throw the
    belief metres away and it never comes back. This is the iterated EKF
    (Gauss-Newton on the posterior's cost): at each iterate ``x`` the ranges
    and slopes are taken at ``x`` and the innovation is linearised about
    ``mu``, ``nu = z - h(x) - H (mu - x)``; the beams are chosen again at each
    iterate (a beam meant for one wall at ``mu`` may reach another at ``x``).
    It stops when a step moves less than 1 um or 1 urad, or after
    ``iterations``; ``P`` comes from the last slopes. From far off,
    Gauss-Newton may still jump away: the update is refused (the prior is
    kept, no beam used) when an iterate leaves no beam within the gate, or
    when the result's robust cost (`_map_cost`) is above the prior mean's,
    or when its NIS is beyond the chi-square's ``refuse`` tail (a wrong
    minimum: on office drives a few steps converge where 17 beams miss by
    20 sigma each). ``iterations=1`` is the plain EKF (refused only by NIS).

    Parameters
    ----------
    mu, P : array_like
        The belief.
    scan : array_like, shape (n_beams,)
        The laser's ranges, m.
    walls : World or array_like (M, 4)
        The map.
    model : LaserModel, optional
        The laser (default: an LMS-200 on a P3-DX).
    beams : array_like of int, optional
        Beams used (default: every tenth).
    sigma : float, optional
        Range noise assumed per beam, m (default: the sensor's own,
        `laser_sigma`). Office drives, 20 seeds, every tenth beam
        (``bench/bench_ekf_nees.py``): the NEES is in its 95 % band on 91 %
        of steps and no seed diverges; a plain EKF at the same sigma: 57 %
        (overconfident: its linearisation error is not in ``P``), at 5 cm:
        29 % (underconfident) and 2 seeds diverge.
    gate : float
        A beam is used only if its innovation is within ``gate`` standard
        deviations of the predicted ``sqrt(H P H^T + sigma^2)``, it and its
        expectation are both echoes (below the maximum range), and its
        expected range is smooth about the iterate (no corner within the
        difference step: there the slope is a jump's, not a wall's).
    iterations : int
        Most linearisations (at least 1).
    refuse : float
        The update is refused when its NIS has a chi-square tail probability
        below this (0: never).

    Returns
    -------
    mu, P : numpy.ndarray
    nis : float
        The innovation's normalised squared size over the beams used.
    used : int
        Beams used.
    """
    mu, P, model, zb, beams, sigma = _laser_inputs(
        mu, P, scan, model, beams, sigma, iterations
    )
    x, fit = mu, None
    for i in range(iterations):
        zhat, H, smooth = _slopes(walls, x, model, beams)
        off = mu - x
        off[2] = wrap_angle(off[2])
        nu = zb - zhat - H @ off
        spread = np.sqrt(np.einsum("bi,ij,bj->b", H, P, H) + sigma**2)
        if i == 0:  # the robust cost's cut: the gate about the prior
            cap = np.where((zb < model.max_range) & smooth, gate * spread, 0.0)
        ok = (zb < model.max_range) & smooth & (np.abs(nu) <= gate * spread)
        if not ok.any():  # no beam agrees with this iterate: it went astray
            return mu, P, 0.0, 0
        used = int(ok.sum())
        fit = _update(mu, P, nu[ok], H[ok], np.eye(used) * sigma**2)
        step = fit[0] - x
        step[2] = wrap_angle(step[2])
        x = fit[0]
        if np.abs(step).max() < 1e-6:
            break
    return _accepted(
        fit, used, mu, P, walls, zb, model, beams, sigma, cap, iterations > 1, refuse
    )


def _laser_inputs(mu, P, scan, model, beams, sigma, iterations):
    """Check a laser update's arguments and fill in their defaults.

    Returns
    -------
    mu, P : numpy.ndarray
        Copies of the belief, shapes (3,) and (3, 3).
    model : LaserModel
    zb : numpy.ndarray, shape (n,)
        The ranges of the beams used, m.
    beams : numpy.ndarray of int, shape (n,)
    sigma : float
        Range noise per beam, m.
    """
    mu, P = _belief(mu, P)
    model = LaserModel() if model is None else model
    z = np.asarray(scan, dtype=float).reshape(-1)
    if z.shape != (model.n_beams,):
        raise ValueError(f"scan must have {model.n_beams} ranges, got {z.shape}")
    if iterations < 1:
        raise ValueError(f"iterations must be at least 1, got {iterations}")
    sigma = laser_sigma(model) if sigma is None else float(sigma)
    if not sigma > 0:
        raise ValueError(f"sigma must be positive, got {sigma}")
    beams = np.arange(0, model.n_beams, 10) if beams is None else np.asarray(beams)
    return mu, P, model, z[beams], beams, sigma


def _accepted(fit, used, mu, P, walls, zb, model, beams, sigma, cap, iterated, refuse):
    """Return a laser update's ``(mu, P, nis, used)``, or the prior if it is refused.

    Refused (the prior ``mu, P`` kept, no beam used) when, after iterating,
    the beams fit the map worse at the result than at the prior's mean
    (`_map_cost`), or when the NIS is beyond the chi-square's ``refuse``
    tail for ``used`` beams.
    """
    if iterated:
        costs = _map_cost(
            walls, mu, P, np.array([mu, fit[0]]), zb, model, beams, sigma, cap
        )
        if costs[1] > costs[0]:  # the beams fit the prior's mean better
            return mu, P, 0.0, 0
    if refuse > 0 and fit[2] > chdtri(used, refuse):  # a fit the beams contradict
        return mu, P, 0.0, 0
    return *fit, used


def _map_cost(walls, mu, P, poses, zb, model, beams, sigma, cap):
    """Return the update's robust cost at each of ``poses`` (K, 3), shape (K,).

    ``(x - mu)^T P^-1 (x - mu)`` plus, for each beam, its squared range
    residual over ``sigma**2`` cut at ``(cap / sigma)**2`` (a beam that
    leaves its wall costs the same wherever the pose goes).
    """
    off = poses - mu
    off[:, 2] = wrap_angle(off[:, 2])
    prior = np.einsum("ki,ki->k", off, np.linalg.solve(P, off.T).T)
    r = zb - expected_laser(walls, poses, model)[:, beams]
    return prior + (np.minimum(r * r, cap * cap) / sigma**2).sum(axis=1)


def nees(mu, P, truth) -> float:
    """Normalised estimation error squared of the pose (3 degrees of freedom)."""
    e = np.asarray(truth, dtype=float).reshape(3) - np.asarray(mu, dtype=float)
    e[2] = wrap_angle(e[2])
    return float(e @ np.linalg.solve(np.asarray(P, dtype=float), e))


def nis_band(dof: int, level: float = 0.95) -> tuple:
    """Return the two-sided ``level`` band of a chi-square with ``dof`` degrees.

    ``chdtri`` is the chi-square's inverse survival function (the same numbers
    as ``scipy.stats.chi2.ppf``); importing ``scipy.stats`` instead took 1.5-2 s
    of Lab 1's first cell.
    """
    return tuple(float(chdtri(dof, q)) for q in ((1 + level) / 2, (1 - level) / 2))
