"""The navigation loop: localize, plan, follow, avoid, re-plan, stop at the goal.

`navigate` drives any `robotlib.robot.Robot` (``sim:``, ``tcp://``,
``serial://``) to a goal in a world it has a map of. It knows only what the
robot reports (sonar and odometry): MCL (`MCL.best` by default) localizes
it from there, starting without knowing where it is; A* plans on the map's
configuration space; a `PathFollower` follows with pure pursuit and hands
obstacles the map does not hold to an avoider; the sonar echoes the map
does not explain are marked in the configuration space and the path is
re-planned. The true pose is recorded when the backend has one
(``true_pose()``, the simulator), for evaluation only: it never steers.

Imports the world, sonar, localization and planning layers; never plots,
never sleeps (each poll of the robot is its 100 ms cycle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..localization import BEST, MCL
from ..p3dx import ROBOT_LENGTH_REAR, ROBOT_RADIUS, ROBOT_WIDTH
from ..sensing import expected_ranges
from ..world import World, compose, relative
from .cspace import CSpace, configuration_space
from .follow import PathFollower, PurePursuit, StopAndTurn, cross_track, sonar_points
from .grid import astar, path_length

__all__ = ["Navigation", "navigate", "LOCALIZE", "FOLLOW", "AVOID", "MODES"]

LOCALIZE, FOLLOW, AVOID = 0, 1, 2

TURN_MARGIN = math.hypot(ROBOT_LENGTH_REAR, ROBOT_WIDTH / 2) - ROBOT_RADIUS + 0.01
"""Margin over `ROBOT_RADIUS` of the default configuration space, m: the
robot's rear corners sweep a circle this much wider when it turns in place."""
MODES = ("localize", "follow", "avoid")
"""Names of the per-cycle modes in `Navigation.mode`."""


@dataclass
class Navigation:
    """What `navigate` did, cycle by cycle (plain arrays).

    Attributes
    ----------
    time : numpy.ndarray, shape (T,)
        Robot clock since the start, s.
    truth : numpy.ndarray, shape (T, 3)
        True pose where the backend reports one (else NaN), m and rad.
    odometry, estimate : numpy.ndarray, shape (T, 3)
        Odometry pose and the MCL estimate (advanced by odometry between
        filter steps), m and rad.
    command : numpy.ndarray, shape (T, 2)
        ``(v, w)`` sent, m/s and rad/s.
    mode : numpy.ndarray of int8, shape (T,)
        `LOCALIZE`, `FOLLOW` or `AVOID`.
    sonar : numpy.ndarray, shape (T, 8)
        Ranges, m.
    stalled : numpy.ndarray of bool, shape (T,)
        The robot reported a stall (it touched something).
    plans : list of numpy.ndarray
        Every path planned, (K, 2) each, m.
    plan_times : numpy.ndarray, shape (P,)
        When each was planned, s.
    hits : numpy.ndarray, shape (H, 2)
        Sonar echoes marked as unmapped obstacles, m.
    goal : numpy.ndarray, shape (2,)
        The goal, m.
    outcome : str
        ``"reached"`` (the estimate within the tolerance of the goal),
        ``"collision"``, ``"timeout"`` or ``"no_path"``.
    localized_at : float
        When the filter first converged, s (NaN if never).
    agreement : numpy.ndarray, shape (T,)
        Smoothed share of sonar readings that agree with the map at the
        estimate.
    lost_times : numpy.ndarray
        When the robot counted itself lost and localized again, s.
    """

    time: np.ndarray
    truth: np.ndarray
    odometry: np.ndarray
    estimate: np.ndarray
    command: np.ndarray
    mode: np.ndarray
    sonar: np.ndarray
    stalled: np.ndarray
    plans: list = field(default_factory=list)
    plan_times: np.ndarray = field(default_factory=lambda: np.zeros(0))
    hits: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    goal: np.ndarray = field(default_factory=lambda: np.zeros(2))
    outcome: str = ""
    localized_at: float = float("nan")
    agreement: np.ndarray = field(default_factory=lambda: np.zeros(0))
    lost_times: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def reached(self) -> bool:
        """The loop stopped at the goal (by its own estimate)."""
        return self.outcome == "reached"

    @property
    def final_error(self) -> float:
        """Distance from the final true position to the goal, m (NaN: no truth)."""
        return float(np.hypot(*(self.truth[-1, :2] - self.goal)))

    @property
    def success(self) -> bool:
        """Reached, no stall, and truly within 0.3 m of the goal."""
        return self.reached and not self.stalled.any() and self.final_error <= 0.3

    @property
    def duration(self) -> float:
        """Simulated (robot) time used, s."""
        return float(self.time[-1]) if len(self.time) else 0.0


def _spread(mcl: MCL) -> tuple[float, float]:
    """Weighted position spread (m) and heading spread (rad) of the particles."""
    p, w = mcl.particles, mcl.weights / mcl.weights.sum()
    mx, my = w @ p[:, 0], w @ p[:, 1]
    pos = math.sqrt(w @ ((p[:, 0] - mx) ** 2 + (p[:, 1] - my) ** 2))
    r = math.hypot(w @ np.cos(p[:, 2]), w @ np.sin(p[:, 2]))
    head = math.sqrt(max(0.0, -2.0 * math.log(max(r, 1e-12))))
    return pos, head


def navigate(
    robot,
    world: World,
    goal,
    *,
    mcl: MCL | None = None,
    rng: np.random.Generator | int | None = None,
    avoider=None,
    cspace: CSpace | None = None,
    speed: float = 0.3,
    lookahead: float = 0.5,
    goal_tolerance: float = 0.15,
    max_time: float = 180.0,
    filter_every: int = 2,
    spread: float = 0.15,
    min_filter_steps: int = 15,
    spin: float = 0.5,
    hit_range: float = 1.5,
    unexplained: float = 0.3,
    replan_period: float = 1.0,
    off_track: float = 0.7,
    lost_agreement: float = 0.62,
    no_progress: float = 30.0,
    planner=None,
    law=None,
) -> Navigation:
    """Drive ``robot`` to ``goal`` in the mapped ``world``.

    First the robot turns in place (and, if that is not enough, wanders with
    the avoider) until the particle cloud is tight (``spread``); then it
    plans with A* from the estimate, follows with pure pursuit, avoids
    unexplained obstacles and re-plans (when new echoes are marked, at most
    every ``replan_period``, when the path ends short of the goal, or when
    the estimate is ``off_track`` of the path), and stops when the estimate
    is within ``goal_tolerance`` of the goal.

    Parameters
    ----------
    robot : robotlib.robot.Robot
        The robot; it may be anywhere in the world.
    world : World
        The map it plans and localizes on (the robot's surroundings may hold
        more: boxes the map does not show).
    goal : array_like, shape (2,)
        The goal, m.
    mcl : MCL, optional
        The filter (default: ``MCL.best(world, rng=rng)``, global
        localization).
    rng : numpy.random.Generator, int or None
        Seeds the default filter.
    avoider : object, optional
        A controller with ``reset()`` and ``command(sonar, pose)`` (default
        `StopAndTurn`); e.g. ``robotlib.avoidance.VFH``.
    cspace : CSpace, optional
        The configuration space (default: `configuration_space` of the map
        with `TURN_MARGIN`).
    speed, lookahead : float
        Pure pursuit's cruise speed (m/s) and look-ahead (m).
    goal_tolerance : float
        Stop within this distance of the goal (by the estimate), m.
    max_time : float
        Give up after this much robot time, s.
    filter_every : int
        Cycles between filter steps.
    spread : float
        The filter has converged when the particles' position spread is
        below this, m (and the heading spread below 0.15 rad).
    min_filter_steps : int
        Filter steps before convergence is trusted.
    spin : float
        Turn rate while localizing, rad/s.
    hit_range, unexplained : float
        A front echo shorter than ``hit_range`` and than the map's expected
        reading by ``unexplained`` is an unmapped obstacle, m.
    replan_period, off_track : float
        Re-planning limits, s and m.
    no_progress : float
        The robot counts itself lost, too, when its plans have not got
        0.5 m shorter for this long, s (it may be driving a look-alike
        place's plan).
    planner : callable, optional
        ``planner(cspace, start, goal) -> path`` ((K, 2) m, or None when
        there is none); default A* (`astar`) with the cost map.
    law : callable, optional
        Pure pursuit's steering law (see `PurePursuit`).
    lost_agreement : float
        The robot counts itself lost, and localizes again from scratch, when
        the share of sonar readings that agree with the map at the estimate
        (within 0.25 m + 10 %), smoothed over about 4 s, falls below this.

    Returns
    -------
    Navigation
    """
    goal = np.asarray(goal, dtype=float)[:2]
    cs0 = configuration_space(world, margin=TURN_MARGIN) if cspace is None else cspace
    cs0.node(goal, "goal")
    if mcl is None:
        kld = {**BEST["kld"], "n_min": 3000}  # keep look-alike places longer
        mcl = MCL.best(world, rng=rng, kld=kld)
    avoider = StopAndTurn() if avoider is None else avoider
    avoider.reset()
    has_truth = hasattr(robot, "true_pose")
    names = ("time", "truth", "odo", "est", "cmd", "mode", "sonar", "st", "agree")
    rec = {k: [] for k in names}
    plans, plan_times, hits, lost_times = [], [], [], []
    robot.readsonar()
    t0 = robot.state.time
    odo_filter = robot.state.pose.copy()
    est_at, odo_at = mcl.last_estimate.copy(), odo_filter.copy()
    mode, steps, cycle = LOCALIZE, 0, 0
    localized_at = float("nan")
    follower = None
    need_plan, hits_dirty, last_plan = False, False, -np.inf
    wander_until, spin_start, agree = -1.0, 0.0, 1.0
    best_left, best_time = np.inf, np.inf
    outcome = ""
    while True:
        st = robot.state
        z, odo, now = st.sonar, st.pose, st.time - t0
        if cycle > 0 and cycle % filter_every == 0:
            est_at = mcl.step(odo_filter, odo, z)
            odo_filter, odo_at = odo.copy(), odo.copy()
            steps += 1
        pose = compose(est_at, relative(odo_at, odo))
        v = w = 0.0
        if st.stalled:
            outcome = "collision"
        elif now > max_time:
            outcome = "timeout"
        elif mode == LOCALIZE:
            pos, head = _spread(mcl)
            if steps >= min_filter_steps and pos < spread and head < 0.15:
                mode, need_plan, agree = FOLLOW, True, 1.0
                best_left, best_time = np.inf, now
                if math.isnan(localized_at):
                    localized_at = now
            elif now < wander_until:
                v, w = avoider.command(z, pose)
            else:
                if now - spin_start > 2 * (2 * math.pi / spin) + 4.0:
                    # two turns did not do it: wander a while, then turn again
                    avoider.reset()
                    wander_until, spin_start = now + 8.0, now + 8.0
                v, w = 0.0, spin
        if mode != LOCALIZE and not outcome:
            expected = expected_ranges(world, pose)[0]
            ok = np.abs(z - expected) < 0.25 + 0.1 * expected
            agree += 0.025 * (float(ok.mean()) - agree)
            if np.hypot(*(pose[:2] - goal)) < goal_tolerance:
                outcome = "reached"
            elif agree < lost_agreement or now - best_time > no_progress:
                # lost: forget the pose and the marks, localize again
                mcl.reset()
                avoider.reset()
                mode, steps, spin_start, wander_until = LOCALIZE, 0, now, -1.0
                follower, hits, hits_dirty = None, [], False
                lost_times.append(now)
            else:
                odd = (z < hit_range) & (z < expected - unexplained)
                if odd.any():
                    hits.extend(sonar_points(pose, np.where(odd, z, np.inf), hit_range))
                    hits_dirty = True
                if follower is not None and not follower.avoiding:
                    off = cross_track(follower.pursuit.path, pose[:2]) > off_track
                    need_plan = need_plan or follower.done or bool(off)
                if need_plan or (hits_dirty and now - last_plan >= replan_period):
                    path = _plan(cs0, hits, pose, goal, planner)
                    last_plan, need_plan, hits_dirty = now, False, False
                    if path is None:
                        outcome = "no_path"
                    else:
                        plans.append(path)
                        plan_times.append(now)
                        left = path_length(path)
                        if left < best_left - 0.5:
                            best_left, best_time = left, now
                        was = follower is not None and follower.avoiding
                        pursuit = PurePursuit(
                            path, lookahead, speed, goal_tolerance=0.05, law=law
                        )
                        follower = PathFollower(
                            pursuit, avoider, unexplained=unexplained
                        )
                        follower.avoiding = was
                if not outcome:
                    v, w = follower.command(z, pose, expected)
                    mode = AVOID if follower.avoiding else FOLLOW
        if outcome:
            v = w = 0.0
        robot.setvel(v)
        robot.setrotvel(w)
        rec["time"].append(now)
        rec["truth"].append(robot.true_pose() if has_truth else np.full(3, np.nan))
        rec["odo"].append(odo.copy())
        rec["est"].append(pose)
        rec["cmd"].append((v, w))
        rec["mode"].append(mode)
        rec["sonar"].append(z.copy())
        rec["st"].append(bool(st.stalled))
        rec["agree"].append(agree)
        if outcome:
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
        plans,
        np.array(plan_times),
        np.array(hits).reshape(-1, 2),
        goal,
        outcome,
        localized_at,
        np.array(rec["agree"]),
        np.array(lost_times),
    )


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
        keep = (np.hypot(*(h - pose[:2]).T) > cs0.radius + 0.15) & (
            np.hypot(*(h - goal).T) > cs0.radius + 0.15
        )
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
