"""Pose-graph SLAM with laser scan matching (the front end and its settings).

`graph_slam` turns a laser log (odometry poses and scans) into a pose graph
and optimises it:

1. a *keyframe* is kept whenever odometry has moved ``keyframe_distance`` m
   or turned ``keyframe_angle`` rad since the last one;
2. each keyframe is matched by ICP (`robotlib.mapping.icp`) against the
   points of the few keyframes before it (a local map), starting from the
   odometry's guess: the match, if it holds, is the edge to the previous
   keyframe (weighted by its covariance, with a floor), else the odometry;
3. *loop closures*: keyframes of the current estimate lying within
   ``loop_radius`` m but at least ``loop_skip`` keyframes back are matched
   too, and the match becomes an edge when most points pair up closely;
4. the graph is optimised (`robotlib.mapping.posegraph.optimize`, sparse
   Gauss-Newton/LM with a Huber kernel against a wrong closure) every
   ``optimize_every`` keyframes, so that the proximity search of later
   loops sees corrected poses, and once at the end.

Every scan's pose is then its keyframe's optimised pose composed with the
odometry since it, refined by ICP onto that keyframe's and the next one's
points (``match_scans``).

Imports numpy, `.icp`, `.posegraph` and `.fastslam`'s degeneracy test;
never plots.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .fastslam import constrained_fit, pinned_directions
from .icp import icp, line_normals, scan_to_points, transform_points
from .posegraph import PoseGraph, compose, optimize, prune_loops, relative_pose

__all__ = ["GraphSLAMSettings", "GraphSLAMResult", "graph_slam"]


@dataclass(frozen=True)
class GraphSLAMSettings:
    """The knobs of `graph_slam` (m, rad).

    Attributes
    ----------
    keyframe_distance, keyframe_angle : float
        Odometry motion that starts a new keyframe (0.3 m, 0.3 rad).
    max_range : float
        Echoes at or beyond this are dropped, m (20).
    local_map : int
        Keyframes before the current one whose points it is matched to (3).
        On the loop world's long corridors each keyframe's heading error
        then adds up (0.005 rad, 0.12 m off mid-loop; RMS 0.05-0.07 m on
        seeds 0-2, FastSLAM 0.037 m): 15 gives 0.016-0.029 m there, but
        0.14 m of mean relation error on the Intel log instead of 0.029 m.
    gate : float
        ICP's initial pairing gate, m (0.5; it shrinks to a third).
    point_to_line : bool
        Point-to-line ICP (True) or point to point.
    min_inliers : float
        A sequential match holds when at least this fraction of points pair
        (0.5), it converged and it lies within ``max_correction`` of the
        odometry's guess.
    max_correction : tuple of float
        (0.5 m, 0.5 rad).
    odometry_sigma : tuple of float
        Standard deviations of an odometry edge per keyframe: along, across
        (m) and heading (rad) (0.1, 0.1, 0.1).
    match_sigma_floor : tuple of float
        Smallest standard deviations given to a match's ``x, y`` (m) and
        heading (rad), since ICP's own covariance is optimistic (0.02, 0.01).
    match_degenerate : float
        A sequential match (and a scan's between keyframes) moves the pose
        from the odometry's guess only along the position directions its
        point-to-line information pins: those with at least this share of
        the strongest direction's (`robotlib.mapping.fastslam.pinned_directions`).
        Along the others (a blank corridor's length) the edge takes the
        odometry's increment and the odometry's information, so the graph
        trusts the odometry there and a loop closure corrects it (0, the
        default: keep every match whole). On the loop world 0.1 evens the
        seeds out without helping on the whole (RMS on seeds 0-4 0.056,
        0.071, 0.050, 0.021, 0.026 m whole; 0.046, 0.045, 0.049, 0.050,
        0.047 m at 0.1, the map's F1 lower on 3 of 5): ICP there is pinned
        along the corridors by the doors and pilasters more often than it
        drifts. On generated rings (seeds 0-2, 8 m laser, corridors blank
        for up to 24 m) 0.1 moved the RMS from 0.16, 0.23 and 0.25 m to
        0.10, 0.20 and 0.31 m, the F1 down on 2 of 3; hence off by default.
    loop_radius : float
        Keyframes this near (current estimate) are loop candidates, m (1.5).
    loop_skip : int
        ... if at least this many keyframes back (30).
    loop_candidates : int
        At most this many candidates tried per keyframe (nearest first) (2).
    loop_every : int
        Loops are looked for at every this-many-th keyframe (2).
    loop_gate : float
        ICP's initial gate for a loop, m (1.0).
    loop_inliers, loop_rms : float
        A loop match is accepted with at least this inlier fraction (0.7) and
        at most this RMS, m (0.05).
    optimize_every : int
        Keyframes between optimisations during the run (25).
    huber : float
        Huber width on an edge's Mahalanobis distance (0.5: edges are
        weighed down from half a standard deviation on; chosen, with
        ``optimize_every``, on the Intel log's relations, where 3 gave
        0.048 m and 0.5 gave 0.029 m of mean relation error).
    match_scans : bool
        Place each scan between keyframes by ICP onto its keyframe and the
        next (True), not by the odometry since its keyframe alone.
    """

    keyframe_distance: float = 0.3
    keyframe_angle: float = 0.3
    max_range: float = 20.0
    local_map: int = 3
    gate: float = 0.5
    point_to_line: bool = True
    min_inliers: float = 0.5
    max_correction: tuple[float, float] = (0.5, 0.5)
    odometry_sigma: tuple[float, float, float] = (0.1, 0.1, 0.1)
    match_sigma_floor: tuple[float, float] = (0.02, 0.01)
    match_degenerate: float = 0.0
    loop_radius: float = 1.5
    loop_skip: int = 30
    loop_candidates: int = 2
    loop_every: int = 2
    loop_gate: float = 1.0
    loop_inliers: float = 0.7
    loop_rms: float = 0.05
    optimize_every: int = 25
    huber: float = 0.5
    match_scans: bool = True

    def __post_init__(self):
        if self.keyframe_distance <= 0 or self.keyframe_angle <= 0:
            raise ValueError("keyframe_distance and keyframe_angle must be > 0")
        if self.local_map < 1 or self.loop_skip < 2 or self.optimize_every < 1:
            raise ValueError("local_map >= 1, loop_skip >= 2, optimize_every >= 1")
        if min(self.odometry_sigma) <= 0 or min(self.match_sigma_floor) <= 0:
            raise ValueError("the sigmas must be > 0")


@dataclass
class GraphSLAMResult:
    """What `graph_slam` built.

    Attributes
    ----------
    poses : numpy.ndarray, shape (T, 3)
        Every scan's estimated pose, m and rad.
    keyframes : numpy.ndarray of int, shape (K,)
        The scans kept as keyframes (graph nodes, in order).
    graph : PoseGraph
        The optimised graph (node k is ``keyframes[k]``).
    loops : int
        Loop-closure edges kept (accepted by ICP, not pruned).
    failed_matches : int
        Sequential matches that did not hold (odometry used instead).
    """

    poses: np.ndarray
    keyframes: np.ndarray
    graph: PoseGraph
    loops: int
    failed_matches: int


def _keyframes(odometry, distance, angle) -> np.ndarray:
    keep = [0]
    for t in range(1, len(odometry)):
        d = relative_pose(odometry[keep[-1]], odometry[t])
        if math.hypot(d[0], d[1]) >= distance or abs(d[2]) >= angle:
            keep.append(t)
    return np.array(keep)


def _information(cov, floor) -> np.ndarray:
    c = np.array(cov, dtype=float)
    if not np.all(np.isfinite(c)):
        c = np.diag([floor[0] ** 2, floor[0] ** 2, floor[1] ** 2]) * 25.0
    c = 0.5 * (c + c.T) + np.diag([floor[0] ** 2, floor[0] ** 2, floor[1] ** 2])
    return np.linalg.inv(c)


def graph_slam(
    odometry,
    scans,
    angles,
    max_range: float,
    settings: GraphSLAMSettings | None = None,
    mount=(0.0, 0.0, 0.0),
) -> GraphSLAMResult:
    """Build and optimise a pose graph from a laser log.

    Parameters
    ----------
    odometry : array_like, shape (T, 3)
        Odometry pose of each scan, m and rad.
    scans : array_like, shape (T, B)
        Laser ranges, m.
    angles : array_like, shape (B,)
        Beam angles in the robot frame, rad.
    max_range : float
        The sensor's "no echo" range, m (the settings' ``max_range`` also
        applies).
    settings : GraphSLAMSettings, optional
    mount : array_like, shape (3,)
        The laser's pose in the robot frame, m and rad (a P3-DX's LMS-200:
        18 mm ahead of the centre).

    Returns
    -------
    GraphSLAMResult
    """
    s = GraphSLAMSettings() if settings is None else settings
    odo = np.asarray(odometry, dtype=float).reshape(-1, 3)
    z = np.asarray(scans, dtype=float)
    ang = np.asarray(angles, dtype=float).reshape(-1)
    if z.ndim != 2 or len(z) != len(odo) or z.shape[1] != len(ang):
        raise ValueError(
            f"need scans (T, B) with T = {len(odo)} poses, B = {len(ang)} angles; "
            f"got {z.shape}"
        )
    if not np.isfinite(odo).all():
        raise ValueError("odometry must be finite")
    rmax = min(float(max_range), s.max_range)
    kf = _keyframes(odo, s.keyframe_distance, s.keyframe_angle)
    mount = np.asarray(mount, dtype=float).reshape(3)
    points = [transform_points(mount, scan_to_points(z[t], ang, rmax)) for t in kf]
    sig = np.array(s.odometry_sigma)
    odo_info = np.diag(1.0 / sig**2)
    graph = PoseGraph()
    graph.add_pose(odo[kf[0]])
    loops = failed = 0
    for k in range(1, len(kf)):
        guess = relative_pose(odo[kf[k - 1]], odo[kf[k]])
        graph.add_pose(compose(graph.poses[k - 1], guess))
        edge = _sequential(graph, points, k, guess, s)
        if edge is None:
            failed += 1
            graph.add_edge(k - 1, k, guess, odo_info, "odometry")
        else:
            graph.add_edge(k - 1, k, edge[0], edge[1], "scan")
            graph.poses[k] = compose(graph.poses[k - 1], edge[0])
        if k % s.loop_every == 0:
            loops += _close_loops(graph, points, k, s)
        if k % s.optimize_every == 0:
            optimize(graph, iterations=10, huber=s.huber)
    pruned = prune_loops(graph, huber=s.huber, iterations=30)
    owner = np.searchsorted(kf, np.arange(len(odo)), side="right") - 1
    poses = compose(graph.poses[owner], relative_pose(odo[kf[owner]], odo))
    if s.match_scans:
        _match_between(poses, graph, kf, owner, points, z, ang, rmax, mount, s)
    return GraphSLAMResult(poses, kf, graph, loops - pruned, failed)


def _match_between(poses, graph, kf, owner, points, z, ang, rmax, mount, s):
    """Lay each scan between keyframes onto its two keyframes' points, in place.

    A scan placed by the odometry since its keyframe carries that stretch's
    heading error (0.007-0.009 rad RMS on the loop world, against the
    optimised keyframes' 0.002-0.005), which at 4 m smears its walls by
    3 cm: the laser map's F1 on loop seeds 2-4 goes from 0.93-0.95 to
    0.985-0.995, and the Intel log's mean relation error from 0.029 m and
    0.75 degrees to 0.024 m and 0.32 degrees (for about 3 times the CPU).
    A match that fails the sequential tests keeps the odometry's pose.
    """
    from scipy.spatial import cKDTree

    is_kf = np.zeros(len(poses), dtype=bool)
    is_kf[kf] = True
    for k in range(len(kf)):
        ts = np.flatnonzero((owner == k) & ~is_kf)
        if not len(ts):
            continue
        ref = [points[k]]
        if k + 1 < len(kf):
            step = relative_pose(graph.poses[k], graph.poses[k + 1])
            ref.append(transform_points(step, points[k + 1]))
        ref = np.concatenate(ref)
        if len(ref) < 10:
            continue
        tree = cKDTree(ref)
        normals = line_normals(ref, tree=tree) if s.point_to_line else None
        for t in ts:
            scan = transform_points(mount, scan_to_points(z[t], ang, rmax))
            if len(scan) < 10:
                continue
            guess = relative_pose(graph.poses[k], poses[t])
            r = icp(
                ref, scan, guess, max_distance=s.gate, point_to_line=s.point_to_line,
                tree=tree, normals=normals,
            )  # fmt: skip
            if _holds(r, guess, s):
                poses[t] = compose(graph.poses[k], _pinned(r, guess, s)[0])


def _sequential(graph, points, k, guess, s):
    """Match keyframe k against the local map; return (z, information) or None."""
    if len(points[k]) < 10:
        return None
    base = graph.poses[k - 1]
    ref = [points[k - 1]]
    for m in range(max(0, k - s.local_map), k - 1):
        ref.append(transform_points(relative_pose(base, graph.poses[m]), points[m]))
    ref = np.concatenate(ref)
    if len(ref) < 10:
        return None
    from scipy.spatial import cKDTree

    tree = cKDTree(ref)
    normals = line_normals(ref, tree=tree) if s.point_to_line else None
    r = icp(ref, points[k], guess, max_distance=s.gate, point_to_line=s.point_to_line,
            tree=tree, normals=normals)  # fmt: skip
    if not _holds(r, guess, s):
        return None
    z, cov = _pinned(r, guess, s)
    return z, _information(cov, s.match_sigma_floor)


def _holds(r, guess, s) -> bool:
    """Whether a match pairs enough points and lies near its guess."""
    off = relative_pose(guess, r.pose)
    return (
        r.inliers >= s.min_inliers
        and math.hypot(off[0], off[1]) <= s.max_correction[0]
        and abs(off[2]) <= s.max_correction[1]
    )


def _pinned(r, guess, s):
    """Return a match's pose and covariance, the odometry's where ICP does not pin.

    Along each position direction ``u`` that ``r.information`` does not pin
    (`GraphSLAMSettings.match_degenerate`), the pose keeps the odometry's
    ``guess`` and the information is the odometry's ``u u^T / sigma_u^2``
    instead of ICP's (``sigma_u``: `GraphSLAMSettings.odometry_sigma` along
    ``u``).
    """
    if s.match_degenerate <= 0.0:
        return r.pose, r.covariance
    h = r.information
    vec, keep = pinned_directions([h[0, 0], h[0, 1], h[1, 1]], s.match_degenerate)
    if keep.all():
        return r.pose, r.covariance
    z = constrained_fit(
        np.asarray(guess)[None], r.pose[None], [[h[0, 0], h[0, 1], h[1, 1]]],
        s.match_degenerate,
    )[0]  # fmt: skip
    sig2 = np.array(s.odometry_sigma[:2]) ** 2
    info = h.copy()
    for u in vec[0].T[~keep[0]]:
        drop = np.eye(3)
        drop[:2, :2] -= np.outer(u, u)
        info = drop @ info @ drop
        info[:2, :2] += np.outer(u, u) / float(u**2 @ sig2)
    if np.linalg.cond(info) >= 1e12:
        return z, np.full((3, 3), np.nan)
    return z, np.linalg.inv(info)


def _close_loops(graph, points, k, s) -> int:
    """Look for loop closures of keyframe k; add the accepted edges."""
    if k <= s.loop_skip or len(points[k]) < 10:
        return 0
    old = graph.poses[: k - s.loop_skip + 1]
    d = np.hypot(old[:, 0] - graph.poses[k, 0], old[:, 1] - graph.poses[k, 1])
    near = np.flatnonzero(d < s.loop_radius)
    if len(near) == 0:
        return 0
    added = 0
    for j in near[np.argsort(d[near])][: s.loop_candidates]:
        if len(points[j]) < 10:
            continue
        guess = relative_pose(graph.poses[j], graph.poses[k])
        r = icp(points[j], points[k], guess, max_distance=s.loop_gate,
                point_to_line=s.point_to_line)  # fmt: skip
        if r.inliers >= s.loop_inliers and r.rms <= s.loop_rms:
            info = _information(r.covariance, s.match_sigma_floor)
            graph.add_edge(int(j), k, r.pose, info, "loop")
            added += 1
    return added
