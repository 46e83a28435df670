"""Odometry motion model: Thrun's ``sample_motion_model_odometry``.

Two successive odometry poses give an increment decomposed as a rotation
``rot1`` towards the direction of travel, a translation ``trans`` and a final
rotation ``rot2`` (Probabilistic Robotics, table 5.6). Each particle moves by
that increment plus zero-mean Gaussian noise whose variances are

- ``rot1``: ``alpha1 rot1^2 + alpha2 trans^2``
- ``trans``: ``alpha3 trans^2 + alpha4 (rot1^2 + rot2^2)``
- ``rot2``: ``alpha1 rot2^2 + alpha2 trans^2``

(units: rad^2 and m^2; the alphas are dimensionless). A backward move is
decomposed with a negative ``trans`` so that reversing does not look like a
half turn. The noise is drawn as standard normals, an ``(N, 3)`` array, by
the caller's `numpy.random.Generator`; `move_particles` scales and applies it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._random import as_rng

__all__ = [
    "OdometryMotionModel",
    "move_particles",
    "noise_std",
    "odometry_increment",
    "sample_motion_odometry",
]

PARALLEL_MIN = 4096
"""Particle count from which kernels run over threads."""

DEFAULT_ALPHAS = (0.002, 0.005, 0.01, 0.0005)
"""Default ``alpha1..alpha4``: the simulator's default odometry slip, with margin."""


def _particles(particles) -> np.ndarray:
    """Return ``particles`` as a C-contiguous float64 array (N, 3), or raise."""
    p = np.ascontiguousarray(particles, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"particles must have shape (N, 3), got {np.shape(particles)}")
    return p


def odometry_increment(odo_prev, odo_now, min_trans: float = 1e-4) -> tuple:
    """Decompose the move between two odometry poses into ``(rot1, trans, rot2)``.

    Parameters
    ----------
    odo_prev, odo_now : array_like, shape (3,)
        Successive odometry poses ``(x, y, theta)``, m and rad.
    min_trans : float
        Below this translation (m) the move counts as a turn in place
        (``rot1 = 0``), so the direction of a tiny move does not matter.

    Returns
    -------
    tuple of float
        ``rot1`` (rad), ``trans`` (m, negative when moving backwards),
        ``rot2`` (rad).
    """
    x0, y0, t0 = (float(v) for v in np.asarray(odo_prev, dtype=float).reshape(3))
    x1, y1, t1 = (float(v) for v in np.asarray(odo_now, dtype=float).reshape(3))
    dx, dy = x1 - x0, y1 - y0
    trans = math.hypot(dx, dy)
    if trans < min_trans:
        rot1 = 0.0
    else:
        rot1 = math.remainder(math.atan2(dy, dx) - t0, 2 * math.pi)
        if abs(rot1) > math.pi / 2:  # backwards
            rot1 = math.remainder(rot1 + math.pi, 2 * math.pi)
            trans = -trans
    rot2 = math.remainder(t1 - t0 - rot1, 2 * math.pi)
    return rot1, trans, rot2


def noise_std(alphas, rot1: float, trans: float, rot2: float) -> tuple:
    """Return the standard deviations of the noise on rot1, trans, rot2, rad and m."""
    a1, a2, a3, a4 = alphas
    return (
        math.sqrt(a1 * rot1 * rot1 + a2 * trans * trans),
        math.sqrt(a3 * trans * trans + a4 * (rot1 * rot1 + rot2 * rot2)),
        math.sqrt(a1 * rot2 * rot2 + a2 * trans * trans),
    )


def move_particles(particles, increment, std, normals) -> np.ndarray:
    """Move every particle by the increment plus scaled noise.

    Parameters
    ----------
    particles : numpy.ndarray, shape (N, 3)
        Poses ``(x, y, theta)``, m and rad.
    increment : tuple of float
        ``(rot1, trans, rot2)``, rad, m, rad (`odometry_increment`).
    std : tuple of float
        The noise's standard deviations (`noise_std`).
    normals : numpy.ndarray, shape (N, 3)
        Standard normal draws.

    Returns
    -------
    numpy.ndarray, shape (N, 3)
        The moved poses (a new array), headings wrapped to (-pi, pi].
    """
    rot1 = increment[0] + std[0] * normals[:, 0]
    trans = increment[1] + std[1] * normals[:, 1]
    rot2 = increment[2] + std[2] * normals[:, 2]
    heading = particles[:, 2] + rot1
    out = np.empty_like(particles)
    out[:, 0] = particles[:, 0] + trans * np.cos(heading)
    out[:, 1] = particles[:, 1] + trans * np.sin(heading)
    out[:, 2] = (heading + rot2 + np.pi) % (2 * np.pi) - np.pi
    return out


def sample_motion_odometry(
    particles,
    odo_prev,
    odo_now,
    alphas=DEFAULT_ALPHAS,
    rng: np.random.Generator | int | None = None,
) -> np.ndarray:
    """Move every particle by the odometry increment plus noise.

    Parameters
    ----------
    particles : array_like, shape (N, 3)
        Poses ``(x, y, theta)``, m and rad.
    odo_prev, odo_now : array_like, shape (3,)
        The robot's odometry poses before and after the move.
    alphas : sequence of 4 float
        Noise parameters ``alpha1..alpha4`` (see the module docstring).
    rng : numpy.random.Generator, int or None
        Draws the (N, 3) standard normals.

    Returns
    -------
    numpy.ndarray, shape (N, 3)
        The moved particles (a new array), headings wrapped to (-pi, pi].
    """
    p = _particles(particles)
    increment = odometry_increment(odo_prev, odo_now)
    normals = as_rng(rng).standard_normal((len(p), 3))
    return move_particles(p, increment, noise_std(alphas, *increment), normals)


@dataclass(frozen=True)
class OdometryMotionModel:
    """The odometry motion model as an object an `MCL` is composed with.

    Attributes
    ----------
    alphas : tuple of 4 float
        ``alpha1`` (rotation noise from rotation), ``alpha2`` (rotation from
        translation), ``alpha3`` (translation from translation), ``alpha4``
        (translation from rotation); variances as in the module docstring.
        The defaults cover the simulator's default odometry slip with margin.
    """

    alphas: tuple[float, float, float, float] = DEFAULT_ALPHAS

    def __post_init__(self):
        if len(self.alphas) != 4 or min(self.alphas) < 0:
            raise ValueError("alphas must be four non-negative numbers")

    def sample(self, particles, odo_prev, odo_now, rng) -> np.ndarray:
        """Return particles moved by the odometry increment plus noise.

        See `sample_motion_odometry` for the parameters.
        """
        return sample_motion_odometry(particles, odo_prev, odo_now, self.alphas, rng)
