"""Laser FastSLAM's scan-matched proposal, as GMapping draws it.

For each particle (Grisetti, Stachniss and Burgard, IEEE T-RO 2007, the
improved proposal): move it by the odometry increment (no noise: the
prediction ``u``); hill-climb ``u`` to the pose ``x*`` where the scan fits
the particle's own map best, less the motion prior's penalty
(`robotlib.mapping._kernels_proposal.fit_pose_many`); score K poses on a
small grid about ``x*``, ``tau_k = p(z | x_k, m)^T p(x_k | u)``; draw the new
pose from the Gaussian with those points' weighted mean and covariance; and
multiply the particle's weight by ``eta = sum_k tau_k``, the proposal's
normaliser. Along a blank corridor the scan scores the grid's points alike
and the motion prior shapes the draw: the pose goes where the odometry puts
it, with the odometry's spread.

`scan_normals` gives the returns' end points and surface normals (the
likelihood field measures along them), `proposal_offsets` lays the grid,
`motion_log_prior` scores it, `gaussian_draw` takes the moments and draws;
`GridFastSLAM.propose_laser` runs the kernels between them. Imports
nothing of robotlib's; never plots.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "gaussian_draw",
    "motion_log_prior",
    "proposal_offsets",
    "scan_normals",
    "to_map_frame",
]


def scan_normals(mount, angles, ranges, max_range, step: int = 1, bend: float = 0.03):
    """End points and surface normals of a scan's returns, robot frame.

    A return's surface runs from its left neighbour's end point to its right
    one's; its normal is that chord's, turned a quarter. Where a neighbour
    gives no return, the chord is over 2 m long, or the end point lies more
    than ``bend`` m off the chord (a corner, an edge), the normal is (0, 0):
    none, the end point scores by its whole distance.

    Parameters
    ----------
    mount : array_like, shape (3,)
        The laser's pose on the robot, m and rad.
    angles, ranges : numpy.ndarray, shape (R,)
        Beam directions (rad, laser frame) and ranges (m).
    max_range : float
        A range at or above it is no return.
    step : int
        Keep every ``step``-th beam's return (the normals use all beams).
    bend : float
        Largest distance of an end point from its neighbours' chord, m.

    Returns
    -------
    points, normals : numpy.ndarray, shape (B, 2)
        The kept returns' end points and their unit normals (or zeros).
    """
    mount = np.asarray(mount, dtype=float)
    a = mount[2] + np.asarray(angles, dtype=float)
    z = np.asarray(ranges, dtype=float)
    p = mount[:2] + z[:, None] * np.column_stack([np.cos(a), np.sin(a)])
    ok = z < max_range
    chord = np.zeros_like(p)
    chord[1:-1] = p[2:] - p[:-2]
    length = np.hypot(chord[:, 0], chord[:, 1])
    good = np.zeros_like(ok)
    good[1:-1] = ok[1:-1] & ok[:-2] & ok[2:]
    good &= (length > 0) & (length < 2.0)
    t = chord / np.where(length > 0, length, 1.0)[:, None]
    normals = np.column_stack([-t[:, 1], t[:, 0]])
    off = np.zeros(len(z))
    off[1:-1] = np.abs(((p[1:-1] - p[:-2]) * normals[1:-1]).sum(axis=1))
    good &= off <= bend
    normals[~good] = 0.0
    keep = ok & (np.arange(len(z)) % step == 0)
    return p[keep], normals[keep]


def proposal_offsets(spacing, counts=(5, 3, 3)) -> np.ndarray:
    """Offsets (K, 3) of the proposal's grid: along, across (m) and heading (rad).

    ``counts[i]`` points (odd), ``spacing[i]`` apart, centred on 0, on each
    axis of the fit's frame; ``K = prod(counts)``.
    """
    axes = [
        s * (np.arange(c) - (c - 1) / 2) for s, c in zip(spacing, counts, strict=True)
    ]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def to_map_frame(poses, offsets) -> np.ndarray:
    """Poses (N, K, 3): ``offsets`` (K, 3) or (N, K, 3) taken in each pose's frame.

    ``poses`` (N, 3); an offset ``(a, b, t)`` moves a pose ``a`` m along its
    heading, ``b`` m to its left and turns it ``t`` rad.
    """
    p = np.asarray(poses, dtype=float)[:, None, :]
    o = np.broadcast_to(offsets, (len(p), *np.shape(offsets)[-2:]))
    c, s = np.cos(p[..., 2]), np.sin(p[..., 2])
    out = np.empty(o.shape)
    out[..., 0] = p[..., 0] + c * o[..., 0] - s * o[..., 1]
    out[..., 1] = p[..., 1] + s * o[..., 0] + c * o[..., 1]
    t = p[..., 2] + o[..., 2]
    out[..., 2] = np.arctan2(np.sin(t), np.cos(t))
    return out


def motion_log_prior(poses, pred, sig) -> np.ndarray:
    """Return the motion prior's log-density (less its constant) at poses (N, K, 3).

    Independent Gaussians about each prediction ``pred[n]`` (N, 3) along its
    heading, across it and in heading, standard deviations ``sig`` (3,), m
    and rad (`robotlib.mapping._kernels_proposal.log_prior`, vectorised).
    """
    u = np.asarray(pred, dtype=float)[:, None, :]
    d = np.asarray(poses, dtype=float) - u
    c, s = np.cos(u[..., 2]), np.sin(u[..., 2])
    a = (c * d[..., 0] + s * d[..., 1]) / sig[0]
    b = (-s * d[..., 0] + c * d[..., 1]) / sig[1]
    t = np.arctan2(np.sin(d[..., 2]), np.cos(d[..., 2])) / sig[2]
    return -0.5 * (a * a + b * b + t * t)


def gaussian_draw(fits, offsets, log_tau, floor, normals):
    """Draw each particle's pose from the Gaussian of its grid's weighted points.

    Parameters
    ----------
    fits : numpy.ndarray, shape (N, 3)
        The grid centres ``x*``, m and rad.
    offsets : numpy.ndarray, shape (K, 3)
        The grid's points in each fit's frame (`proposal_offsets`).
    log_tau : numpy.ndarray, shape (N, K)
        Each point's log of scan likelihood (tempered) times motion prior.
    floor : array_like, shape (3,)
        Standard deviations added to the covariance's diagonal (along,
        across, heading), so that a grid finer than the points' spread still
        draws a spread.
    normals : numpy.ndarray, shape (N, 3)
        Standard normal draws.

    Returns
    -------
    poses : numpy.ndarray, shape (N, 3)
        The drawn poses, map frame.
    log_eta : numpy.ndarray, shape (N,)
        ``log sum_k tau_k``: each particle's log weight factor.
    """
    top = log_tau.max(axis=1, keepdims=True)
    w = np.exp(log_tau - top)
    eta = w.sum(axis=1)
    w /= eta[:, None]
    mu = w @ offsets  # (N, 3)
    d = offsets[None, :, :] - mu[:, None, :]
    cov = np.einsum("nk,nki,nkj->nij", w, d, d) + np.diag(np.square(floor))
    local = mu + np.einsum("nij,nj->ni", np.linalg.cholesky(cov), normals)
    return to_map_frame(fits, local[:, None, :])[:, 0], np.log(eta) + top[:, 0]
