"""A pose graph over SE(2) and its least-squares optimiser (Gauss-Newton / LM).

Nodes are robot poses ``(x, y, theta)``; an edge ``(i, j, z, Omega)`` says
that pose ``j`` was measured at ``z`` in the frame of pose ``i`` (odometry,
or a scan match) with information matrix ``Omega`` (the inverse of the
measurement's covariance). Its error (Grisetti et al., "A tutorial on
graph-based SLAM", 2010) is

    e_ij = ( R(theta_z)^T (R(theta_i)^T (t_j - t_i) - t_z),
             wrap(theta_j - theta_i - theta_z) )

`edge_errors` computes it and its Jacobians (`edge_jacobians`, analytic;
tests check them against finite differences). `optimize` minimises
``sum e^T Omega e`` by Gauss-Newton with a Levenberg-Marquardt damping,
building the sparse normal equations with `scipy.sparse` and holding the
first pose fixed; a Huber kernel (optional) lowers the weight of edges that
disagree with the rest, and `prune_loops` removes the loop closures that
still disagree after optimising (a wrong match).

Imports numpy and scipy.sparse only (when `optimize` runs: importing
`robotlib.mapping` does not load it); never plots.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "PoseGraph",
    "OptimizeResult",
    "edge_errors",
    "edge_jacobians",
    "optimize",
    "prune_loops",
    "relative_pose",
    "compose",
]


def _wrap(a):
    return np.remainder(np.asarray(a) + np.pi, 2.0 * np.pi) - np.pi


def relative_pose(a, b) -> np.ndarray:
    """Return ``b`` in the frame of ``a`` (``a^-1 b``); rows of shape (..., 3)."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    dx, dy = b[..., 0] - a[..., 0], b[..., 1] - a[..., 1]
    return np.stack(
        [c * dx + s * dy, -s * dx + c * dy, _wrap(b[..., 2] - a[..., 2])], -1
    )


def compose(a, b) -> np.ndarray:
    """Return ``a b``: pose ``b`` given in the frame of ``a``, in the world."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack(
        [
            a[..., 0] + c * b[..., 0] - s * b[..., 1],
            a[..., 1] + s * b[..., 0] + c * b[..., 1],
            _wrap(a[..., 2] + b[..., 2]),
        ],
        -1,
    )


def edge_errors(xi, xj, z) -> np.ndarray:
    """Return the edges' errors ``e_ij`` (E, 3) from poses (E, 3) and z (E, 3)."""
    return relative_pose(z, relative_pose(xi, xj))


def edge_jacobians(xi, xj, z) -> tuple[np.ndarray, np.ndarray]:
    """Return the Jacobians of `edge_errors` wrt ``xi`` and ``xj``, each (E, 3, 3)."""
    xi, xj, z = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (xi, xj, z))
    ci, si = np.cos(xi[:, 2]), np.sin(xi[:, 2])
    cz, sz = np.cos(z[:, 2]), np.sin(z[:, 2])
    dx, dy = xj[:, 0] - xi[:, 0], xj[:, 1] - xi[:, 1]
    # Rz^T Ri^T = R(-(theta_i + theta_z))
    c, s = np.cos(xi[:, 2] + z[:, 2]), np.sin(xi[:, 2] + z[:, 2])
    e = len(xi)
    a = np.zeros((e, 3, 3))
    b = np.zeros((e, 3, 3))
    b[:, 0, 0], b[:, 0, 1] = c, s
    b[:, 1, 0], b[:, 1, 1] = -s, c
    b[:, 2, 2] = 1.0
    a[:, :2, :2] = -b[:, :2, :2]
    # d/dtheta_i of Ri^T (t_j - t_i), then Rz^T
    u = -si * dx + ci * dy
    w = -ci * dx - si * dy
    a[:, 0, 2] = cz * u + sz * w
    a[:, 1, 2] = -sz * u + cz * w
    a[:, 2, 2] = -1.0
    return a, b


@dataclass
class PoseGraph:
    """Poses and relative-pose constraints.

    Attributes
    ----------
    poses : numpy.ndarray, shape (N, 3)
        The current estimate, m and rad.
    edges : list of tuple
        ``(i, j, z, information, kind)``: ``z`` (3,), the measured pose of
        ``j`` in the frame of ``i``; ``information`` (3, 3); ``kind`` a label
        (``"odometry"``, ``"scan"``, ``"loop"``).
    """

    poses: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    edges: list = field(default_factory=list)

    def add_pose(self, pose) -> int:
        """Append a pose; return its index."""
        self.poses = np.vstack(
            [self.poses, np.asarray(pose, dtype=float).reshape(1, 3)]
        )
        return len(self.poses) - 1

    def add_edge(self, i: int, j: int, z, information, kind: str = "odometry") -> None:
        """Add the constraint that ``j`` lies at ``z`` in the frame of ``i``."""
        n = len(self.poses)
        if not (0 <= i < n and 0 <= j < n) or i == j:
            raise ValueError(f"edge ({i}, {j}) needs two distinct poses of {n}")
        info = np.asarray(information, dtype=float).reshape(3, 3)
        if not np.all(np.isfinite(info)) or np.any(np.linalg.eigvalsh(info) <= 0):
            raise ValueError("an edge's information must be finite, positive definite")
        self.edges.append(
            (int(i), int(j), np.asarray(z, dtype=float).reshape(3), info, kind)
        )

    def arrays(self):
        """Return the edges as arrays ``(i (E,), j (E,), z (E, 3), info (E, 3, 3))``."""
        if not self.edges:
            return (
                np.zeros(0, int),
                np.zeros(0, int),
                np.zeros((0, 3)),
                np.zeros((0, 3, 3)),
            )
        i = np.array([e[0] for e in self.edges])
        j = np.array([e[1] for e in self.edges])
        z = np.array([e[2] for e in self.edges])
        info = np.array([e[3] for e in self.edges])
        return i, j, z, info

    def chi2(self, poses=None) -> float:
        """Return the total ``sum e^T Omega e`` at ``poses`` (default: the estimate)."""
        x = self.poses if poses is None else poses
        i, j, z, info = self.arrays()
        e = edge_errors(x[i], x[j], z)
        return float(np.einsum("ka,kab,kb->", e, info, e))


@dataclass(frozen=True)
class OptimizeResult:
    """What `optimize` did: chi-square before and after, iterations, converged."""

    chi2_start: float
    chi2_end: float
    iterations: int
    converged: bool


def _weights(e, info, huber):
    if huber is None:
        return np.ones(len(e))
    chi = np.sqrt(np.einsum("ka,kab,kb->k", e, info, e))
    return np.where(chi <= huber, 1.0, huber / np.maximum(chi, 1e-300))


def _robust_chi2(e, info, huber):
    chi2 = np.einsum("ka,kab,kb->k", e, info, e)
    if huber is None:
        return float(chi2.sum())
    chi = np.sqrt(chi2)
    return float(np.where(chi <= huber, chi2, 2 * huber * chi - huber**2).sum())


def optimize(
    graph: PoseGraph,
    iterations: int = 20,
    tolerance: float = 1e-6,
    huber: float | None = None,
    damping: float = 1e-4,
) -> OptimizeResult:
    """Minimise the graph's error in place (Gauss-Newton, LM damping, sparse).

    Parameters
    ----------
    graph : PoseGraph
        Its ``poses`` are updated; pose 0 is held fixed (the gauge).
    iterations : int
        At most this many linear solves.
    tolerance : float
        Stop when the largest step is below this (m and rad).
    huber : float, optional
        Huber kernel width on each edge's Mahalanobis distance (None: plain
        least squares).
    damping : float
        Initial Levenberg-Marquardt ``lambda``, relative to the diagonal; it
        grows tenfold after a step that raises the error (the step is then
        undone) and shrinks tenfold after one that lowers it.

    Returns
    -------
    OptimizeResult
    """
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    n = len(graph.poses)
    ii, jj, z, info = graph.arrays()
    x = graph.poses.copy()
    e = edge_errors(x[ii], x[jj], z)
    cost = start = _robust_chi2(e, info, huber)
    if n < 2 or len(ii) == 0:
        return OptimizeResult(start, start, 0, True)
    lam = damping
    converged = False
    done = 0
    # the sparsity pattern: 3x3 blocks (i, i), (i, j), (j, i), (j, j) per edge
    bi = np.concatenate([ii, ii, jj, jj])
    bj = np.concatenate([ii, jj, ii, jj])
    rows = (3 * bi[:, None, None] + np.arange(3)[None, :, None]).repeat(3, 2).ravel()
    cols = (3 * bj[:, None, None] + np.arange(3)[None, None, :]).repeat(3, 1).ravel()
    for _ in range(iterations):
        done += 1
        a, b = edge_jacobians(x[ii], x[jj], z)
        om = info * _weights(e, info, huber)[:, None, None]
        at_om = np.einsum("kba,kbc->kac", a, om)
        bt_om = np.einsum("kba,kbc->kac", b, om)
        blocks = np.concatenate([at_om @ a, at_om @ b, bt_om @ a, bt_om @ b]).ravel()
        h = sp.csc_matrix((blocks, (rows, cols)), shape=(3 * n, 3 * n))
        g = np.zeros(3 * n)
        np.add.at(g, 3 * ii[:, None] + np.arange(3), np.einsum("kab,kb->ka", at_om, e))
        np.add.at(g, 3 * jj[:, None] + np.arange(3), np.einsum("kab,kb->ka", bt_om, e))
        h = h[3:, 3:]  # hold pose 0
        diag = h.diagonal()
        while True:
            hd = h + sp.diags(lam * np.maximum(diag, 1e-9))
            dx = spla.spsolve(hd.tocsc(), -g[3:])
            trial = x.copy()
            trial[1:] += dx.reshape(-1, 3)
            trial[:, 2] = _wrap(trial[:, 2])
            e_trial = edge_errors(trial[ii], trial[jj], z)
            c_trial = _robust_chi2(e_trial, info, huber)
            if c_trial <= cost or lam > 1e8:
                break
            lam *= 10.0
        if c_trial > cost:
            break
        x, e, cost = trial, e_trial, c_trial
        lam = max(lam / 10.0, 1e-12)
        if np.abs(dx).max() < tolerance:
            converged = True
            break
    graph.poses = x
    return OptimizeResult(start, cost, done, converged)


def prune_loops(
    graph: PoseGraph,
    threshold: float = 16.27,
    huber: float | None = 3.0,
    max_removed: int = 20,
    iterations: int = 20,
) -> int:
    """Optimise, then drop the worst loop edge while one disagrees; repeat.

    A wrong loop closure pulls the whole graph; a robust kernel alone cannot
    undo it when the start is far off. Each round optimises the graph and
    removes the ``"loop"`` edge of largest ``e^T Omega e`` if that exceeds
    ``threshold`` (default: the chi-square 99.9 % point for 3 degrees of
    freedom), until none does.

    Returns
    -------
    int
        The number of loop edges removed.
    """
    removed = 0
    while True:
        optimize(graph, iterations=iterations, huber=huber)
        loops = [k for k, e in enumerate(graph.edges) if e[4] == "loop"]
        if not loops or removed >= max_removed:
            return removed
        i, j, z, info = graph.arrays()
        e = edge_errors(graph.poses[i[loops]], graph.poses[j[loops]], z[loops])
        chi2 = np.einsum("ka,kab,kb->k", e, info[loops], e)
        worst = int(np.argmax(chi2))
        if chi2[worst] <= threshold:
            return removed
        del graph.edges[loops[worst]]
        removed += 1
