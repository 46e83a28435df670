"""Small geometric helpers shared across robotlib (SI units: metres, radians).

Pure Python and NumPy; imports nothing of robotlib.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["wrap_angle", "compose", "relative"]


def wrap_angle(theta):
    """Wrap angles to the interval (-pi, pi].

    Parameters
    ----------
    theta : float or numpy.ndarray
        Angles in radians.

    Returns
    -------
    float or numpy.ndarray
        The same angles wrapped to (-pi, pi], with the input's shape.
    """
    if np.isscalar(theta):
        w = math.remainder(float(theta), 2.0 * math.pi)
        return math.pi if w == -math.pi else w
    w = np.remainder(np.asarray(theta, dtype=float) + np.pi, 2.0 * np.pi) - np.pi
    return np.where(w <= -np.pi, w + 2.0 * np.pi, w)


def compose(pose, delta):
    """Apply a robot-frame increment to a pose.

    Parameters
    ----------
    pose : array_like, shape (3,) or (N, 3)
        ``(x, y, theta)`` in metres and radians, world frame.
    delta : array_like, shape (3,) or (N, 3)
        ``(dx, dy, dtheta)`` in the frame of ``pose``.

    Returns
    -------
    numpy.ndarray
        The composed pose(s), heading wrapped to (-pi, pi].
    """
    p = np.asarray(pose, dtype=float)
    d = np.asarray(delta, dtype=float)
    c, s = np.cos(p[..., 2]), np.sin(p[..., 2])
    out = np.empty(np.broadcast_shapes(p.shape, d.shape))
    out[..., 0] = p[..., 0] + c * d[..., 0] - s * d[..., 1]
    out[..., 1] = p[..., 1] + s * d[..., 0] + c * d[..., 1]
    out[..., 2] = wrap_angle(p[..., 2] + d[..., 2])
    return out


def relative(pose_from, pose_to):
    """Express ``pose_to`` in the frame of ``pose_from`` (inverse of `compose`).

    Parameters
    ----------
    pose_from, pose_to : array_like, shape (3,) or (N, 3)
        Poses ``(x, y, theta)`` in the same world frame.

    Returns
    -------
    numpy.ndarray
        ``delta`` such that ``compose(pose_from, delta) == pose_to``.
    """
    a = np.asarray(pose_from, dtype=float)
    b = np.asarray(pose_to, dtype=float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    dx, dy = b[..., 0] - a[..., 0], b[..., 1] - a[..., 1]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = c * dx + s * dy
    out[..., 1] = -s * dx + c * dy
    out[..., 2] = wrap_angle(b[..., 2] - a[..., 2])
    return out
