"""The navigation loop: localize, plan, follow, avoid, re-plan, stop at the goal.

A `Navigator` (or the one-call `navigate`) drives any `robotlib.robot.Robot`
(``sim:``, ``tcp://``, ``serial://``) to a goal in a world it has a map of.
It knows only what the robot reports (sonar and odometry): MCL (`MCL.best`
by default) localizes it from there, starting without knowing where it is;
A* plans on the map's configuration space; a `PathFollower` follows with
pure pursuit and hands obstacles the map does not hold to an avoider; the
sonar echoes the map does not explain are marked in the configuration space
and the path is re-planned. A small state machine: LOCALIZE (turn in place,
wander when that is not enough) until the cloud is tight, then FOLLOW or
AVOID (the follower's hand-over), back to LOCALIZE when the sonar stops
agreeing with the map. At the goal it says "reached" only if a second,
independently seeded filter fed the same readings agrees (`NavSettings.confirm`)
and no place it believed in earlier and gave up explains the whole drive
behind it better (`NavSettings.rival_margin`); otherwise it localizes again
(around that place if there is one); and where the map looks the same turned (a
warehouse of racks) and the drive since localizing fits the turned place as
well, it says "ambiguous" instead (`robotlib.planning.aliasing`). Its knobs
are a `NavSettings`. The true pose is
recorded when the backend has one (``true_pose()``, the simulator), for
evaluation only: it never steers.

Imports the world, sonar, localization and planning layers; never plots,
never sleeps (each poll of the robot is its 100 ms cycle).
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from .._random import as_rng
from ..avoidance import VFH
from ..localization import BEST, MCL
from ..p3dx import ROBOT_LENGTH_REAR, ROBOT_RADIUS, ROBOT_WIDTH
from ..sensing import expected_ranges
from ..world import World, compose, relative, wrap_angle
from .aliasing import drive_score, fits, look_alike, map_symmetries
from .cspace import CSpace, configuration_space
from .follow import PathFollower, PurePursuit, cross_track, sonar_points
from .grid import astar, path_length
from .navigation import AVOID, FOLLOW, LOCALIZE, MODES, Navigation, NavSettings

__all__ = [
    "Navigation",
    "NavSettings",
    "Navigator",
    "navigate",
    "LOCALIZE",
    "FOLLOW",
    "AVOID",
    "MODES",
]

TURN_MARGIN = math.hypot(ROBOT_LENGTH_REAR, ROBOT_WIDTH / 2) - ROBOT_RADIUS + 0.01
"""Margin over `ROBOT_RADIUS` of the default configuration space, m: the
robot's rear corners sweep a circle this much wider when it turns in place."""


def _spread(mcl: MCL) -> tuple[float, float]:
    """Weighted position spread (m) and heading spread (rad) of the particles."""
    p, w = mcl.particles, mcl.weights / mcl.weights.sum()
    mx, my = w @ p[:, 0], w @ p[:, 1]
    pos = math.sqrt(w @ ((p[:, 0] - mx) ** 2 + (p[:, 1] - my) ** 2))
    r = math.hypot(w @ np.cos(p[:, 2]), w @ np.sin(p[:, 2]))
    head = math.sqrt(max(0.0, -2.0 * math.log(max(r, 1e-12))))
    return pos, head


def _share_near(mcl: MCL, pose, radius: float) -> float:
    """Share of the particles' weight within ``radius`` m of ``pose``."""
    p, w = mcl.particles, mcl.weights
    near = np.hypot(p[:, 0] - pose[0], p[:, 1] - pose[1]) < radius
    return float(w[near].sum() / w.sum())


class Navigator:
    """Drive a robot to ``goal`` in the mapped ``world``: localize, plan, follow, avoid.

    First the robot turns in place (and, if that is not enough, wanders with
    the avoider) until the particle cloud is tight; then it plans from the
    estimate, follows with pure pursuit, avoids unexplained obstacles and
    re-plans (when new echoes are marked, at most every ``replan_period``,
    when the path ends short of the goal, or when the estimate is
    ``off_track`` of the path), and stops when the estimate is within
    ``goal_tolerance`` of the goal (`NavSettings`). A navigator runs once.

    Parameters
    ----------
    world : World
        The map it plans and localizes on (the robot's surroundings may hold
        more: boxes the map does not show).
    goal : array_like, shape (2,)
        The goal, m.
    mcl : MCL, optional
        The filter (default: ``MCL.best(world, rng=rng)``, global
        localization, with a second one to confirm the goal,
        `NavSettings.confirm`; a filter given here is trusted alone).
    rng : numpy.random.Generator, int or None
        Seeds the default filter.
    avoider : object, optional
        A controller with ``reset()`` and ``command(sonar, pose)`` (default
        Lab 2's `robotlib.avoidance.VFH`, with its default settings); e.g.
        `robotlib.planning.StopAndTurn`.
    cspace : CSpace, optional
        The configuration space (default: `configuration_space` of the map
        with `TURN_MARGIN`).
    planner : callable, optional
        ``planner(cspace, start, goal) -> path`` ((K, 2) m, or None when
        there is none); default A* (`astar`) with the cost map.
    law : callable, optional
        Pure pursuit's steering law (see `PurePursuit`).
    settings : NavSettings, optional
        The loop's knobs (default `NavSettings()`).

    Attributes
    ----------
    mode : int
        `LOCALIZE`, `FOLLOW` or `AVOID`, the state of the last cycle.
    outcome : str
        ``""`` while running, then as `Navigation.outcome`.
    """

    def __init__(
        self,
        world: World,
        goal,
        *,
        mcl: MCL | None = None,
        rng: np.random.Generator | int | None = None,
        avoider=None,
        cspace: CSpace | None = None,
        planner=None,
        law=None,
        settings: NavSettings | None = None,
    ):
        self.settings = NavSettings() if settings is None else settings
        if not isinstance(self.settings, NavSettings):
            kind = type(self.settings).__name__
            raise TypeError(f"settings must be a NavSettings, got {kind}")
        self.world = world
        self.goal = np.asarray(goal, dtype=float)[:2]
        if cspace is None:
            cspace = configuration_space(world, margin=TURN_MARGIN)
        cspace.node(self.goal, "goal")
        self.cspace = cspace
        kld = {**BEST["kld"], "n_min": 3000}  # keep look-alike places longer
        second = None
        if mcl is None and self.settings.confirm > 0:  # own stream: first's unchanged
            second = MCL.best(world, rng=as_rng(rng).spawn(1)[0], kld=kld)
        if mcl is None:
            mcl = MCL.best(world, rng=rng, kld=kld)
        self.mcl, self.second = mcl, second
        # turns that map the walls onto themselves: no sensor tells them apart
        self.symmetries = map_symmetries(world) if second is not None else []
        self.avoider = VFH() if avoider is None else avoider
        self.planner, self.law = planner, law
        self.mode, self.outcome = LOCALIZE, ""
        self.localized_at = float("nan")
        self._ran = False

    # -- the states ---------------------------------------------------------
    def _start_localizing(self, now: float) -> None:
        """Enter LOCALIZE: turn in place from ``now``, no follower, no marks."""
        self.avoider.reset()
        self.mode, self._steps = LOCALIZE, 0
        self._window = deque(maxlen=self.settings.window)
        self._spin_start, self._wander_until = now, -1.0
        self._follower, self._hits, self._hits_dirty = None, [], False

    def _localize(self, z, pose, now: float) -> tuple[float, float]:
        """LOCALIZE: spin (or wander) until the cloud is tight, then FOLLOW."""
        s = self.settings
        if self._steps >= s.min_filter_steps and self._settled():
            self.mode, self._need_plan, self._agree = FOLLOW, True, 1.0
            self._since = len(self._rec["est"])
            self._best_left, self._best_time = np.inf, now
            if math.isnan(self.localized_at):
                self.localized_at = now
            return 0.0, 0.0
        if now < self._wander_until:
            return self.avoider.command(z, pose)
        if now - self._spin_start > 2 * (2 * math.pi / s.spin) + 4.0:
            # two turns did not do it: wander a while, then turn again
            self.avoider.reset()
            self._wander_until = self._spin_start = now + 8.0
        return 0.0, s.spin

    def _drive(self, z, pose, now: float) -> tuple[float, float]:
        """FOLLOW or AVOID: stop at the goal, notice being lost, mark, re-plan."""
        s = self.settings
        expected = expected_ranges(self.world, pose)[0]
        self._agree += 0.025 * (float(fits(z, expected).mean()) - self._agree)
        if np.hypot(*(pose[:2] - self.goal)) < s.goal_tolerance:
            rival = self._better_place(pose, z)
            if rival is None and self._settled() and self._confirmed(pose):
                self.outcome = "ambiguous" if self._aliased() else "reached"
                return 0.0, 0.0
            # doubt: give this place (and the second filter's) up, and start
            # again, both filters around a place the drive fits better if any
            self._given_up.append((pose.copy(), self._odo.copy()))
            if self.second is not None:
                self._given_up.append((self._second_place(), self._odo.copy()))
            self.mcl.reset(rival)
            if self.second is not None:
                self.second.reset(rival)
            self._start_localizing(now)
            self._doubt_times.append(now)
            return 0.0, 0.0
        if self._agree < s.lost_agreement or now - self._best_time > s.no_progress:
            # lost: forget the pose and the marks, localize again
            self._given_up.append((pose.copy(), self._odo.copy()))
            self.mcl.reset()
            self._start_localizing(now)
            self._lost_times.append(now)
            return 0.0, 0.0
        odd = (z < s.hit_range) & (z < expected - s.unexplained)
        if odd.any():
            self._hits.extend(sonar_points(pose, np.where(odd, z, np.inf), s.hit_range))
            self._hits_dirty = True
        follower = self._follower
        if follower is not None and not follower.avoiding:
            off = cross_track(follower.pursuit.path, pose[:2]) > s.off_track
            self._need_plan = self._need_plan or follower.done or bool(off)
        marks_due = self._hits_dirty and now - self._last_plan >= s.replan_period
        if self._need_plan or marks_due:
            self._replan(pose, now)
            if self.outcome:
                return 0.0, 0.0
        v, w = self._follower.command(z, pose, expected)
        self.mode = AVOID if self._follower.avoiding else FOLLOW
        return v, w

    def _note_belief(self, estimate, odometry) -> None:
        """Record after a filter step whether the cloud is tight and unimodal."""
        s = self.settings
        pos, head = _spread(self.mcl)
        share = _share_near(self.mcl, estimate, s.mode_radius)
        tight = pos < s.spread and head < 0.15 and share >= s.mode_share
        self._window.append((tight, estimate.copy(), odometry.copy()))

    def _settled(self) -> bool:
        """Whether the belief is unimodal and consistent over the window.

        The last ``window`` filter steps all had a tight cloud with at least
        ``mode_share`` of its weight near the estimate, and every one of
        their estimates, carried forward by the odometry since, lands within
        ``consistent`` m (and 0.1 rad) of the newest: a filter that jumped
        from one place to another in that time has not settled
        (`NavSettings`).
        """
        s = self.settings
        if len(self._window) < s.window or not all(t for t, _, _ in self._window):
            return False
        _, est, odo = self._window[-1]
        for _, e, o in self._window:
            p = compose(e, relative(o, odo))
            off = math.hypot(p[0] - est[0], p[1] - est[1])
            if off > s.consistent or abs(wrap_angle(p[2] - est[2])) > 0.1:
                return False
        return True

    def _second_place(self) -> np.ndarray:
        """Return the second filter's estimate, carried to now by the odometry."""
        return compose(self._second_at, relative(self._odo_at, self._odo))

    def _confirmed(self, pose) -> bool:
        """Whether the second filter is tight and within ``confirm`` of ``pose``."""
        if self.second is None:
            return True
        pos, head = _spread(self.second)
        off = math.hypot(*(self._second_place()[:2] - pose[:2]))
        return (
            off < self.settings.confirm and pos < self.settings.spread and head < 0.15
        )

    def _better_place(self, pose, z) -> np.ndarray | None:
        """Return a place that explains the whole drive better than ``pose``, or None.

        The candidates are the places given up earlier (at the goal in
        doubt, or lost) and the second filter's, each carried to now by the
        odometry, unless within ``rival_radius`` of ``pose``; the best of
        them by `drive_score`, if it beats ``pose`` by ``rival_margin``
        (`NavSettings`).
        """
        s = self.settings
        places = [compose(p, relative(o, self._odo)) for p, o in self._given_up]
        if self.second is not None:
            places.append(self._second_place())
        places = [p for p in places if math.dist(p[:2], pose[:2]) > s.rival_radius]
        if not places:
            return None
        rows = len(self._rec["odo"])
        odometry = np.vstack([np.reshape(self._rec["odo"], (rows, 3)), self._odo])
        scans = np.vstack([np.reshape(self._rec["sonar"], (rows, len(z))), z])
        own = drive_score(self.world, pose, odometry, scans)
        scores = [drive_score(self.world, p, odometry, scans) for p in places]
        k = int(np.argmax(scores))
        return places[k] if scores[k] > own + s.rival_margin else None

    def _aliased(self) -> bool:
        """Whether a symmetry of the map explains the drive as well (`look_alike`)."""
        if not self.symmetries:
            return False
        rec, k = self._rec, self._since
        poses, scans = np.array(rec["est"][k::5]), np.array(rec["sonar"][k::5])
        return look_alike(self.world, poses, scans, self.symmetries) is not None

    def _replan(self, pose, now: float) -> None:
        """Plan from ``pose`` around the marks; a new follower (or no_path)."""
        s = self.settings
        path = _plan(self.cspace, self._hits, pose, self.goal, self.planner)
        self._last_plan, self._need_plan, self._hits_dirty = now, False, False
        if path is None:
            self.outcome = "no_path"
            return
        self._plans.append(path)
        self._plan_times.append(now)
        left = path_length(path)
        if left < self._best_left - 0.5:
            self._best_left, self._best_time = left, now
        was = self._follower is not None and self._follower.avoiding
        pursuit = PurePursuit(
            path, s.lookahead, s.speed, goal_tolerance=0.05, law=self.law
        )
        self._follower = PathFollower(pursuit, self.avoider, unexplained=s.unexplained)
        self._follower.avoiding = was

    # -- the loop -----------------------------------------------------------
    def run(self, robot, max_time: float = 180.0) -> Navigation:
        """Drive ``robot`` (anywhere in the world) until it stops; the record.

        Parameters
        ----------
        robot : robotlib.robot.Robot
            The robot.
        max_time : float
            Give up after this much robot time, s.

        Returns
        -------
        Navigation
        """
        if self._ran:
            raise RuntimeError("a Navigator runs once; make a new one")
        self._ran = True
        s = self.settings
        self._plans, self._plan_times, self._lost_times = [], [], []
        self._doubt_times, self._given_up = [], []
        self._need_plan, self._last_plan, self._agree = False, -np.inf, 1.0
        self._best_left, self._best_time = np.inf, np.inf
        self._start_localizing(0.0)
        has_truth = hasattr(robot, "true_pose")
        names = ("time", "truth", "odo", "est", "cmd", "mode", "sonar", "st", "agree")
        rec = self._rec = {k: [] for k in names}
        self._since = 0
        robot.readsonar()
        t0 = robot.state.time
        odo_filter = robot.state.pose.copy()
        est_at, odo_at = self.mcl.last_estimate.copy(), odo_filter.copy()
        if self.second is not None:
            self._second_at = self.second.last_estimate.copy()
        cycle = 0
        while True:
            st = robot.state
            z, odo, now = st.sonar, st.pose, st.time - t0
            if cycle > 0 and cycle % s.filter_every == 0:
                est_at = self.mcl.step(odo_filter, odo, z)
                if self.second is not None:
                    self._second_at = self.second.step(odo_filter, odo, z)
                odo_filter, odo_at = odo.copy(), odo.copy()
                self._steps += 1
                self._note_belief(np.asarray(est_at, dtype=float), odo_at)
            self._odo_at, self._odo = odo_at, odo
            pose = compose(est_at, relative(odo_at, odo))
            v = w = 0.0
            if st.stalled:
                self.outcome = "collision"
            elif now > max_time:
                self.outcome = "timeout"
            else:
                if self.mode == LOCALIZE:
                    v, w = self._localize(z, pose, now)
                if self.mode != LOCALIZE:  # (converged this cycle, or before)
                    v, w = self._drive(z, pose, now)
            if self.outcome:
                v = w = 0.0
            robot.setvel(v)
            robot.setrotvel(w)
            rec["time"].append(now)
            rec["truth"].append(robot.true_pose() if has_truth else np.full(3, np.nan))
            rec["odo"].append(odo.copy())
            rec["est"].append(pose)
            rec["cmd"].append((v, w))
            rec["mode"].append(self.mode)
            rec["sonar"].append(z.copy())
            rec["st"].append(bool(st.stalled))
            rec["agree"].append(self._agree)
            if self.outcome:
                break
            robot.readsonar()
            cycle += 1
        robot.stop()
        return Navigation(
            np.array(rec["time"]),
            np.array(rec["truth"]),
            np.array(rec["odo"]),
            np.array(rec["est"]),
            np.array(rec["cmd"], dtype=float),
            np.array(rec["mode"], dtype=np.int8),
            np.array(rec["sonar"]),
            np.array(rec["st"], dtype=bool),
            self._plans,
            np.array(self._plan_times),
            np.array(self._hits).reshape(-1, 2),
            self.goal,
            self.outcome,
            self.localized_at,
            np.array(rec["agree"]),
            np.array(self._lost_times),
            np.array(self._doubt_times),
        )


def navigate(
    robot,
    world: World,
    goal,
    *,
    mcl: MCL | None = None,
    rng: np.random.Generator | int | None = None,
    avoider=None,
    cspace: CSpace | None = None,
    planner=None,
    law=None,
    max_time: float = 180.0,
    settings: NavSettings | None = None,
) -> Navigation:
    """Drive ``robot`` to ``goal`` in the mapped ``world``: one `Navigator` run.

    ``robot`` may be anywhere in the world; ``max_time`` (s) is the robot
    time it is given; the other arguments are `Navigator`'s.

    Returns
    -------
    Navigation
    """
    nav = Navigator(
        world, goal, mcl=mcl, rng=rng, avoider=avoider, cspace=cspace,
        planner=planner, law=law, settings=settings,
    )  # fmt: skip
    return nav.run(robot, max_time)


def _astar_path(cs: CSpace, start, goal) -> np.ndarray | None:
    plan = astar(cs, start, goal)
    return plan.path if plan.found else None


def _plan(cs0: CSpace, hits, pose, goal, planner=None) -> np.ndarray | None:
    """Plan with A* from the estimate to the goal around the marked echoes.

    Echoes near the robot or the goal are left out (the robot must be able
    to leave where it is); without a path around the echoes, plan on the
    map alone.
    """
    attempts = []
    if hits:
        h = np.asarray(hits)
        # the marks are grown from their cells' centres: a mark 0.15 m
        # beyond the radius, rounded to its cell and the goal to its own,
        # blocked the goal's cell on a 10 cm grid (ValueError from A*)
        clear = cs0.radius + 0.15 + 1.5 * cs0.resolution
        keep = (np.hypot(*(h - pose[:2]).T) > clear) & (np.hypot(*(h - goal).T) > clear)
        attempts.append(cs0.with_points(h[keep]))
    attempts.append(cs0)
    for cs in attempts:
        start = cs.nearest_free(pose[:2], 0.6)
        if start is None:
            continue
        path = (planner or _astar_path)(cs, start, goal)
        if path is not None and len(path):
            path = np.array(path, dtype=float).reshape(-1, 2)
            path[-1] = goal
            return np.vstack([pose[:2], path]) if len(path) > 1 else path
    return None
