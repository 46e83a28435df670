"""Look-alike places: a map's symmetries, and whether a trajectory tells them apart.

A building that looks the same turned by half a turn (a generated warehouse
of racks, most office floors of identical rooms round a core) cannot be
told apart from its turned self by any sensor: a robot that localized in
one half with sonar may as well be in the other, and two filters fed the
same readings settle in the same half. `map_symmetries` finds the turns
(90, 180 and 270 degrees about the walls' centre) that map the walls onto
themselves; `look_alike` says whether a trajectory turned by one of them
stays in free space and explains the recorded sonar as well as the
trajectory itself does. `robotlib.planning.Navigator` asks before it says
"reached", and says ``"ambiguous"`` instead when the answer is yes.
`drive_score` weighs one hypothesis of where the robot is now by the whole
drive behind it: the navigator compares its belief with the places it
believed in earlier and gave up (carried along by the odometry).

Imports the world and the sonar model; never plots.
"""

from __future__ import annotations

import math

import numpy as np

from ..sensing import expected_ranges
from ..world import World, compose, relative

__all__ = ["map_symmetries", "look_alike", "fits", "agreement", "drive_score"]

PASS_THROUGH = 0.05
"""A hypothesis whose drive comes this close to a wall went through it, m."""


def fits(scans, expected: np.ndarray) -> np.ndarray:
    """Tell which sonar readings agree with the ranges expected from the map.

    A reading agrees within 0.25 m plus 10 % of the expected range.

    Parameters
    ----------
    scans : array_like, shape (..., S)
        The readings, m.
    expected : numpy.ndarray, shape (..., S)
        The map's ranges at the same poses, m.

    Returns
    -------
    numpy.ndarray of bool, the shape of ``expected``
    """
    return np.abs(np.asarray(scans, dtype=float) - expected) < 0.25 + 0.1 * expected


def _wall_points(world: World, step: float) -> np.ndarray:
    """Points every ``step`` m along every wall, shape (P, 2)."""
    out = []
    for x1, y1, x2, y2 in np.asarray(world.obstacles, dtype=float):
        k = max(int(math.hypot(x2 - x1, y2 - y1) / step), 1)
        t = np.linspace(0.0, 1.0, k + 1)
        out.append(np.column_stack([x1 + t * (x2 - x1), y1 + t * (y2 - y1)]))
    return np.concatenate(out) if out else np.zeros((0, 2))


def map_symmetries(
    world: World, tolerance: float = 0.15, share: float = 0.97, step: float = 0.1
) -> list[np.ndarray]:
    """Find the turns about the walls' centre that map the walls onto themselves.

    Parameters
    ----------
    world : World
        The map.
    tolerance : float
        A turned wall point matches when it lies this close to a wall, m
        (generated worlds jitter their walls by a few cm).
    share : float
        A turn is a symmetry when at least this share of the points match.
    step : float
        Spacing of the points along the walls, m.

    Returns
    -------
    list of numpy.ndarray, shape (3,)
        Each symmetry as a rigid motion ``g`` (``compose(g, pose)`` turns a
        pose), among the turns by 90, 180 and 270 degrees.
    """
    pts = _wall_points(world, step)
    if len(pts) == 0:
        return []
    seg = np.asarray(world.obstacles, dtype=float)
    cx = 0.5 * (
        min(seg[:, 0].min(), seg[:, 2].min()) + max(seg[:, 0].max(), seg[:, 2].max())
    )
    cy = 0.5 * (
        min(seg[:, 1].min(), seg[:, 3].min()) + max(seg[:, 1].max(), seg[:, 3].max())
    )
    out = []
    for turn in (0.5 * math.pi, math.pi, 1.5 * math.pi):
        c, s = math.cos(turn), math.sin(turn)
        g = np.array([cx - c * cx + s * cy, cy - s * cx - c * cy, turn])
        moved = np.column_stack(
            [g[0] + c * pts[:, 0] - s * pts[:, 1], g[1] + s * pts[:, 0] + c * pts[:, 1]]
        )
        if np.mean(world.distance_to_walls(moved) < tolerance) >= share:
            out.append(g)
    return out


def agreement(world: World, poses, scans) -> float:
    """Share of sonar readings that the map explains at the poses.

    A reading agrees when it lies within 0.25 m + 10 % of the map's
    noise-free reading (the navigator's own test of being lost).

    Parameters
    ----------
    world : World
        The map.
    poses : array_like, shape (K, 3)
        Where the readings were taken, m and rad.
    scans : array_like, shape (K, S)
        The readings, m.

    Returns
    -------
    float
        In [0, 1] (nan without poses).
    """
    poses = np.asarray(poses, dtype=float).reshape(-1, 3)
    if len(poses) == 0:
        return math.nan
    expected = expected_ranges(world, poses)
    return float(fits(scans, expected).mean())


def look_alike(world: World, poses, scans, symmetries, margin: float = 0.03):
    """Return the symmetry under which the trajectory is as likely, or None.

    Parameters
    ----------
    world : World
        The map.
    poses : array_like, shape (K, 3)
        The estimated trajectory, m and rad.
    scans : array_like, shape (K, S)
        The sonar readings taken along it, m.
    symmetries : sequence of numpy.ndarray, shape (3,)
        Candidate rigid motions (`map_symmetries`).
    margin : float
        The turned trajectory counts as as likely when its `agreement` is
        at least the trajectory's minus this.

    Returns
    -------
    numpy.ndarray, shape (3,), or None
        The first symmetry whose turned trajectory stays free (the robot's
        disc) and agrees with the readings as well; None when none does.
    """
    poses = np.asarray(poses, dtype=float).reshape(-1, 3)
    if len(poses) == 0:
        return None
    own = agreement(world, poses, scans)
    for g in symmetries:
        turned = np.array([compose(g, p) for p in poses])
        if not world.is_free(turned[:, :2]).all():
            continue
        if agreement(world, turned, scans) >= own - margin:
            return np.asarray(g)
    return None


def drive_score(world: World, pose, odometry, scans, every: int = 5) -> float:
    """Share of the drive's readings the map explains, were the robot at ``pose`` now.

    The drive is laid out backwards from ``pose`` by the odometry (its last
    row is now): the trajectory ``pose * odometry[-1]^-1 * odometry[k]``.
    Every ``every``-th row's readings are compared with the map's (as in
    `agreement`); where the trajectory comes within `PASS_THROUGH` of a wall
    before the next scored row (a wrong place's drive runs through walls),
    that row explains none of its readings. The odometry's drift lowers the
    score of the true place's early rows too, so compare scores of places,
    not a score with a bar.

    Parameters
    ----------
    world : World
        The map.
    pose : array_like, shape (3,)
        The hypothesis: where the robot is at the drive's last row, m and rad.
    odometry : array_like, shape (K, 3)
        The odometry poses of the drive, m and rad.
    scans : array_like, shape (K, S)
        The sonar readings at those rows, m.
    every : int
        Score every ``every``-th row (the walls are tested at every row).

    Returns
    -------
    float
        In [0, 1] (nan without rows).
    """
    odo = np.asarray(odometry, dtype=float).reshape(-1, 3)
    if len(odo) == 0:
        return math.nan
    path = compose(np.asarray(pose, dtype=float), relative(odo[-1], odo))
    every = max(int(every), 1)
    z = np.asarray(scans, dtype=float)[::every]
    expected = expected_ranges(world, path[::every])
    ok = fits(z, expected).mean(axis=1)
    # a scored row counts nothing if the walls are crossed before the next one
    through = np.zeros(len(ok), dtype=bool)
    np.logical_or.at(
        through, np.arange(len(odo)) // every, ~world.is_free(path[:, :2], PASS_THROUGH)
    )
    return float(np.where(through, 0.0, ok).mean())
