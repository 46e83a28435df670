"""Scan matching by the iterative closest point algorithm (ICP), in the plane.

`icp` finds the rigid motion ``(x, y, theta)`` that lays one laser scan's
points onto another's: it pairs each point with its nearest neighbour in
the reference (a k-d tree), drops pairs further apart than a gate, solves
for the motion that best aligns the pairs, and repeats until the motion
stops changing. Two error measures:

- point to point (Besl and McKay 1992): the closed-form rotation of the
  paired, centred point sets (an SVD);
- point to line (Chen and Medioni 1992; Censi's PL-ICP 2008 in 2D): the
  distance along the reference's local normal, linearised in the motion and
  solved by least squares; it converges in fewer steps along walls.

With the match comes a covariance (the Gauss-Newton estimate
``s**2 (J^T J)^-1`` of the final residuals) and its quality (the inlier
fraction and RMS), which a pose graph uses to weigh and to accept the edge.

Imports numpy and scipy's k-d tree only (when a match runs: importing
`robotlib.mapping` does not load scipy.spatial); never plots.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from scipy.spatial import cKDTree

__all__ = ["ICPResult", "icp", "scan_to_points", "transform_points", "line_normals"]


@dataclass(frozen=True)
class ICPResult:
    """One scan match.

    Attributes
    ----------
    pose : numpy.ndarray, shape (3,)
        ``(x, y, theta)`` of the scan's frame in the reference's frame, m and
        rad: the reference point ``q`` matching a scan point ``p`` is about
        ``R(theta) p + (x, y)``.
    covariance : numpy.ndarray, shape (3, 3)
        Its covariance, m^2, m rad, rad^2 (NaN where `information` is
        singular).
    information : numpy.ndarray, shape (3, 3)
        The Gauss-Newton information ``J^T J / s**2`` of the final pairs,
        per m^2, m rad, rad^2 (zeros when fewer than 3 pair). Point to line,
        its position block is ``sum(n n^T) / s**2`` over the pairs' normals
        ``n``: along a blank corridor the direction along the walls gets
        almost nothing. Point to point it is ``pairs / s**2`` in every
        direction, which never shows such a direction.
    rms : float
        RMS distance of the inlier pairs at the end, m.
    inliers : float
        Fraction of the scan's points paired within the gate at the end.
    iterations : int
        Iterations run.
    converged : bool
        The last step moved less than the tolerance.
    """

    pose: np.ndarray
    covariance: np.ndarray
    information: np.ndarray
    rms: float
    inliers: float
    iterations: int
    converged: bool


def scan_to_points(ranges, angles, max_range: float, min_range: float = 0.05):
    """Return a scan's echoes as points in the sensor frame, shape (K, 2), m.

    Ranges at or beyond ``max_range`` (no echo) or below ``min_range`` or not
    finite are left out.
    """
    r = np.asarray(ranges, dtype=float)
    a = np.asarray(angles, dtype=float)
    if r.shape != a.shape:
        raise ValueError(f"{r.shape[0]} ranges but {a.shape[0]} angles")
    ok = np.isfinite(r) & (r < max_range) & (r >= min_range)
    return np.column_stack([r[ok] * np.cos(a[ok]), r[ok] * np.sin(a[ok])])


def transform_points(pose, points) -> np.ndarray:
    """Return ``R(theta) p + (x, y)`` for each row ``p`` of ``points`` (K, 2)."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    return np.column_stack(
        [pose[0] + c * p[:, 0] - s * p[:, 1], pose[1] + s * p[:, 0] + c * p[:, 1]]
    )


def line_normals(points, k: int = 5, tree: cKDTree | None = None) -> np.ndarray:
    """Return unit normals of the local lines through each point (k-neighbour PCA).

    Returns
    -------
    numpy.ndarray, shape (K, 2)
        The direction of least spread of each point's ``k`` nearest
        neighbours (itself included); its sign is arbitrary.
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    k = min(k, len(pts))
    if tree is None:
        from scipy.spatial import cKDTree

        tree = cKDTree(pts)
    _, idx = tree.query(pts, k=k)
    nb = pts[np.asarray(idx).reshape(len(pts), k)]
    d = nb - nb.mean(axis=1, keepdims=True)
    cov = np.einsum("kni,knj->kij", d, d)
    _, vecs = np.linalg.eigh(cov)
    return vecs[:, :, 0]


def _kabsch(p, q):
    """Return the rigid motion minimising sum |R p + t - q|^2 over pairs."""
    mp, mq = p.mean(axis=0), q.mean(axis=0)
    h = (p - mp).T @ (q - mq)
    theta = math.atan2(h[0, 1] - h[1, 0], h[0, 0] + h[1, 1])
    c, s = math.cos(theta), math.sin(theta)
    t = mq - np.array([c * mp[0] - s * mp[1], s * mp[0] + c * mp[1]])
    return np.array([t[0], t[1], theta])


def _compose(a, b):
    c, s = math.cos(a[2]), math.sin(a[2])
    return np.array(
        [a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], a[2] + b[2]]
    )


def icp(
    reference,
    scan,
    init=(0.0, 0.0, 0.0),
    *,
    max_distance: float = 0.5,
    min_distance: float | None = None,
    max_iterations: int = 40,
    tolerance: float = 1e-5,
    point_to_line: bool = False,
    tree: cKDTree | None = None,
    normals: np.ndarray | None = None,
) -> ICPResult:
    """Align ``scan`` onto ``reference`` by ICP.

    Parameters
    ----------
    reference : array_like, shape (N, 2)
        Points of the reference scan, in its frame, m (N >= 3).
    scan : array_like, shape (M, 2)
        Points of the scan to align, in its own frame, m (M >= 3).
    init : array_like, shape (3,)
        Initial guess of the scan's pose in the reference frame (odometry).
    max_distance : float
        Pairs further apart than this are dropped, m; the gate shrinks
        linearly from it to ``min_distance`` over the first half of the
        iterations, so that a poor guess still finds its pairs.
    min_distance : float, optional
        The final gate, m (default: ``max_distance / 3``).
    max_iterations : int
        At most this many pairings.
    tolerance : float
        Stop when a step moves less than this (m, and rad).
    point_to_line : bool
        Minimise the distance to the reference's local lines instead of to
        its points.
    tree, normals : optional
        The reference's k-d tree and normals, if already built.

    Returns
    -------
    ICPResult
    """
    ref = np.asarray(reference, dtype=float).reshape(-1, 2)
    cur = np.asarray(scan, dtype=float).reshape(-1, 2)
    if len(ref) < 3 or len(cur) < 3:
        raise ValueError(f"ICP needs 3 points a side, got {len(ref)} and {len(cur)}")
    if not (np.isfinite(ref).all() and np.isfinite(cur).all()):
        raise ValueError("scan points must be finite")
    if max_distance <= 0 or max_iterations < 1:
        raise ValueError("max_distance must be > 0 and max_iterations >= 1")
    lo = max_distance / 3.0 if min_distance is None else float(min_distance)
    if tree is None:
        from scipy.spatial import cKDTree

        tree = cKDTree(ref)
    if point_to_line and normals is None:
        normals = line_normals(ref, tree=tree)
    pose = np.asarray(init, dtype=float).reshape(3).copy()
    converged = False
    half = max(1, max_iterations // 2)
    it = 0
    for it in range(1, max_iterations + 1):
        gate = max(lo, max_distance - (max_distance - lo) * (it - 1) / half)
        moved = transform_points(pose, cur)
        dist, idx = tree.query(moved, distance_upper_bound=gate)
        ok = np.isfinite(dist)
        if ok.sum() < 3:
            break
        p, q = moved[ok], ref[idx[ok]]
        if point_to_line:
            n = normals[idx[ok]]
            jac = np.column_stack([n, n[:, 1] * p[:, 0] - n[:, 0] * p[:, 1]])
            res = np.einsum("ki,ki->k", n, p - q)
            step = -np.linalg.lstsq(jac, res, rcond=None)[0]
        else:
            step = _kabsch(p, q)
        pose = _compose(step, pose)
        pose[2] = math.remainder(pose[2], 2.0 * math.pi)
        if np.abs(step).max() < tolerance and gate <= lo:
            converged = True
            break
    return _finish(ref, cur, pose, tree, normals, lo, it, converged, point_to_line)


def _finish(ref, cur, pose, tree, normals, gate, iterations, converged, to_line):
    """Return the result: the final pairs' covariance and quality."""
    moved = transform_points(pose, cur)
    dist, idx = tree.query(moved, distance_upper_bound=gate)
    ok = np.isfinite(dist)
    n_in = int(ok.sum())
    cov = np.full((3, 3), np.nan)
    info = np.zeros((3, 3))
    rms = math.inf
    if n_in >= 3:
        p, q = moved[ok], ref[idx[ok]]
        # residuals about the scan frame's origin, moved into the reference
        arm = p - pose[:2]
        if to_line:
            n = normals[idx[ok]]
            jac = np.column_stack([n, n[:, 1] * arm[:, 0] - n[:, 0] * arm[:, 1]])
            res = np.einsum("ki,ki->k", n, p - q)
            dof = max(n_in - 3, 1)
        else:
            jac = np.zeros((2 * n_in, 3))
            jac[0::2, 0] = 1.0
            jac[1::2, 1] = 1.0
            jac[0::2, 2] = -arm[:, 1]
            jac[1::2, 2] = arm[:, 0]
            res = (p - q).ravel()
            dof = max(2 * n_in - 3, 1)
        s2 = max(float(res @ res) / dof, 1e-6)
        info = jac.T @ jac / s2
        if np.linalg.cond(info) < 1e12:
            cov = np.linalg.inv(info)
        rms = float(np.sqrt(np.mean(np.sum((p - q) ** 2, axis=1))))
    return ICPResult(pose, cov, info, rms, n_in / len(cur), iterations, converged)
