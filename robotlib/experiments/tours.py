"""A seeded tour of any building: A* legs between far-apart free cells, pure pursuit.

`drive_tour` drives the simulated Pioneer through a world's free space and
logs it as `drive_route` does (a `RouteLog`: odometry, sonar and truth after
each step of about ``step_length``), so the paper's experiment runs in any
world file, real buildings included. The driver knows the true pose and the
true map (it makes the route; the filters never see it):

1. pick a goal: a random reachable cell with at least ``clearance`` to the
   walls (a corridor's or a room's middle) at least ``min_leg`` away along
   the free space (or half the farthest such cell, when the world is small);
2. plan to it with A* on the configuration space (robot radius plus
   ``margin``, with the cost map that keeps to the middle);
3. follow the path with pure pursuit on the true pose, one velocity command
   per 100 ms cycle, logging a step each ``step_length`` of odometry travel;
   a new goal when the path ends.

``kidnap=K`` moves the robot, just before step ``K``'s motion, to a random
reachable pose (its own random stream, so the route up to step ``K`` is the
one without a kidnapping) without touching its odometry: the filters are
not told. The sonar runs only on each step's last cycle (the log reads
nothing else), which keeps a 46,000-segment building at a few seconds a
route.

Imports the simulator, the world and the planners; never an estimator.
"""

from __future__ import annotations

import weakref

import numpy as np

from ..p3dx import ROBOT_RADIUS
from ..planning import PurePursuit, astar, configuration_space, wavefront_field
from ..sim import Simulator
from ..world import World
from .routes import MAX_STEPS, RouteLog

__all__ = ["drive_tour", "tour_space", "TourSpace"]

RESOLUTION = 0.05
"""Cell side of the tour's configuration space, m (the filters' too: one
distance field serves both)."""


class TourSpace:
    """Where a tour may go in a world: its configuration space and reachable cells.

    Parameters
    ----------
    world : World
        The map.
    margin : float
        Clearance over the robot radius kept by the planner, m.
    clearance : float
        Goals and kidnapping poses lie at least this far from walls, m.

    Attributes
    ----------
    cspace : robotlib.planning.CSpace
        The configuration space (the component reachable from the start only).
    reachable : numpy.ndarray of bool, shape (ny, nx)
        Cells connected to the start's.
    goals : numpy.ndarray of int64, shape (G, 2)
        Candidate goal cells ``(i, j)``.
    """

    def __init__(self, world: World, margin: float = 0.1, clearance: float = 0.45):
        cs = configuration_space(world, RESOLUTION, ROBOT_RADIUS, margin)
        start = np.asarray(world.start[:2], dtype=float)
        near = cs.nearest_free(start, 1.0)
        if near is None:
            raise ValueError(f"the start {tuple(start)} of {world.name!r} is not free")
        field = wavefront_field(cs, near)
        self.reachable = field >= 0
        blocked = cs.blocked | ~self.reachable
        self.cspace = type(cs)(blocked, cs.cost, cs.origin, cs.resolution, cs.radius)
        dist = world.distance_field(RESOLUTION).data
        goals = np.argwhere(self.reachable & (dist >= clearance))
        if len(goals) < 2:
            goals = np.argwhere(self.reachable)
        self.goals = goals

    def random_pose(self, rng: np.random.Generator) -> np.ndarray:
        """Draw a random pose ``(x, y, theta)`` at a goal cell's centre, m and rad."""
        c = self.goals[rng.integers(len(self.goals))]
        x, y = self.cspace.to_metres(c)
        return np.array([x, y, np.pi - 2 * np.pi * rng.random()])

    def pick_goal(self, xy, rng: np.random.Generator, min_leg: float) -> np.ndarray:
        """Draw a goal (m) at least ``min_leg`` (or half the farthest) away."""
        cs = self.cspace
        here = cs.nearest_free(xy, 1.0)
        if here is None:
            here = cs.to_metres(self.goals[0])
        field = wavefront_field(cs, here)
        moves = field[self.goals[:, 0], self.goals[:, 1]] * cs.resolution
        far = min(float(min_leg), 0.5 * float(moves.max()))
        pool = self.goals[(moves >= far) & (moves > 0)]
        if len(pool) == 0:
            pool = self.goals
        return cs.to_metres(pool[rng.integers(len(pool))])


_SPACES: dict[int, tuple] = {}


def tour_space(world: World) -> TourSpace:
    """Return the `TourSpace` of ``world`` (default settings), kept while it lives."""
    key = id(world)
    entry = _SPACES.get(key)
    if entry is not None and entry[0]() is world:
        return entry[1]
    space = TourSpace(world)
    _SPACES[key] = (weakref.ref(world, lambda _: _SPACES.pop(key, None)), space)
    return space


def _plan(space: TourSpace, xy, goal):
    cs = space.cspace
    here = cs.nearest_free(xy, 1.0)
    if here is None:
        return None
    plan = astar(cs, here, goal)
    return plan.path if plan.found and len(plan.path) > 1 else None


def drive_tour(
    world: World,
    seed: int,
    n_steps: int = MAX_STEPS,
    step_length: float = 0.5,
    kidnap: int | None = None,
    speed: float = 0.4,
    min_leg: float = 8.0,
    space: TourSpace | None = None,
) -> RouteLog:
    """Drive a seeded tour of ``world``'s free space (see the module docstring).

    Parameters
    ----------
    world : World
        Where to drive (the robot starts at ``world.start``).
    seed : int
        Seeds the simulator (odometry slip, sonar noise), the goals and the
        kidnapping pose; the same seed gives the same log, bit for bit.
    n_steps : int
        Scans in the log, the start's included.
    step_length : float
        Odometry travel per step, m.
    kidnap : int, optional
        Move the robot to a random pose just before step ``kidnap``
        (``1 <= kidnap < n_steps``), so ``truth[kidnap]`` is in the new place.
    speed : float
        Pure pursuit's cruise speed, m/s.
    min_leg : float
        Shortest leg to a goal, m (along the free space).
    space : TourSpace, optional
        Default `tour_space(world)`.

    Returns
    -------
    RouteLog
        With ``kidnapped_at`` set when ``kidnap`` is given.
    """
    if kidnap is not None and not 1 <= kidnap < n_steps:
        raise ValueError(f"kidnap must be in [1, {n_steps}), got {kidnap}")
    space = tour_space(world) if space is None else space
    sim = Simulator(world, seed=seed)
    body = sim.add_robot()
    rng = np.random.default_rng([seed, 4])
    kidnap_rng = np.random.default_rng([seed, 5])
    body.enable_sonar(False)
    odo, sonar, truth = [], [], []
    trace = [body.true_pose.copy()]
    cycle = sim.step

    def step():
        cycle()
        trace.append(body.true_pose.copy())

    def scan_and_log():
        body.enable_sonar(True)
        step()
        state = body.state
        body.enable_sonar(False)  # (this clears the readings: read them first)
        odo.append(state.pose)
        sonar.append(state.sonar)
        truth.append(body.true_pose.copy())

    scan_and_log()
    pursuit = None
    for k in range(1, n_steps):
        if k == kidnap:
            body.command("STOP")
            for _ in range(30):
                if not body.moving:
                    break
                step()
            body.set_true_pose(space.random_pose(kidnap_rng))
            pursuit = None
        start = body.state.pose[:2].copy()
        for _cycle in range(200):
            if pursuit is None or pursuit.done:
                goal = space.pick_goal(body.true_pose[:2], rng, min_leg)
                path = _plan(space, body.true_pose[:2], goal)
                if path is None:  # nowhere to go from here: turn on the spot
                    body.command("VEL", 0.0)
                    body.command("RVEL", 0.5)
                    step()
                    continue
                pursuit = PurePursuit(path, lookahead=0.6, speed=speed, w_max=0.8)
            v, w = pursuit.command(body.true_pose)
            body.command("VEL", v)
            body.command("RVEL", w)
            step()
            if body.stalled:  # never expected: drop the path, plan again
                pursuit = None
            if np.hypot(*(body.state.pose[:2] - start)) >= step_length:
                break
        scan_and_log()
    return RouteLog(
        np.array(odo),
        np.array(sonar),
        np.array(truth),
        world,
        seed,
        kidnap,
        np.array(trace),
    )
