"""One robot of an exploring team: its belief, its path, and how it keeps clear.

`Member` holds a robot's simulated body, the pose it believes (the truth
or its own grid FastSLAM's best particle), its target and pure-pursuit
path, and adds its readings to the shared map. The functions below are the
checks `robotlib.exploration.Exploration` makes from what the robots sense
and from the shared map, every cycle:

- `clear_bodies`: the cells under every robot's body are free on the map
  (the laser and sonar see teammates; they are not walls);
- `count_echoes`: near echoes of the forward sonars, per cell (posts the
  laser's beams pass between);
- `teammate_ahead`: a teammate closer ahead than the stopping distance;
- `keeps_clear`: whether a command keeps the robot clear of the known walls,
  the echoes and the teammates for half a second.

Imports the simulator's robot model, mapping and planning; never plots.
"""

from __future__ import annotations

import math

import numpy as np

from ..mapping import SONAR_SETTINGS, FastSLAMSettings, GridFastSLAM, OccupancyGrid
from ..p3dx import (
    DEFAULT_ACCELERATION,
    ROBOT_LENGTH_FRONT,
    ROBOT_LENGTH_REAR,
    ROBOT_RADIUS,
    ROBOT_WIDTH,
    SONAR_POSES,
)
from ..planning import PurePursuit
from ..planning.follow import sonar_points
from ..world import wrap_angle
from .settings import ExploreSettings

__all__ = [
    "Member",
    "cell",
    "clear_bodies",
    "count_echoes",
    "teammate_ahead",
    "keeps_clear",
    "EXPLORE",
    "HOME",
    "DONE",
]

ECHO_RANGE = 0.6
"""Echoes of the two forward sonars (``AXIS``) nearer than this (m) mark
their cell for planning (two echoes in a cell block it): thin posts the
laser's beams pass between. The oblique sonars are left out: an echo is put
on its sonar's axis, and a door jamb seen at the edge of a 30 degree cone
would close the door."""

AXIS = slice(3, 5)
"""The sonars at +-10 degrees."""

BODY = math.hypot(ROBOT_LENGTH_REAR, ROBOT_WIDTH / 2) + 0.05
"""A teammate's reach from its centre, m: its rear corners, and a little."""

EXPLORE, HOME, DONE = "explore", "home", "done"
"""A robot's modes: driving to a frontier, driving home, home (or idle)."""


class Member:
    """One team member: its body, its belief, its target and path.

    Parameters
    ----------
    index : int
        Its place in the team (later robots wait longer for teammates).
    body : robotlib.sim.Robot
        Its simulated body.
    settings : ExploreSettings
        The knobs (sensor, pose source, SLAM particles, pure pursuit).
    world : World
        Only for the extent of SLAM's own map.
    rng : numpy.random.Generator
        Seeds its SLAM.
    """

    def __init__(self, index: int, body, settings: ExploreSettings, world, rng):
        self.index = index
        self.body = body
        self.home = body.true_pose.copy()
        self.pose = body.true_pose.copy()
        self.mode = EXPLORE
        self.target: np.ndarray | None = None
        self.follower: PurePursuit | None = None
        self.waited = 0.0
        self.stuck = 0.0
        self.spin = 2 * math.pi  # a look round first: the laser sees only ahead
        self.blocked = False
        self.stalled = False
        self.truth = [self.pose.copy()]
        self.estimates = [self.pose.copy()]
        self.targets: list[np.ndarray] = []
        self.slam = None
        if settings.pose == "slam":
            fs = SONAR_SETTINGS if settings.sensor == "sonar" else FastSLAMSettings()
            self.slam = GridFastSLAM.for_world(
                world, settings.resolution, start=self.home,
                n_particles=settings.particles, sensor=settings.sensor,
                settings=fs, rng=rng,
            )  # fmt: skip

    def sense(self, grid: OccupancyGrid, sensor: str) -> None:
        """Add this cycle's reading to the shared map at the believed pose."""
        z = self.body.scan_laser() if sensor == "laser" else self.body.state.sonar
        if self.slam is not None:
            self.slam.step(self.body.state.pose, z)
            self.pose = self.slam.particles[self.slam.best()].copy()
        else:
            self.pose = self.body.true_pose.copy()
        if sensor == "laser":
            grid.update_laser(self.pose, z)
        else:
            grid.update_sonar(self.pose, z)

    def drive_to(self, path, goal, settings: ExploreSettings) -> None:
        """Follow ``path`` (K, 2) to ``goal`` (2,)."""
        self.target = np.asarray(goal, dtype=float)
        self.follower = PurePursuit(
            path, settings.lookahead, settings.speed, settings.w_max,
            settings.goal_tolerance,
        )  # fmt: skip
        self.waited = self.stuck = 0.0

    def stop(self, mode: str = DONE) -> None:
        """Drop the target and path; take ``mode``."""
        self.mode, self.follower, self.target = mode, None, None

    def distance_home(self) -> float:
        """Distance from the believed position to the start, m."""
        return float(np.hypot(*(self.pose[:2] - self.home[:2])))

    def remaining_path(self) -> np.ndarray:
        """Return the part of the path still ahead, (K, 2) m."""
        p = self.follower
        k = int(np.searchsorted(p.cum, p.s, side="right")) - 1
        return p.path[max(k, 0) :]


def cell(grid: OccupancyGrid, xy) -> tuple[int, int]:
    """Row and column of the cell holding ``xy`` (clipped to the grid)."""
    ny, nx = grid.shape
    j = int((xy[0] - grid.origin[0]) // grid.resolution)
    i = int((xy[1] - grid.origin[1]) // grid.resolution)
    return min(max(i, 0), ny - 1), min(max(j, 0), nx - 1)


def clear_bodies(grid: OccupancyGrid, team, free_level: float) -> None:
    """Mark the cells under every robot's body free: it stands there, no wall.

    The laser and sonar see teammates' bodies; without this, a teammate
    would leave a trail of obstacles on the shared map.
    """
    k = int(math.ceil(BODY / grid.resolution))
    level = -(free_level + 0.1)
    for r in team:
        i, j = cell(grid, r.pose)
        win = (slice(max(i - k, 0), i + k + 1), slice(max(j - k, 0), j + k + 1))
        ii, jj = np.mgrid[win]
        cx = grid.origin[0] + (jj + 0.5) * grid.resolution
        cy = grid.origin[1] + (ii + 0.5) * grid.resolution
        c, si = math.cos(r.pose[2]), math.sin(r.pose[2])
        dx, dy = cx - r.pose[0], cy - r.pose[1]
        along, across = c * dx + si * dy, c * dy - si * dx
        pad = grid.resolution / 2
        inside = (along <= ROBOT_LENGTH_FRONT + pad) & (
            along >= -ROBOT_LENGTH_REAR - pad
        )
        inside &= np.abs(across) <= ROBOT_WIDTH / 2 + pad
        cells = grid.logodds[win]
        cells[inside] = np.minimum(cells[inside], level)


def count_echoes(echoes: np.ndarray, grid: OccupancyGrid, r: Member, others) -> None:
    """Count ``r``'s near forward sonar echoes not explained by a teammate.

    ``echoes`` (int, the grid's shape) is incremented where they fall;
    ``others`` (K, 2) are the teammates' positions, m.
    """
    if r.spin > 0:
        return
    z = np.full(len(SONAR_POSES), np.inf)
    z[AXIS] = r.body.state.sonar[AXIS]
    pts = sonar_points(r.pose, z, ECHO_RANGE)
    if len(others) and len(pts):
        d = np.hypot(*(pts[:, None, :] - others[None, :, :]).transpose(2, 0, 1))
        pts = pts[d.min(axis=1) > ROBOT_RADIUS + 0.15]
    for x, y in pts:
        i, j = cell(grid, (x, y))
        echoes[i, j] = min(echoes[i, j] + 1, 100)


def teammate_ahead(r: Member, others, keep_out: float) -> bool:
    """Whether a teammate (positions ``others`` (K, 2)) is close ahead of ``r``.

    Close: nearer than ``keep_out`` plus ``r``'s stopping distance at its
    speed; ahead: within 60 degrees of its heading.
    """
    v = max(float(r.body.state.velocity[0]), 0.0)
    reach = keep_out + v * v / (2 * DEFAULT_ACCELERATION)
    for o in others:
        d = o - r.pose[:2]
        if math.hypot(*d) < reach:
            bearing = wrap_angle(math.atan2(d[1], d[0]) - r.pose[2])
            if abs(bearing) < math.pi / 3:
                return True
    return False


def keeps_clear(
    grid: OccupancyGrid, occupied_level: float, echoes, pose, v: float, w: float, mates
) -> bool:
    """Whether driving ``(v, w)`` from ``pose`` for half a second keeps clear.

    Clear of the cells the map holds occupied (log-odds above
    ``occupied_level``) or that hold two ``echoes`` (int, the grid's shape),
    and of the teammates at ``mates`` (K, 2); moving away from one already
    too close is allowed.
    """
    i, j = cell(grid, pose)
    k = int(math.ceil(1.0 / grid.resolution))
    win = (slice(max(i - k, 0), i + k + 1), slice(max(j - k, 0), j + k + 1))
    ii, jj = np.nonzero((grid.logodds[win] > occupied_level) | (echoes[win] >= 2))
    cx = grid.origin[0] + (jj + win[1].start + 0.5) * grid.resolution
    cy = grid.origin[1] + (ii + win[0].start + 0.5) * grid.resolution
    x, y, th = pose
    t = np.linspace(0.0, 0.5, 6)
    a = th + w * t
    px = x + v * t * np.cos(a)
    py = y + v * t * np.sin(a)
    d = np.full(len(t), np.inf)
    if len(cx):
        d = np.hypot(px[:, None] - cx, py[:, None] - cy).min(axis=1)
    if len(mates):  # a teammate: a disc round its corners
        gap = np.hypot(px[:, None] - mates[:, 0], py[:, None] - mates[:, 1])
        d = np.minimum(d, gap.min(axis=1) - BODY)
    return bool(d[1:].min() >= min(ROBOT_RADIUS + 0.02, d[0] - 0.005))
