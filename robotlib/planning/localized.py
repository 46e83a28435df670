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

The robot's odometry must start in the map frame (the simulator's does: the
odometry pose starts at the true start pose).

Imports: `robotlib.avoidance`'s controller base and `robotlib.localization`;
never plotting.
"""

from __future__ import annotations

import math

import numpy as np

from ..avoidance import Controller
from ..avoidance.base import OK, REACHED
from ..localization import MCL
from ..world import World

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
            goal = _compose(to_odometry, np.array([*self.goal, 0.0]))[:2]
            self.inner.goal = goal
            if self.inner.status == REACHED:
                self.inner.status = OK
        v, w = self.inner.command(sonar, pose)
        self.status = self.inner.status
        return v, w
