"""The odometry increment as an arc, sampled and linearised for SLAM.

The simulator moves a robot each cycle along an arc of length ``ds`` turning
``dtheta`` (mid-angle integration) and adds slip whose variances grow with
the motion (`robotlib.sim.OdometryNoise`). `arc_increment` recovers
``(ds, dtheta)`` from two odometry poses, `sample_arc_motion` moves
particles by it with that noise (inflated for safety), and `arc_jacobians`
gives the EKF its linearisation. Imports the geometry and the sim's noise
model only; never plots.
"""

from __future__ import annotations

import math

import numpy as np

from .._random import as_rng
from ..sim import OdometryNoise
from ..world.geometry import wrap_angle

__all__ = ["arc_increment", "apply_arc", "sample_arc_motion", "arc_noise_cov"]


def arc_increment(odo_prev, odo_now) -> tuple[float, float]:
    """Return ``(ds, dtheta)``: the arc that takes ``odo_prev`` to ``odo_now``.

    ``ds`` (m) is negative for a backward move; ``dtheta`` (rad) is wrapped.
    """
    x0, y0, t0 = (float(v) for v in odo_prev)
    x1, y1, t1 = (float(v) for v in odo_now)
    dth = wrap_angle(t1 - t0)
    dx, dy = x1 - x0, y1 - y0
    mid = t0 + 0.5 * dth
    ds = math.hypot(dx, dy)
    if dx * math.cos(mid) + dy * math.sin(mid) < 0:
        ds = -ds
    return ds, dth


def apply_arc(poses, ds, dth) -> np.ndarray:
    """Move poses (N, 3) along arcs ``ds`` (N,) or scalar, turning ``dth``."""
    p = np.array(poses, dtype=float, ndmin=2)
    mid = p[:, 2] + 0.5 * np.asarray(dth)
    p[:, 0] += ds * np.cos(mid)
    p[:, 1] += ds * np.sin(mid)
    p[:, 2] = wrap_angle(p[:, 2] + dth)
    return p


def arc_noise_cov(ds: float, dth: float, noise: OdometryNoise, inflate: float = 1.0):
    """Covariance (2, 2) of the true ``(ds, dtheta)`` given the measured ones."""
    var_s = noise.trans_per_m**2 * abs(ds)
    var_t = noise.rot_per_rad**2 * abs(dth) + noise.rot_per_m**2 * abs(ds)
    return np.diag([var_s, var_t]) * inflate**2


def sample_arc_motion(
    particles,
    odo_prev,
    odo_now,
    noise: OdometryNoise | None = None,
    inflate: float = 1.5,
    rng: np.random.Generator | int | None = None,
) -> np.ndarray:
    """Move particles (N, 3) by the odometry increment plus the slip's noise.

    Parameters
    ----------
    particles : array_like, shape (N, 3)
        Poses, m and rad.
    odo_prev, odo_now : array_like, shape (3,)
        Successive odometry poses.
    noise : OdometryNoise, optional
        The slip model (default: the simulator's).
    inflate : float
        Standard deviations are multiplied by this (a filter should not
        assume less noise than there is).
    rng : numpy.random.Generator, int or None
        Draws (N, 2) standard normals.

    Returns
    -------
    numpy.ndarray, shape (N, 3)
    """
    noise = OdometryNoise() if noise is None else noise
    rng = as_rng(rng)
    p = np.asarray(particles, dtype=float)
    ds, dth = arc_increment(odo_prev, odo_now)
    sd = np.sqrt(np.diag(arc_noise_cov(ds, dth, noise, inflate)))
    n = rng.standard_normal((len(p), 2))
    return apply_arc(p, ds + sd[0] * n[:, 0], dth + sd[1] * n[:, 1])
