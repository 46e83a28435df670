"""The exploration loop: map, find frontiers, choose, plan, follow, avoid, go home.

An `Exploration` runs one or more robots in one `robotlib.sim.Simulator`
on one shared log-odds map. Each 100 ms cycle:

1. every robot adds its reading (the laser scan, or the eight sonars) to
   the map at the pose it believes (the truth, or its own grid FastSLAM's
   best particle when ``ExploreSettings.pose`` is ``"slam"``);
2. every ``decide_period`` (or at once when a robot needs one) the
   frontiers are found again (those facing only a small closed pocket, the
   inside of a box, left out); a robot whose path now crosses a known wall
   re-plans; a robot that reached its target, whose target is no longer a
   frontier, or that waited too long for a teammate, gets a new target
   (`robotlib.exploration.choose`: nearest, utility, or coordinated among
   the team, gains discounted near the targets teammates drive to and near
   where they stand, which their sensors see; path costs count the turn in
   place before a robot can set off); with no reachable frontier left it
   drives home;
3. every robot follows its A* path (planned on the inflated known map,
   unknown cells blocked) with pure pursuit, as fast as it can still stop
   short of the known walls, the near sonar echoes and its teammates
   (`robotlib.exploration.member.keeps_clear`), else creeping along the
   path itself, else turning in place (one way until it can drive; the
   laser returns that stopped it are blocked for the next plan), or
   backing off a wall it came too near; a robot stops while a teammate is
   close ahead of it and, after ``wait_time``, re-plans around its
   teammates;
4. the simulator steps; a robot that stalls against a wall or a robot
   counts a collision, and a stall (the robot's own report) blocks the
   cell it ran into on the map.

The true poses are used to judge (coverage, collisions) and, with ``pose``
``"true"``, to map; they never steer otherwise. Imports the simulator,
mapping, planning and this package's parts; never plots, never sleeps.
"""

from __future__ import annotations

import math

import numpy as np

from .._random import as_rng
from ..mapping import OccupancyGrid, map_score
from ..p3dx import CYCLE, ROBOT_RADIUS
from ..planning import astar
from ..sim import Simulator
from ..world import World
from .choice import choose, frontier_costs, information_gain, known_space
from .frontiers import classify, frontier_cells, frontier_regions, open_frontier
from .member import (
    BACK_OFF,
    DONE,
    EXPLORE,
    HOME,
    Member,
    cell,
    clear_bodies,
    count_echoes,
    escape,
    keeps_clear,
    mark_contact,
    mark_stuck,
    teammate_ahead,
)
from .metrics import ExplorationResult, explored_fraction, reachable_area
from .settings import ExploreSettings

__all__ = ["Exploration", "explore"]

SLOWER = (1.0, 0.5, 0.25)
"""The shares of pure pursuit's speed tried, in turn, when the next arc
does not keep clear (`keeps_clear`) before the robot stops to turn."""

NEAR = 0.2
"""Look-ahead (m) along the path when pure pursuit's own arc does not keep
clear (`Exploration._hug_path`)."""

CREEP = 0.15
"""Speed (m/s) along the path at `NEAR` look-ahead."""

POCKET = 1.0
"""Unknown pieces smaller than this (m^2), their rim all known, are not
explored (`robotlib.exploration.frontiers.open_frontier`): a generated hall's
boxes are at most 0.9 m wide."""

PARK = 2.5
"""A robot driving home that a teammate blocks this near its start (m) parks
there: the start poses of a team lie in one file, and the first one home
would otherwise stand in the way of the others."""


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
            self.robots.append(Member(k, body, s, world, rng.spawn(1)[0]))
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

    def _no_teammate_at(self, r: Member) -> bool:
        """Whether no teammate is near enough to ``r`` to be what it touched."""
        mates = self._positions(skip=r)
        gap = np.hypot(*(mates - r.pose[:2]).T) if len(mates) else [np.inf]
        return bool(np.min(gap) > 2 * ROBOT_RADIUS + 0.15)

    def _held_up(self, r: Member) -> bool:
        """Whether a teammate holds ``r`` up.

        Close ahead of it, or near it while no arc along its path keeps clear
        (a teammate parked on its way home).
        """
        mates = self._positions(skip=r)
        gap = np.hypot(*(mates - r.pose[:2]).T) if len(mates) else [np.inf]
        near = np.min(gap) < self.settings.keep_out + 2 * ROBOT_RADIUS
        return bool(r.blocked or (r.stuck > 0 and near))

    def _needs_target(self, r: Member, state, frontier) -> bool:
        if r.mode != EXPLORE or r.target is None or r.follower is None:
            return True
        if (
            r.follower.done
            or np.hypot(*(r.pose[:2] - r.target)) < self.settings.goal_tolerance
        ):
            return True
        i, j = cell(self.grid, r.target)
        win = frontier[max(i - 2, 0) : i + 3, max(j - 2, 0) : j + 3]
        return not win.any()

    def _path_blocked(self, r: Member, cs) -> bool:
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
        frontier = open_frontier(state, frontier, round(POCKET / g.resolution**2))
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
        # what teammates will see: where they drive to, and where they stand
        taken = [
            r.target
            for r in self.robots
            if r not in needy and r.mode == EXPLORE and r.target is not None
        ]
        taken += [r.pose[:2] for r in self.robots if r not in needy]
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
                costs[n], targets[n] = frontier_costs(
                    c, start, regions, heading=r.pose[2], turn=s.speed / s.w_max
                )
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
            elif r.mode == HOME and self._held_up(r) and r.distance_home() < PARK:
                r.stop()  # parked by home
            else:
                self._go_home(r, spaces[n])

    def _plan(self, r: Member, cs, goal) -> bool:
        start = _start(cs, r.pose)
        if start is None or not cs.is_free(goal):
            return False
        plan = astar(cs, start, goal)
        if not plan.found:
            return False
        path = plan.path[2::3] if len(plan.path) > 3 else plan.path[1:]
        r.drive_to(np.vstack([r.pose[:2], path, plan.path[-1:]]), goal, self.settings)
        return True

    def _go_home(self, r: Member, cs) -> None:
        if not self.settings.go_home or np.hypot(*(r.pose[:2] - r.home[:2])) < 0.3:
            r.stop()
            return
        home = cs.nearest_free(r.home, 1.0)
        if home is not None and self._plan(r, cs, home):
            r.mode = HOME
        else:
            r.stop()

    # -- driving ------------------------------------------------------------
    def _command(self, r: Member) -> tuple[float, float]:
        if r.spin > 0:
            r.spin -= abs(r.body.state.velocity[1]) * CYCLE
            return 0.0, self.settings.w_max
        if r.follower is None:
            return 0.0, 0.0
        s = self.settings
        v, w = r.follower.command(r.pose)
        if v == 0.0 and w != 0.0:  # turning in place: keep the way it began
            r.turn = r.turn or math.copysign(1.0, w)
            w = math.copysign(abs(w), r.turn)
        mates = self._positions(skip=r)
        # two robots each waiting for the other: the later one keeps waiting
        # (a teammate that waits for this one is no reason to wait)
        ahead = [
            o.pose[:2]
            for o in self.robots
            if o is not r and not (o.blocked and o.index > r.index)
        ]
        r.blocked = v > 0 and teammate_ahead(r, np.reshape(ahead, (-1, 2)), s.keep_out)
        if r.blocked:
            r.waited += CYCLE
            return 0.0, 0.0
        r.waited = 0.0
        if r.backing:
            off = escape(
                self.grid, s.occupied_level, self.echoes, r.pose, s.w_max, BACK_OFF,
                r.returns,
            )  # fmt: skip
            r.backing = off is not None
            if r.backing:
                return off
        if v > 0:  # on the same arc, as fast as keeps clear until it can stop
            speed = float(r.body.state.velocity[0])
            for f in SLOWER:
                if keeps_clear(
                    self.grid, s.occupied_level, self.echoes, r.pose, f * v, f * w,
                    mates, speed, r.returns,
                ):  # fmt: skip
                    v, w, r.turn = f * v, f * w, 0.0
                    break
            else:
                r.stuck += CYCLE
                off = escape(
                    self.grid, s.occupied_level, self.echoes, r.pose, s.w_max, 0.0,
                    r.returns,
                )  # fmt: skip
                if off is not None:  # too near a wall: back off it first
                    r.backing = True
                    return off
                return self._hug_path(r, mates, speed)
        if r.follower.done:
            if r.mode == HOME:
                r.stop()
        return v, w

    def _hug_path(self, r: Member, mates, speed: float) -> tuple[float, float]:
        """Creep along the path itself when pure pursuit's arc does not keep clear.

        The look-ahead point cuts corners (out of a door into a corridor,
        round a jamb); the planned path keeps its distance from the walls.
        The robot steers at `CREEP` speed to the point `NEAR` ahead on its
        path, or turns in place towards it (towards where the path goes, so
        the turn does not flip as the far point's bearing crosses zero).
        """
        s = self.settings
        p = r.follower
        v, w = p.law(r.pose, p.point_at(p.s + NEAR), CREEP, s.w_max)
        if v > 0 and keeps_clear(
            self.grid, s.occupied_level, self.echoes, r.pose, v, w, mates, speed,
            r.returns,
        ):  # fmt: skip
            r.turn = 0.0
            return v, w
        mark_stuck(self.echoes, self.grid, r, mates)
        r.turn = r.turn or math.copysign(1.0, w)
        return 0.0, math.copysign(s.w_max / 2, r.turn)

    # -- the loop -----------------------------------------------------------
    def step(self) -> None:
        """Run one 100 ms cycle: sense, decide (now and then), drive, step."""
        s = self.settings
        for r in self.robots:
            r.sense(self.grid, s.sensor)
            count_echoes(self.echoes, self.grid, r, self._positions(skip=r))
        clear_bodies(self.grid, self.robots, s.free_level)
        needs = any(
            r.mode == EXPLORE and (r.follower is None or r.follower.done)
            for r in self.robots
        )
        if self.cycle % self._every == 0 or needs:
            self.decide()
        for r in self.robots:
            v, w = self._command(r)
            r.command, r.speed = (v, w), float(r.body.state.velocity[0])
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
            if r.body.state.stalled and self._no_teammate_at(r):
                mark_contact(self.echoes, self.grid, r, r.command[0] or r.speed)
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
