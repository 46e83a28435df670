"""A pose estimate for a particle cloud split over several places.

The weighted mean (`robotlib.localization.paper.estimate`) of a cloud with
two modes lies between them, often in a wall: during a global start or after
a kidnapping it is far from both places until one of them has won outright.
`mode_estimate` reports the heaviest place instead, as AMCL reports its
heaviest cluster: for a cloud gathered in one place it is that cloud's mean.
"""

from __future__ import annotations

import math

import numpy as np

from .resampling import _cloud

__all__ = ["mode_estimate"]


def mode_estimate(particles, weights, cell: float = 1.0, radius: float = 0.75):
    """Return the weighted mean pose of the heaviest place in a weighted cloud.

    The weights are summed on a grid of ``cell`` squares; the 3 x 3 block of
    cells holding the most weight gives a first mean, refined twice as the
    weighted mean of the particles within ``radius`` of it. The heading is
    the weighted circular mean of those particles.

    Parameters
    ----------
    particles : array_like, shape (N, 3)
        Poses, m and rad.
    weights : array_like, shape (N,)
        Non-negative weights, not all zero (need not be normalised).
    cell : float
        Grid cell side, m.
    radius : float
        Radius of the refining disc, m.

    Returns
    -------
    numpy.ndarray, shape (3,)
        ``(x, y, theta)``, m and rad.
    """
    p, w = _cloud(particles, weights)
    ij = np.floor((p[:, :2] - p[:, :2].min(axis=0)) / cell).astype(np.int64)
    nx, ny = ij.max(axis=0) + 1
    heap = np.bincount(ij[:, 0] * ny + ij[:, 1], weights=w, minlength=nx * ny)
    padded = np.pad(heap.reshape(nx, ny), 1)
    block = sum(padded[a : a + nx, b : b + ny] for a in range(3) for b in range(3))
    bi, bj = np.unravel_index(int(np.argmax(block)), block.shape)
    near = (np.abs(ij[:, 0] - bi) <= 1) & (np.abs(ij[:, 1] - bj) <= 1)
    for _ in range(2):  # the block's mean, then the disc's
        centre = w[near] @ p[near, :2] / w[near].sum()
        disc = np.hypot(*(p[:, :2] - centre).T) < radius
        if not w[disc].sum() > 0:  # the mean fell between two clouds: keep the block
            break
        near = disc
    heading = math.atan2(w[near] @ np.sin(p[near, 2]), w[near] @ np.cos(p[near, 2]))
    centre = w[near] @ p[near, :2] / w[near].sum()
    return np.array([centre[0], centre[1], heading])
