"""`Localized`: any avoidance controller, aimed by a map-based pose estimate.

A controller on odometry alone aims at where its odometry says the goal is,
and the odometry drifts (in the simulator about 0.4 m in 12 m of weaving,
several metres in 30 m): on the generated worlds of
`robotlib.world.generate_world` half the episodes that VFH counts as
reached end truly more than 0.5 m off. `Localized` keeps the controller as
it is (its certainty grid and all its memory stay in the odometry frame,
which is smooth) and moves only its goal: each cycle a particle filter
tracking the robot on the map (`robotlib.localization.MCL.best`, started
around the first pose) gives the map pose, hence the rigid transform from
the map to the odometry frame, and the goal (given in the map) is handed to
the controller in the odometry frame.

With ``plan=True`` it hands the controller waypoints along an A* path on
the map's configuration space instead of the goal, so that a local method
finds the door of a room or the shorter way round a building; the
controller still avoids whatever it senses, mapped or not.

The robot's odometry must start in the map frame (the simulator's does: the
odometry pose starts at the true start pose).

Imports: `robotlib.avoidance`'s controller base, `robotlib.localization`
and the planners here; never plotting.
"""

from __future__ import annotations

import math

import numpy as np

from ..avoidance import Controller
from ..avoidance.base import OK, REACHED
from ..localization import MCL
from ..world import World
from .cspace import configuration_space
from .grid import astar

__all__ = ["Localized"]


def _compose(a, b) -> np.ndarray:
    """Return pose ``a`` composed with pose ``b`` (``a * b``), shape (3,)."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return np.array(
        [a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], a[2] + b[2]]
    )


def _inverse(a) -> np.ndarray:
    """Return the inverse of pose ``a``, shape (3,)."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return np.array([-c * a[0] - s * a[1], s * a[0] - c * a[1], -a[2]])


class Localized(Controller):
    """Drive ``controller`` to a goal given in the map, localized on ``world``.

    Parameters
    ----------
    controller : Controller
        The avoidance controller (`VFH`, `Bug2`, ...); it is reset with this
        one and sees the odometry pose, as before.
    world : World
        The map the filter tracks the robot on.
    goal : array_like, shape (2,), optional
        Goal in the map frame, m.
    n : int
        The filter's particles at the start (KLD-sampling then adapts them).
    init_std : tuple of float
        Spread of the first particles around the first pose ``(x, y,
        theta)``, m and rad.
    rng : numpy.random.Generator, int or None
        The filter's randomness.
    plan : bool
        Hand the controller waypoints instead of the goal: the points
        ``step`` m apart along an A* path on the map (planned from the
        estimate, again every ``replan`` s), each until the estimate is
        within ``step / 2`` of it; the controller still avoids what it
        senses. Without a path, the goal itself.
    step, replan : float
        Waypoint spacing, m (2.0), and re-planning period, s (10).

    Attributes
    ----------
    mcl : MCL or None
        The filter (built on the first `command`).
    estimate : numpy.ndarray, shape (3,)
        The last map pose estimate, m and rad.
    """

    def __init__(
        self,
        controller: Controller,
        world: World,
        goal=None,
        n: int = 1000,
        init_std=(0.05, 0.05, 0.02),
        rng: np.random.Generator | int | None = None,
        plan: bool = False,
        step: float = 2.0,
        replan: float = 10.0,
    ):
        if not isinstance(controller, Controller):
            raise TypeError(f"controller must be a Controller, got {controller!r}")
        if not isinstance(world, World):
            raise TypeError(f"world must be a World, got {type(world).__name__}")
        self.inner = controller
        self.world = world
        self.n_particles = int(n)
        self.init_std = tuple(float(s) for s in init_std)
        self._seed = rng
        self.step, self.replan = float(step), float(replan)
        self.cspace = configuration_space(world, resolution=0.1) if plan else None
        self.name = f"{controller.name}+MCL"
        super().__init__(
            goal, controller.tolerance, controller.max_speed, controller.max_turn
        )

    @property
    def tolerance(self) -> float:
        """The goal radius, m (the wrapped controller's)."""
        return self.inner.tolerance

    @tolerance.setter
    def tolerance(self, value: float) -> None:
        if hasattr(self, "inner"):
            self.inner.tolerance = float(value)

    def _reset(self) -> None:
        self.inner.reset()
        self.mcl = None
        self.estimate = np.full(3, np.nan)
        self._odometry = None
        self.waypoints = None
        self._cycle = 0

    def command(self, sonar, pose, goal=None) -> tuple[float, float]:
        """Step the filter, move the goal into the odometry frame, ask the controller.

        Parameters and returns as `Controller.command`; ``goal`` is in the map.
        """
        if goal is not None:
            self.goal = np.asarray(goal, dtype=float)[:2]
            self.status = OK
        sonar = np.ascontiguousarray(sonar, dtype=np.float64)
        pose = np.ascontiguousarray(pose, dtype=np.float64)
        if self.mcl is None:
            self.mcl = MCL.best(
                self.world, n=self.n_particles, init=pose, init_std=self.init_std,
                rng=self._seed,
            )  # fmt: skip
            self.estimate = pose.copy()
        else:
            self.estimate = np.asarray(self.mcl.step(self._odometry, pose, sonar))
        self._odometry = pose.copy()
        if self.goal is None:
            self.inner.goal = None
        else:
            # map -> odometry: odometry pose * inverse(map pose)
            to_odometry = _compose(pose, _inverse(self.estimate))
            aim = self.goal if self.cspace is None else self._waypoint()
            goal = _compose(to_odometry, np.array([*aim, 0.0]))[:2]
            self.inner.goal = goal
            if self.inner.status == REACHED:
                self.inner.status = OK
        v, w = self.inner.command(sonar, pose)
        self.status = self.inner.status
        if (
            self.status == REACHED
            and self.waypoints is not None
            and len(self.waypoints) > 1
        ):
            self.status = OK  # a waypoint, not the goal
        self._cycle += 1
        return v, w

    def _waypoint(self) -> np.ndarray:
        """Return the waypoint to aim at (map frame), re-planning when due."""
        due = self._cycle % max(int(round(self.replan / 0.1)), 1) == 0
        if self.waypoints is None or due:
            self.waypoints = self._plan()
        here = self.estimate[:2]
        while (
            len(self.waypoints) > 1
            and math.dist(here, self.waypoints[0]) < 0.5 * self.step
        ):
            self.waypoints = self.waypoints[1:]
        return self.waypoints[0]

    def _plan(self) -> np.ndarray:
        """Plan waypoints ``step`` m apart along A* from the estimate to the goal."""
        goal = np.asarray(self.goal, dtype=float)
        start = self.cspace.nearest_free(self.estimate[:2], 0.6)
        plan = None if start is None else astar(self.cspace, start, goal)
        if plan is None or not plan.found or len(plan.path) < 2:
            return goal[None, :]
        path = np.asarray(plan.path, dtype=float).reshape(-1, 2)
        along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))])
        marks = np.arange(self.step, along[-1], self.step)
        points = np.column_stack(
            [np.interp(marks, along, path[:, 0]), np.interp(marks, along, path[:, 1])]
        )
        return np.vstack([points, goal])
