"""The exploration loop: map, find frontiers, choose, plan, follow, avoid, go home.

An `Exploration` runs one or more robots in one `robotlib.sim.Simulator`
on one shared log-odds map. Each 100 ms cycle:

1. every robot adds its reading (the laser scan, or the eight sonars) to
   the map at the pose it believes (the truth, or its own grid FastSLAM's
   best particle when ``ExploreSettings.pose`` is ``"slam"``);
2. every ``decide_period`` (or at once when a robot needs one) the
   frontiers are found again; a robot whose path now crosses a known wall
   re-plans; a robot that reached its target, whose target is no longer a
   frontier, or that waited too long for a teammate, gets a new target
   (`robotlib.exploration.choose`: nearest, utility, or coordinated among
   the team); with no reachable frontier left it drives home;
3. every robot follows its A* path (planned on the inflated known map,
   unknown cells blocked) with pure pursuit, handing over to a sonar
   stop-and-turn avoider when something is very close in front; a robot
   stops while a teammate is close ahead of it and, after
   ``wait_time``, re-plans around its teammates;
4. the simulator steps; a robot that stalls against a wall or a robot
   counts a collision.

The true poses are used to judge (coverage, collisions) and, with ``pose``
``"true"``, to map; they never steer otherwise. Imports the simulator,
mapping, planning and this package's parts; never plots, never sleeps.
"""

from __future__ import annotations

import math

import numpy as np

from .._random import as_rng
from ..mapping import (
    SONAR_SETTINGS,
    FastSLAMSettings,
    GridFastSLAM,
    OccupancyGrid,
    map_score,
)
from ..p3dx import (
    CYCLE,
    DEFAULT_ACCELERATION,
    ROBOT_LENGTH_FRONT,
    ROBOT_LENGTH_REAR,
    ROBOT_RADIUS,
    ROBOT_WIDTH,
    SONAR_POSES,
)
from ..planning import PurePursuit, astar
from ..planning.follow import sonar_points
from ..sim import Simulator
from ..world import World, wrap_angle
from .choice import choose, frontier_costs, information_gain, known_space
from .frontiers import classify, frontier_cells, frontier_regions
from .metrics import ExplorationResult, explored_fraction, reachable_area
from .settings import ExploreSettings

__all__ = ["Exploration", "explore", "EXPLORE", "HOME", "DONE"]

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

PARK = 2.5
"""A robot driving home that a teammate blocks this near its start (m) parks
there: the start poses of a team lie in one file, and the first one home
would otherwise stand in the way of the others."""

EXPLORE, HOME, DONE = "explore", "home", "done"
"""A robot's modes: driving to a frontier, driving home, home (or idle)."""


class _Robot:
    """One team member: its body, its belief, its target and path."""

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

    def distance_home(self) -> float:
        """Distance from the believed position to the start, m."""
        return float(np.hypot(*(self.pose[:2] - self.home[:2])))

    def remaining_path(self) -> np.ndarray:
        """Return the part of the path still ahead, (K, 2) m."""
        p = self.follower
        k = int(np.searchsorted(p.cum, p.s, side="right")) - 1
        return p.path[max(k, 0) :]


class Exploration:
    """Robots exploring ``world`` from ``starts`` on one shared map.

    Parameters
    ----------
    world : World
        The truth (the robots know nothing of it but their start poses).
    starts : array_like, shape (R, 3)
        Start poses, m and rad; known to the whole team.
    settings : ExploreSettings, optional
        The knobs.
    rng : numpy.random.Generator, int or None
        Seeds the simulator (slip, sonar and laser noise) and SLAM.
    frontiers : callable, optional
        ``frontiers(state) -> mask``, bool ``(ny, nx)`` from the cell states:
        replaces `frontier_cells` (Lab 7 plugs a student's in).
    chooser : callable, optional
        Replaces `choose`, same arguments and result.
    """

    def __init__(
        self,
        world: World,
        starts,
        settings: ExploreSettings | None = None,
        rng: np.random.Generator | int | None = None,
        frontiers=None,
        chooser=None,
    ):
        self.frontiers = frontier_cells if frontiers is None else frontiers
        self.chooser = choose if chooser is None else chooser
        self.settings = s = ExploreSettings() if settings is None else settings
        starts = np.asarray(starts, dtype=float).reshape(-1, 3)
        if len(starts) < 1:
            raise ValueError("need at least one start pose")
        rng = as_rng(rng)
        self.world = world
        self.sim = Simulator(world, seed=rng.spawn(1)[0])
        self.robots = []
        for k, pose in enumerate(starts):
            body = self.sim.add_robot(pose)
            body.command("SETV", max(s.speed, 0.75))
            self.robots.append(_Robot(k, body, s, world, rng.spawn(1)[0]))
        self.grid = OccupancyGrid.for_world(world, s.resolution)
        self.echoes = np.zeros(self.grid.shape, dtype=np.int16)
        self.reachable = reachable_area(world, s.resolution)
        self.radius = ROBOT_RADIUS + s.margin
        self.cycle = 0
        self.times: list[float] = []
        self.coverage: list[float] = []
        self.snapshots: list[tuple] = []
        self.wall_collisions = 0
        self.robot_collisions = 0
        self._every = max(1, round(s.decide_period / CYCLE))
        self._sample = max(1, round(s.coverage_period / CYCLE))
        self._snap = round(s.snapshot_period / CYCLE) if s.snapshot_period else 0
        self.finished = False

    # -- deciding -----------------------------------------------------------
    def _positions(self, skip=None) -> np.ndarray:
        return np.array([r.pose[:2] for r in self.robots if r is not skip]).reshape(
            -1, 2
        )

    def _needs_target(self, r: _Robot, state, frontier) -> bool:
        if r.mode != EXPLORE or r.target is None or r.follower is None:
            return True
        if (
            r.follower.done
            or np.hypot(*(r.pose[:2] - r.target)) < self.settings.goal_tolerance
        ):
            return True
        i, j = _cell(self.grid, r.target)
        win = frontier[max(i - 2, 0) : i + 3, max(j - 2, 0) : j + 3]
        return not win.any()

    def _path_blocked(self, r: _Robot, cs) -> bool:
        if r.follower is None:
            return False
        ahead = r.remaining_path()
        return bool((~cs.is_free(ahead[1:])).any()) if len(ahead) > 1 else False

    def decide(self) -> None:
        """Find frontiers, check paths, give targets to the robots that need one."""
        s = self.settings
        g = self.grid
        state = classify(g, s.free_level, s.occupied_level)
        frontier = np.asarray(self.frontiers(state))
        if frontier.shape != state.shape:
            raise ValueError(
                f"frontiers(state) gave shape {frontier.shape}, not {state.shape}"
            )
        frontier = frontier.astype(bool)
        regions = frontier_regions(frontier, g.origin, g.resolution, s.min_frontier)
        robots_xy = self._positions()
        echoes = self.echoes >= 2
        cs = known_space(
            state, g.origin, g.resolution, self.radius, robots_xy, (), echoes
        )
        needy, spaces = [], []
        for r in self.robots:
            if r.spin > 0:
                continue
            waited = r.waited > s.wait_time * (1 + r.index)
            if (
                waited
                or self._needs_target(r, state, frontier)
                or self._path_blocked(r, cs)
                or r.stuck > 2 * self.settings.wait_time
            ):
                needy.append(r)
                spaces.append(
                    known_space(
                        state,
                        g.origin,
                        g.resolution,
                        self.radius,
                        robots_xy,
                        self._positions(skip=r),
                        echoes,
                    )  # fmt: skip
                    if waited
                    else cs
                )
        if not needy:
            return
        taken = [r.target for r in self.robots if r not in needy and r.mode == EXPLORE]
        centroids = np.array([f.centroid for f in regions]).reshape(-1, 2)
        gains = information_gain(
            state, g.origin, g.resolution, centroids, s.gain_radius
        )
        costs = np.full((len(needy), len(regions)), np.inf)
        targets = []
        for n, (r, c) in enumerate(zip(needy, spaces, strict=True)):
            start = _start(c, r.pose)
            targets.append(np.array([f.target for f in regions]).reshape(-1, 2))
            if start is not None and regions:
                costs[n], targets[n] = frontier_costs(c, start, regions)
        pick = (
            np.asarray(
                self.chooser(
                    costs,
                    gains,
                    centroids,
                    s.strategy,
                    s.beta,
                    s.discount_radius,
                    taken,
                )
            )
            .reshape(-1)
            .astype(np.int64)
        )
        if len(pick) != len(needy):
            raise ValueError(
                f"the chooser gave {len(pick)} targets for {len(needy)} robots"
            )
        for n, r in enumerate(needy):
            if pick[n] >= 0 and self._plan(r, spaces[n], targets[n][pick[n]]):
                r.mode = EXPLORE
                r.targets.append(r.target.copy())
            elif spaces[n] is not cs and r.mode != HOME:
                r.waited = 0.0  # nothing reachable around the teammates: wait again
            elif r.mode == HOME and r.blocked and r.distance_home() < PARK:
                r.mode, r.follower, r.target = DONE, None, None  # parked by home
            else:
                self._go_home(r, spaces[n])

    def _plan(self, r: _Robot, cs, goal) -> bool:
        start = _start(cs, r.pose)
        if start is None or not cs.is_free(goal):
            return False
        plan = astar(cs, start, goal)
        if not plan.found:
            return False
        path = plan.path[2::3] if len(plan.path) > 3 else plan.path[1:]
        r.drive_to(np.vstack([r.pose[:2], path, plan.path[-1:]]), goal, self.settings)
        return True

    def _go_home(self, r: _Robot, cs) -> None:
        if not self.settings.go_home or np.hypot(*(r.pose[:2] - r.home[:2])) < 0.3:
            r.mode, r.follower, r.target = DONE, None, None
            return
        home = cs.nearest_free(r.home, 1.0)
        if home is not None and self._plan(r, cs, home):
            r.mode = HOME
        else:
            r.mode, r.follower, r.target = DONE, None, None

    def _clear_bodies(self) -> None:
        """Mark the cells under every robot's body free: it stands there, no wall.

        The laser and sonar see teammates' bodies; without this, a teammate
        would leave a trail of obstacles on the shared map.
        """
        g = self.grid
        k = int(math.ceil(BODY / g.resolution))
        level = -(self.settings.free_level + 0.1)
        for r in self.robots:
            i, j = _cell(g, r.pose)
            win = (slice(max(i - k, 0), i + k + 1), slice(max(j - k, 0), j + k + 1))
            ii, jj = np.mgrid[win]
            cx = g.origin[0] + (jj + 0.5) * g.resolution
            cy = g.origin[1] + (ii + 0.5) * g.resolution
            c, si = math.cos(r.pose[2]), math.sin(r.pose[2])
            dx, dy = cx - r.pose[0], cy - r.pose[1]
            along, across = c * dx + si * dy, c * dy - si * dx
            pad = g.resolution / 2
            inside = (along <= ROBOT_LENGTH_FRONT + pad) & (
                along >= -ROBOT_LENGTH_REAR - pad
            )
            inside &= np.abs(across) <= ROBOT_WIDTH / 2 + pad
            cells = g.logodds[win]
            cells[inside] = np.minimum(cells[inside], level)

    def _mark_echoes(self, r: _Robot) -> None:
        """Count the near sonar echoes not explained by a teammate, per cell."""
        if r.spin > 0:
            return
        z = np.full(len(SONAR_POSES), np.inf)
        z[AXIS] = r.body.state.sonar[AXIS]
        pts = sonar_points(r.pose, z, ECHO_RANGE)
        others = self._positions(skip=r)
        if len(others) and len(pts):
            d = np.hypot(*(pts[:, None, :] - others[None, :, :]).transpose(2, 0, 1))
            pts = pts[d.min(axis=1) > ROBOT_RADIUS + 0.15]
        for x, y in pts:
            i, j = _cell(self.grid, (x, y))
            self.echoes[i, j] = min(self.echoes[i, j] + 1, 100)

    # -- driving ------------------------------------------------------------
    def _teammate_ahead(self, r: _Robot) -> bool:
        v = max(float(r.body.state.velocity[0]), 0.0)
        reach = self.settings.keep_out + v * v / (2 * DEFAULT_ACCELERATION)
        for o in self.robots:
            if o is r:
                continue
            d = o.pose[:2] - r.pose[:2]
            if math.hypot(*d) < reach:
                bearing = wrap_angle(math.atan2(d[1], d[0]) - r.pose[2])
                if abs(bearing) < math.pi / 3:
                    return True
        return False

    def _safe(self, r: _Robot, v: float, w: float) -> bool:
        """Whether driving ``(v, w)`` for half a second keeps clear.

        Clear of the known walls, the sonar's echoes and the teammates;
        moving away from one already too close is allowed.
        """
        g, s = self.grid, self.settings
        i, j = _cell(g, r.pose)
        k = int(math.ceil(1.0 / g.resolution))
        win = (slice(max(i - k, 0), i + k + 1), slice(max(j - k, 0), j + k + 1))
        occ = (g.logodds[win] > s.occupied_level) | (self.echoes[win] >= 2)
        ii, jj = np.nonzero(occ)
        cx = g.origin[0] + (jj + win[1].start + 0.5) * g.resolution
        cy = g.origin[1] + (ii + win[0].start + 0.5) * g.resolution
        x, y, th = r.pose
        t = np.linspace(0.0, 0.5, 6)
        a = th + w * t
        px = x + v * t * np.cos(a)
        py = y + v * t * np.sin(a)
        d = np.full(len(t), np.inf)
        if len(cx):
            near = np.hypot(px[:, None] - cx, py[:, None] - cy).min(axis=1)
            d = near
        mates = self._positions(skip=r)
        if len(mates):  # a teammate: a disc round its corners
            gap = np.hypot(px[:, None] - mates[:, 0], py[:, None] - mates[:, 1])
            d = np.minimum(d, gap.min(axis=1) - BODY)
        return bool(d[1:].min() >= min(ROBOT_RADIUS + 0.02, d[0] - 0.005))

    def _command(self, r: _Robot) -> tuple[float, float]:
        if r.spin > 0:
            r.spin -= abs(r.body.state.velocity[1]) * CYCLE
            return 0.0, self.settings.w_max
        if r.follower is None:
            return 0.0, 0.0
        v, w = r.follower.command(r.pose)
        r.blocked = v > 0 and self._teammate_ahead(r)
        if r.blocked:
            r.waited += CYCLE
            return 0.0, 0.0
        r.waited = 0.0
        if v > 0 and not self._safe(r, v, w):
            r.stuck += CYCLE  # turn in place towards the path (always safe)
            return 0.0, math.copysign(self.settings.w_max / 2, w)
        if r.follower.done:
            if r.mode == HOME:
                r.mode, r.follower, r.target = DONE, None, None
        return v, w

    # -- the loop -----------------------------------------------------------
    def step(self) -> None:
        """Run one 100 ms cycle: sense, decide (now and then), drive, step."""
        s = self.settings
        for r in self.robots:
            r.sense(self.grid, s.sensor)
            self._mark_echoes(r)
        self._clear_bodies()
        needs = any(
            r.mode == EXPLORE and (r.follower is None or r.follower.done)
            for r in self.robots
        )
        if self.cycle % self._every == 0 or needs:
            self.decide()
        for r in self.robots:
            v, w = self._command(r)
            r.body.command("VEL", v)
            r.body.command("RVEL", w)
        self.sim.step()
        self.cycle += 1
        for r in self.robots:
            if r.body.stalled and not r.stalled:
                near = [
                    np.hypot(*(o.body.true_pose[:2] - r.body.true_pose[:2]))
                    for o in self.robots
                    if o is not r
                ]
                if near and min(near) < 2 * ROBOT_RADIUS + 0.05:
                    self.robot_collisions += 1
                else:
                    self.wall_collisions += 1
            r.stalled = r.body.stalled
            r.truth.append(r.body.true_pose.copy())
            r.estimates.append(r.pose.copy())
        if self.cycle % self._sample == 0:
            self.times.append(self.sim.time)
            self.coverage.append(
                explored_fraction(self.grid, self.reachable, s.free_level)
            )
        if self._snap and self.cycle % self._snap == 0:
            self.snapshots.append(self._snapshot())
        self.finished = all(r.mode == DONE for r in self.robots)

    def _snapshot(self) -> tuple:
        poses = np.array([r.body.true_pose for r in self.robots])
        targets = np.array(
            [
                r.target if r.target is not None else [np.nan, np.nan]
                for r in self.robots
            ]
        )
        return (self.sim.time, self.grid.logodds.astype(np.float16), poses, targets)

    def run(self) -> ExplorationResult:
        """Step until every robot is home (or idle) or ``max_time``; return the run."""
        s = self.settings
        limit = round(s.max_time / CYCLE)
        while not self.finished and self.cycle < limit:
            self.step()
        if not self.times or self.times[-1] < self.sim.time:
            self.times.append(self.sim.time)
            self.coverage.append(
                explored_fraction(self.grid, self.reachable, s.free_level)
            )
        if self._snap:
            self.snapshots.append(self._snapshot())
        at_home = all(
            np.hypot(*(r.body.true_pose[:2] - r.home[:2])) < PARK for r in self.robots
        )
        outcome = (
            "timeout" if not self.finished else ("home" if at_home else "explored")
        )
        return ExplorationResult(
            map=self.grid.copy(),
            times=np.array(self.times),
            coverage=np.array(self.coverage),
            paths=[np.array(r.truth) for r in self.robots],
            estimates=[np.array(r.estimates) for r in self.robots],
            score=map_score(self.grid, self.world, s.resolution, s.occupied_level),
            wall_collisions=self.wall_collisions,
            robot_collisions=self.robot_collisions,
            outcome=outcome,
            duration=self.sim.time,
            snapshots=self.snapshots,
            targets=[np.array(r.targets).reshape(-1, 2) for r in self.robots],
        )


def _start(cs, pose):
    """Where a robot at ``pose`` starts planning: its cell, or the nearest free one."""
    return pose[:2] if cs.is_free(pose[:2]) else cs.nearest_free(pose, 1.0)


def _cell(grid: OccupancyGrid, xy) -> tuple[int, int]:
    ny, nx = grid.shape
    j = int((xy[0] - grid.origin[0]) // grid.resolution)
    i = int((xy[1] - grid.origin[1]) // grid.resolution)
    return min(max(i, 0), ny - 1), min(max(j, 0), nx - 1)


def explore(
    world: World,
    start=None,
    settings: ExploreSettings | None = None,
    rng: np.random.Generator | int | None = None,
    frontiers=None,
    chooser=None,
) -> ExplorationResult:
    """Explore ``world`` with one robot from ``start`` (default ``world.start``).

    See `Exploration` (``frontiers`` and ``chooser`` replace the library's
    `frontier_cells` and `choose`); ``robotlib.exploration.explore_team``
    runs a team.
    """
    start = world.start if start is None else start
    return Exploration(world, [start], settings, rng, frontiers, chooser).run()
