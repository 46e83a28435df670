"""The episode runner: one controller drives one robot to a goal, recorded.

`run_episode` steps a robot at its 100 ms cycle (one `Robot.readsonar` poll
per cycle) with the controller's ``(v, w)`` until the goal is reached (the
odometry pose within ``tolerance`` of it: all a robot knows), the time runs
out, the robot stalls against an obstacle (a collision), or the controller
reports that it is trapped (``status == "local_minimum"``). It returns an
`Episode` of plain arrays with two verdicts: `Episode.true_success`, judged
on the true pose where the backend has one (the simulator: the controller's
"reached" counts only if the robot truly ends within `TRUE_TOLERANCE` of the
goal; what Lab 2's graded check counts), and beside it the robot's own,
`Episode.success` (odometry: drift alone puts a correct VFH more than 0.5 m
off in one or two episodes of ten in the clutter arena).
`run_episodes` runs many seeded start/goal pairs in a world, in parallel
processes if asked (spawn-safe).

Imports: the robot interface, the simulator and the world; never plotting.
"""

from __future__ import annotations

import concurrent.futures as cf
import copy
import math
import multiprocessing
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..p3dx import CYCLE, ROBOT_RADIUS
from ..robot import Robot
from ..sim import SimRobot, Simulator
from ..world import World, load_world
from .base import LOCAL_MINIMUM, Controller

__all__ = ["Episode", "run_episode", "run_episodes", "OUTCOMES", "TRUE_TOLERANCE"]

TRUE_TOLERANCE = 0.5
"""An episode succeeds when the true position ends this close to the goal, m."""

OUTCOMES = ("reached", "timeout", "collision", "local_minimum")
"""How an episode can end."""


@dataclass
class Episode:
    """One run of a controller, cycle by cycle (row 0 is before the first command).

    Attributes
    ----------
    time : numpy.ndarray, shape (T,)
        Robot clock, s, from 0.
    odometry : numpy.ndarray, shape (T, 3)
        Odometry pose, m and rad.
    truth : numpy.ndarray or None, shape (T, 3)
        True pose where the backend has one (the simulator), else None.
    sonar : numpy.ndarray, shape (T, 8)
        Sonar ranges, m.
    commands : numpy.ndarray, shape (T, 2)
        ``(v, w)`` commanded after each row's reading, m/s and rad/s (the
        last row's is 0).
    stalled : numpy.ndarray of bool, shape (T,)
        The robot reported a stall (pushing against an obstacle).
    clearance : numpy.ndarray or None, shape (T,)
        True distance from the robot's body (a disc of the Pioneer's radius)
        to the nearest wall, m, where the world and truth are known.
    outcome : str
        One of `OUTCOMES`.
    goal : numpy.ndarray or None, shape (2,)
        The goal (odometry frame), m.
    controller : str
        The controller's name.
    world : str
        The world's name ("" if unknown).
    seed : int or None
        The simulator's seed.
    wall_time : float
        Wall-clock seconds the episode took.
    """

    time: np.ndarray
    odometry: np.ndarray
    truth: np.ndarray | None
    sonar: np.ndarray
    commands: np.ndarray
    stalled: np.ndarray
    clearance: np.ndarray | None
    outcome: str
    goal: np.ndarray | None = None
    controller: str = ""
    world: str = ""
    seed: int | None = None
    wall_time: float = 0.0
    extra: dict = field(default_factory=dict)

    @property
    def success(self) -> bool:
        """Reached the goal by the odometry (the controller's word), no collision."""
        return self.outcome == "reached" and self.collisions == 0

    @property
    def true_error(self) -> float:
        """Distance from the final true position to the goal, m (nan when unknown)."""
        if self.truth is None or self.goal is None:
            return math.nan
        return float(np.hypot(*(self.truth[-1, :2] - self.goal)))

    @property
    def true_success(self) -> bool:
        """Reached the goal without touching anything, judged by the truth.

        The controller stopped at the goal, nothing was hit and, where the
        true pose is known, it ends within `TRUE_TOLERANCE` of the goal
        (without truth: `success`, the odometry's verdict).
        """
        if not self.success:
            return False
        return self.truth is None or self.true_error <= TRUE_TOLERANCE

    @property
    def duration(self) -> float:
        """Simulated seconds from the first command to the end, s."""
        return float(self.time[-1])

    @property
    def collisions(self) -> int:
        """Number of stalls (each start of a run of stalled cycles)."""
        s = self.stalled.astype(np.int8)
        return int(s[0] + np.count_nonzero(np.diff(s) == 1))

    @property
    def min_clearance(self) -> float:
        """Smallest true clearance, m (nan when unknown)."""
        return float(self.clearance.min()) if self.clearance is not None else math.nan

    @property
    def min_sonar(self) -> float:
        """Smallest sonar reading of the episode, m."""
        return float(self.sonar.min())

    @property
    def path_length(self) -> float:
        """Distance driven (true where known, else odometry), m."""
        p = self.truth if self.truth is not None else self.odometry
        return float(np.hypot(*np.diff(p[:, :2], axis=0).T).sum())


def _as_robot(robot, seed, start, sim_options=None) -> Robot:
    if isinstance(robot, Robot):
        return robot
    world = robot if isinstance(robot, World) else load_world(robot)
    sim = Simulator(world, seed=seed, **(sim_options or {}))
    return SimRobot(sim, sim.add_robot(start))


def run_episode(
    robot: Robot | World | str,
    controller: Controller,
    goal=None,
    max_time: float = 120.0,
    seed: int | None = None,
    start=None,
    tolerance: float | None = None,
    stop_on_collision: bool = True,
    sim_options: dict | None = None,
) -> Episode:
    """Drive ``robot`` with ``controller`` until it reaches the goal or gives up.

    Parameters
    ----------
    robot : Robot, World or str
        A robot (any backend), or a world (or its name) to build a simulated
        one in, seeded with ``seed`` and placed at ``start``.
    controller : Controller
        Anything with ``reset()``, ``command(sonar, pose) -> (v, w)``, a
        ``goal`` attribute and a ``status`` attribute; it is reset first.
    goal : array_like, shape (2,), optional
        Goal in the robot's odometry frame, m (default: the controller's).
    max_time : float
        Simulated (robot clock) time limit, s.
    seed : int, optional
        Simulator seed when ``robot`` is a world.
    start : array_like, shape (3,), optional
        Start pose when ``robot`` is a world (default: the world's).
    tolerance : float, optional
        Goal radius, m (default: the controller's, 0.3 m).
    stop_on_collision : bool
        End the episode at the first stall (outcome ``"collision"``).
    sim_options : dict, optional
        Keyword arguments of the `Simulator` built when ``robot`` is a world
        (e.g. ``{"end_faces": False}``).

    Returns
    -------
    Episode
    """
    wall0 = time.perf_counter()
    r = _as_robot(robot, seed, start, sim_options)
    if goal is not None:
        controller.goal = np.asarray(goal, dtype=float)[:2]
    if tolerance is not None:
        controller.tolerance = float(tolerance)
    controller.reset()
    has_truth = hasattr(r, "true_pose")
    st = r.state
    t0 = st.time
    rows_t, rows_odo, rows_true, rows_sonar, rows_cmd, rows_stall = (
        [],
        [],
        [],
        [],
        [],
        [],
    )

    def log(state):
        rows_t.append(state.time - t0)
        rows_odo.append(state.pose)
        rows_sonar.append(state.sonar)
        rows_stall.append(bool(state.stalled))
        if has_truth:
            rows_true.append(r.true_pose())

    log(st)
    outcome = "timeout"
    n_cycles = int(round(max_time / CYCLE))
    for _ in range(n_cycles):
        v, w = controller.command(st.sonar, st.pose)
        rows_cmd.append((v, w))
        if controller.status == "reached":
            outcome = "reached"
            break
        if controller.status == LOCAL_MINIMUM:
            outcome = LOCAL_MINIMUM
            break
        r.setvel(v)
        r.setrotvel(w)
        r.readsonar()
        st = r.state
        log(st)
        if st.stalled and stop_on_collision:
            outcome = "collision"
            break
    else:
        v, w = controller.command(st.sonar, st.pose)
        if controller.status == "reached":
            outcome = "reached"
    r.stop()
    rows_cmd.append((0.0, 0.0))
    rows_cmd = rows_cmd[: len(rows_t)]
    truth = np.array(rows_true) if has_truth else None
    world = getattr(getattr(r, "simulator", None), "world", None)
    clearance = None
    if truth is not None and world is not None:
        clearance = world.distance_to_walls(truth[:, :2]) - ROBOT_RADIUS
    return Episode(
        time=np.array(rows_t),
        odometry=np.array(rows_odo),
        truth=truth,
        sonar=np.array(rows_sonar),
        commands=np.array(rows_cmd, dtype=float).reshape(-1, 2),
        stalled=np.array(rows_stall, dtype=bool),
        clearance=clearance,
        outcome=outcome,
        goal=None if controller.goal is None else np.array(controller.goal),
        controller=getattr(controller, "name", type(controller).__name__),
        world=world.name if world is not None else "",
        seed=seed,
        wall_time=time.perf_counter() - wall0,
    )


def _one(job) -> Episode:
    world, controller, pair, seed, max_time, sim_options = job
    return run_episode(
        world,
        copy.deepcopy(controller),
        goal=pair.goal,
        start=pair.start,
        seed=seed,
        max_time=max_time,
        sim_options=sim_options,
    )


def run_episodes(
    world: World | str,
    controller: Controller,
    pairs,
    max_time: float = 120.0,
    seed: int = 0,
    jobs: int = 1,
    progress: bool | Callable = False,
    sim_options: dict | None = None,
) -> list[Episode]:
    """Run one episode per start/goal pair, each in its own seeded simulator.

    Parameters
    ----------
    world : World or str
        The world (or its name).
    controller : Controller
        Copied for every episode (pickled to the workers when ``jobs > 1``).
    pairs : sequence of StartGoal
        Start poses and goals (`robotlib.avoidance.start_goal_pairs`).
    max_time : float
        Time limit per episode, simulated s.
    seed : int
        Episode ``k``'s simulator is seeded with ``[seed, k]``.
    jobs : int
        Worker processes (``spawn``); 1 runs here, in order.
    progress : bool or callable
        True prints a progress line to stderr; a bar factory (called as
        ``progress(total=n, desc=...)``, e.g. ``robotlib.notebook.progress``)
        shows a bar that counts the episodes.
    sim_options : dict, optional
        Keyword arguments of each episode's `Simulator`.

    Returns
    -------
    list of Episode
        In the order of ``pairs``.
    """
    world = load_world(world) if isinstance(world, str) else world
    job_list = [
        (
            world,
            controller,
            p,
            int(np.random.SeedSequence([seed, k]).generate_state(1)[0]),
            max_time,
            sim_options,
        )
        for k, p in enumerate(pairs)
    ]
    out: list[Episode | None] = [None] * len(job_list)
    bar = None
    if callable(progress):
        bar = progress(total=len(job_list), desc=f"{controller.name} in {world.name}")

    def tick(done: int) -> None:
        if bar is not None:
            bar.update(1)
            if done == len(job_list):
                bar.close()
        elif progress:
            print(  # noqa: T201 - the progress bar
                f"\r{controller.name} in {world.name}: {done}/{len(job_list)}",
                end="" if done < len(job_list) else "\n",
                file=sys.stderr,  # noqa: T201 - the progress bar
            )

    if jobs <= 1:
        for k, job in enumerate(job_list):
            out[k] = _one(job)
            tick(k + 1)
        return out
    ctx = multiprocessing.get_context("spawn")
    with cf.ProcessPoolExecutor(jobs, mp_context=ctx) as pool:
        futures = {pool.submit(_one, job): k for k, job in enumerate(job_list)}
        for done, fut in enumerate(cf.as_completed(futures), 1):
            out[futures[fut]] = fut.result()
            tick(done)
    return out
