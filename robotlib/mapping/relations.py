"""The relative-pose error of Kümmerle et al. (2009) on published relations.

R. Kümmerle, B. Steder, C. Dornhege, M. Ruhnke, G. Grisetti, C. Stachniss
and A. Kleiner, "On measuring the accuracy of SLAM algorithms", Autonomous
Robots 27(4), 2009, score a SLAM result by relations between pairs of its
poses rather than by absolute poses: each relation gives the true motion
from the pose at one laser timestamp to the pose at another (``inv(p1)
p2``, hand-checked by the authors), and the error of a relation is the
estimated motion compared with it. Their relation files for the Freiburg
benchmark logs hold one relation a line: ``t1 t2 x y z roll pitch yaw``.

Imports numpy and `.posegraph`'s pose algebra; never plots.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .posegraph import relative_pose

__all__ = ["read_relations", "relation_errors", "RelationErrors"]


def read_relations(path) -> np.ndarray:
    """Read a relations file into rows ``(t1, t2, x, y, yaw)``, shape (R, 5).

    Lines starting with ``#`` are skipped; z, roll and pitch are dropped.
    """
    rows = []
    for line in Path(path).read_text(encoding="ascii").splitlines():
        tok = line.split()
        if not tok or tok[0].startswith("#"):
            continue
        if len(tok) < 8:
            raise ValueError(f"{path}: a relation needs 8 numbers, got {line!r}")
        v = [float(t) for t in tok[:8]]
        rows.append((v[0], v[1], v[2], v[3], v[7]))
    return np.array(rows, dtype=float).reshape(-1, 5)


@dataclass(frozen=True)
class RelationErrors:
    """Absolute errors per relation matched, and their summary.

    Attributes
    ----------
    translation : numpy.ndarray, shape (R,)
        ``|(x, y)|`` of each relation's error, m.
    rotation : numpy.ndarray, shape (R,)
        ``|yaw|`` of each relation's error, rad.
    unmatched : int
        Relations whose timestamps matched no pose.
    """

    translation: np.ndarray
    rotation: np.ndarray
    unmatched: int

    def summary(self) -> dict:
        """Mean and standard deviation (m; degrees) and the count."""
        return {
            "relations": int(len(self.translation)),
            "unmatched": self.unmatched,
            "trans_mean_m": float(np.mean(self.translation)),
            "trans_std_m": float(np.std(self.translation)),
            "rot_mean_deg": float(np.degrees(np.mean(self.rotation))),
            "rot_std_deg": float(np.degrees(np.std(self.rotation))),
        }


def relation_errors(times, poses, relations, tolerance: float = 1e-3):
    """Compare estimated poses with relations (Kümmerle et al. 2009).

    Parameters
    ----------
    times : array_like, shape (T,)
        Timestamp of each estimated pose, s (the laser's, as in the file).
    poses : array_like, shape (T, 3)
        Estimated poses, m and rad.
    relations : array_like, shape (R, 5)
        From `read_relations`.
    tolerance : float
        A relation's timestamp matches the nearest pose's within this, s.

    Returns
    -------
    RelationErrors
    """
    t = np.asarray(times, dtype=float)
    p = np.asarray(poses, dtype=float).reshape(-1, 3)
    rel = np.asarray(relations, dtype=float).reshape(-1, 5)
    order = np.argsort(t)
    ts = t[order]

    def find(stamps):
        k = np.clip(np.searchsorted(ts, stamps), 1, len(ts) - 1)
        k = np.where(np.abs(ts[k - 1] - stamps) < np.abs(ts[k] - stamps), k - 1, k)
        return order[k], np.abs(ts[k] - stamps) <= tolerance

    i, ok_i = find(rel[:, 0])
    j, ok_j = find(rel[:, 1])
    ok = ok_i & ok_j
    est = relative_pose(p[i[ok]], p[j[ok]])
    true = rel[ok][:, [2, 3, 4]]
    err = relative_pose(true, est)
    return RelationErrors(
        np.hypot(err[:, 0], err[:, 1]), np.abs(err[:, 2]), int((~ok).sum())
    )
