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
- `mark_contact`, `mark_stuck`: block on the map's twin (``echoes``) the
  cell a robot ran into, or the laser returns too near a robot that cannot
  move on;
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
    CYCLE,
    DEFAULT_ACCELERATION,
    ROBOT_LENGTH_FRONT,
    ROBOT_LENGTH_REAR,
    ROBOT_RADIUS,
    ROBOT_WIDTH,
    SONAR_POSES,
)
from ..planning import PurePursuit
from ..planning.follow import sonar_points
from ..sensing.laser import LaserModel, laser_poses
from ..world import wrap_angle
from .settings import ExploreSettings

__all__ = [
    "Member",
    "look_round",
    "cell",
    "clear_bodies",
    "count_echoes",
    "mark_contact",
    "mark_stuck",
    "teammate_ahead",
    "keeps_clear",
    "escape",
    "EXPLORE",
    "HOME",
    "DONE",
]

TOUCH = ROBOT_RADIUS + 0.15
"""Returns nearer the robot's centre than this (m) are kept for
`mark_contact`."""

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

CLEARANCE = 0.02
"""`keeps_clear` wants the body this far (m) from the nearest occupied
cell's centre along the next half second."""

BACK_OFF = 0.1
"""A robot backing off a wall (`escape`) stops when it is this much (m)
further than `keeps_clear` wants: at the limit itself, the first turn
towards its path would bring it back."""

STUCK_REACH = ROBOT_RADIUS + CLEARANCE + 0.1
"""Returns nearer than this (m) to a robot no command keeps clear are
blocked for planning (`mark_stuck`)."""

AWAY = 0.3
"""A robot nearer a blocked cell than `keeps_clear` wants may drive only
where the distance grows by this share of the way (about 17 degrees off
the tangent): the wall can lie 0.07 m from the cell's centre, so moving
along the circle round the centre can still push into it."""

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
        self.spin = look_round(index, settings.sensor)
        self.turn = 0.0  # the way it turns in place (rad/s sign), 0 when not
        self.blocked = False
        self.backing = False  # backing off a wall it came too near
        self.stalled = False
        self.near = np.zeros((0, 2))  # this cycle's returns within TOUCH, m
        self.returns = np.zeros((0, 2))  # its laser returns within 1 m, m
        self.scan = None  # this cycle's laser scan (None: mapping with sonar)
        self.command = (0.0, 0.0)  # the last (v, w) sent, and the speed then
        self.speed = 0.0
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
            self.returns = laser_points(self.pose, z, 1.0)
            gap = np.hypot(*(self.returns - self.pose[:2]).T)
            self.near = self.returns[gap < TOUCH]
            self.scan = z
        else:
            grid.update_sonar(self.pose, z)
            self.near = sonar_points(self.pose, z, TOUCH)

    def drive_to(self, path, goal, settings: ExploreSettings) -> None:
        """Follow ``path`` (K, 2) to ``goal`` (2,)."""
        self.target = np.asarray(goal, dtype=float)
        self.follower = PurePursuit(
            path, settings.lookahead, settings.speed, settings.w_max,
            settings.goal_tolerance,
        )  # fmt: skip
        self.waited = self.stuck = self.turn = 0.0

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


def look_round(index: int, sensor: str) -> float:
    """How far (rad) a team's robot ``index`` turns in place before it starts.

    The first robot looks round: half a turn with the laser (its 180 degree
    field sees every direction by then), a whole turn with the sonar ring
    (its cones leave gaps). Its teammates, started beside it facing the same
    way, see ahead at once and drive off while it looks behind them.
    """
    if index > 0:
        return 0.0
    return math.pi if sensor == "laser" else 2 * math.pi


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
    ny, nx = grid.shape
    for r in team:
        i, j = cell(grid, r.pose)
        win = (slice(max(i - k, 0), min(i + k + 1, ny)),
               slice(max(j - k, 0), min(j + k + 1, nx)))  # fmt: skip
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
    ``others`` (K, 2) are the teammates' positions, m. An echo is put on its
    sonar's axis, but it may come from the edge of the cone: with a laser,
    an echo whose point the laser's beams (the nearest three) all pass
    beyond is no obstacle there (a door jamb seen obliquely would otherwise
    close the door the robot is driving through).
    """
    if r.spin > 0:
        return
    z = np.full(len(SONAR_POSES), np.inf)
    z[AXIS] = r.body.state.sonar[AXIS]
    pts = sonar_points(r.pose, z, ECHO_RANGE)
    if len(others) and len(pts):
        d = np.hypot(*(pts[:, None, :] - others[None, :, :]).transpose(2, 0, 1))
        pts = pts[d.min(axis=1) > ROBOT_RADIUS + 0.15]
    if r.scan is not None and len(pts):
        pts = pts[~_seen_through(r.pose, r.scan, pts)]
    for x, y in pts:
        i, j = cell(grid, (x, y))
        echoes[i, j] = min(echoes[i, j] + 1, 100)


def _seen_through(pose, ranges, pts) -> np.ndarray:
    """Whether the laser's three beams nearest each point (K, 2) pass it by 0.1 m."""
    laser = LaserModel()
    x, y, th = laser_poses(pose, laser)[0]
    ang = laser.angles
    bearing = np.arctan2(pts[:, 1] - y, pts[:, 0] - x) - th
    bearing = (bearing + np.pi) % (2 * np.pi) - np.pi
    k = np.rint((bearing - ang[0]) / (ang[1] - ang[0])).astype(np.int64)
    dist = np.hypot(pts[:, 0] - x, pts[:, 1] - y)
    out = np.zeros(len(pts), dtype=bool)
    for n in range(len(pts)):
        if 0 <= k[n] < len(ang):
            near = np.asarray(ranges)[max(k[n] - 1, 0) : k[n] + 2]
            out[n] = near.min() > dist[n] + 0.1
    return out


def laser_points(pose, ranges, max_range: float) -> np.ndarray:
    """World points ``(x, y)`` of the laser returns shorter than ``max_range``, m."""
    laser = LaserModel()
    x, y, th = laser_poses(pose, laser)[0]
    z = np.asarray(ranges, dtype=float)
    keep = z < max_range
    a = th + laser.angles[keep]
    return np.column_stack([x + z[keep] * np.cos(a), y + z[keep] * np.sin(a)])


def mark_contact(echoes: np.ndarray, grid: OccupancyGrid, r: Member, v: float) -> None:
    """Block the cell ``r`` ran into (its motors stalled driving at ``v``, m/s).

    A wall can stand in a cell the map holds free (the laser's beams pass
    through the rest of a cell a wall only grazes: a box's corner, a door
    jamb's end). The nearest return of this cycle's reading on the side the
    robot drove to, or without one the point just ahead of the body, is
    blocked in ``echoes`` so that neither the plan nor `keeps_clear` lead
    there again.
    """
    if v == 0.0:
        return
    a = r.pose[2] + (0.0 if v > 0 else math.pi)
    way = np.array([math.cos(a), math.sin(a)])
    spot = r.pose[:2] + (ROBOT_RADIUS + grid.resolution / 2) * way
    d = r.near - r.pose[:2]
    ahead = d @ way > 0
    if ahead.any():
        k = np.argmin(np.hypot(*d[ahead].T))
        spot = r.near[ahead][k]
    i, j = cell(grid, spot)
    echoes[i, j] = 100


def mark_stuck(echoes: np.ndarray, grid: OccupancyGrid, r: Member, others) -> None:
    """Block the cells of ``r``'s laser returns that keep it from moving on.

    A robot that no command along its path keeps clear of (`keeps_clear`)
    stands too near returns the map does not hold: a door jamb's end or a
    box's corner, in a cell the beams passing by keep free. The plan led
    there through that cell and would lead there again. The returns within
    `STUCK_REACH` of the robot, but not on a teammate at ``others`` (K, 2),
    are blocked in ``echoes`` so the next plan keeps its distance.
    """
    if not len(r.returns):
        return
    d = np.hypot(*(r.returns - r.pose[:2]).T)
    pts = r.returns[d < STUCK_REACH]
    if len(others) and len(pts):
        gap = np.hypot(*(pts[:, None, :] - others[None, :, :]).transpose(2, 0, 1))
        pts = pts[gap.min(axis=1) > BODY + 0.1]
    for x, y in pts:
        i, j = cell(grid, (x, y))
        echoes[i, j] = 100


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


def _blocked_near(grid, occupied_level, echoes, pose, returns=None):
    """Centres (K, 2) of the blocked cells within a metre of ``pose``, m.

    With the laser's ``returns`` (P, 2) after them: a wall can stand in a
    cell the map holds free (one the beams only graze), never where the
    laser sees it.
    """
    i, j = cell(grid, pose)
    k = int(math.ceil(1.0 / grid.resolution))
    win = (slice(max(i - k, 0), i + k + 1), slice(max(j - k, 0), j + k + 1))
    ii, jj = np.nonzero((grid.logodds[win] > occupied_level) | (echoes[win] >= 2))
    cx = grid.origin[0] + (jj + win[1].start + 0.5) * grid.resolution
    cy = grid.origin[1] + (ii + win[0].start + 0.5) * grid.resolution
    cells = np.column_stack([cx, cy])
    if returns is None or not len(returns):
        return cells
    return np.vstack([cells, np.asarray(returns, dtype=float).reshape(-1, 2)])


def escape(
    grid: OccupancyGrid,
    occupied_level: float,
    echoes,
    pose,
    w_max: float,
    margin: float = 0.0,
    returns=None,
):
    """Return a command ``(v, w)`` backing a robot off the cell it is too near.

    None when no blocked cell is nearer than `keeps_clear` wants plus
    ``margin`` (m; the loop keeps backing off to ``BACK_OFF``), counting
    the laser's ``returns`` (P, 2) as blocked too. The robot
    turns in place until its front or its back points away from the near
    cells (the sum of their unit vectors, within 20 degrees), then drives
    that way at 0.1 m/s.
    """
    cells = _blocked_near(grid, occupied_level, echoes, pose, returns)
    if not len(cells):
        return None
    gap = pose[:2] - cells
    d = np.hypot(*gap.T)
    near = d < ROBOT_RADIUS + CLEARANCE + margin
    if not near.any():
        return None
    push = (gap[near] / d[near, None]).sum(axis=0)  # away from all the near cells
    away = math.atan2(push[1], push[0])
    err = wrap_angle(away - pose[2])
    if abs(err) <= math.radians(20):
        return 0.1, 0.0
    back = wrap_angle(err + math.pi)
    if abs(back) <= math.radians(20):
        return -0.1, 0.0
    turn = err if abs(err) < abs(back) else back
    return 0.0, math.copysign(w_max / 2, turn)


def keeps_clear(
    grid: OccupancyGrid,
    occupied_level: float,
    echoes,
    pose,
    v: float,
    w: float,
    mates,
    speed: float = 0.0,
    returns=None,
) -> bool:
    """Whether driving ``(v, w)`` from ``pose`` keeps clear until it could stop.

    The arc is followed for half a second at ``v`` or, if longer, for the
    distance the robot needs to brake (at `DEFAULT_ACCELERATION`) from the
    larger of ``v`` and its present ``speed`` (m/s): a robot at 0.5 m/s
    coasts 0.4 m after it is told to stop. Clear of the cells the map holds
    occupied (log-odds above ``occupied_level``) or that hold two ``echoes``
    (int, the grid's shape), of the laser's ``returns`` (P, 2, m) and of
    the teammates at ``mates`` (K, 2). A
    robot already too close may only move clearly away (``AWAY``): the
    nearest cell's centre is not where the wall is.
    """
    cx, cy = _blocked_near(grid, occupied_level, echoes, pose, returns).T
    u = max(v, speed, 0.0)
    reach = max(0.5 * v, u * CYCLE + u * u / (2 * DEFAULT_ACCELERATION))
    s = np.linspace(0.0, reach, 8)
    x, y, th = pose
    a = th + (w / v if v > 0 else 0.0) * s
    px = x + s * np.cos(a)
    py = y + s * np.sin(a)
    d = np.full(len(s), np.inf)
    if len(cx):
        d = np.hypot(px[:, None] - cx, py[:, None] - cy).min(axis=1)
    if len(mates):  # a teammate: a disc round its corners
        gap = np.hypot(px[:, None] - mates[:, 0], py[:, None] - mates[:, 1])
        d = np.minimum(d, gap.min(axis=1) - BODY)
    need = np.minimum(ROBOT_RADIUS + CLEARANCE, d[0] + AWAY * s)
    return bool((d[1:] >= need[1:]).all())
