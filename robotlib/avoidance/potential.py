"""Potential fields on sonar (Khatib 1986), with the local minimum detected.

The goal attracts (a constant pull, weaker within 1 m of it); every sonar
echo repels from its endpoint in the robot frame, with Khatib's
``k_rep (1/rho - 1/d0) / rho**2`` within ``d0`` (`potential_force`). The
robot steers along the force and slows when it points away from the
heading.

A potential field has no memory, so in a trap (a U open towards the robot,
a wall across the way) the pull and the push balance or make the robot
oscillate, and it never arrives. `PotentialField` detects this: when its
distance to the goal has not shrunk by ``progress`` m in ``patience`` s
while it stays within ``radius`` m of one place, it sets ``status`` to
``"local_minimum"`` (and the episode runner stops there).

Imports: the kernels and `robotlib.avoidance.base`; never plotting.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from .._config import readonly
from ..world import wrap_angle
from . import _kernels
from .base import LOCAL_MINIMUM, Controller, goal_in_robot_frame

__all__ = ["PotentialField", "potential_force", "force_field"]


def potential_force(
    sonar,
    pose,
    goal,
    k_att: float = 1.0,
    k_rep: float = 0.5,
    d0: float = 1.2,
    sensors=None,
    max_range: float = 5.0,
) -> np.ndarray:
    """Return the potential field's force on the robot, in the robot frame.

    Parameters
    ----------
    sonar : array_like, shape (S,)
        Sonar ranges, m; ``max_range`` means no echo (no push).
    pose : array_like, shape (3,)
        Odometry pose, m and rad.
    goal : array_like, shape (2,)
        Goal, odometry frame, m.
    k_att : float
        Attraction: ``k_att`` times the unit vector to the goal (times the
        distance, within 1 m of it).
    k_rep : float
        Repulsion gain, in force units times m^3.
    d0 : float
        Echo endpoints further than this from the robot's centre do not push, m.
    sensors : array_like, shape (S, 3), optional
        Sonar poses in the robot frame (default: the Pioneer 3-DX's ring).
    max_range : float
        The "no echo" range, m.

    Returns
    -------
    numpy.ndarray, shape (2,)
        ``(fx, fy)``: x ahead, y to the left.
    """
    from ..p3dx import SONAR_POSES

    s = np.ascontiguousarray(SONAR_POSES if sensors is None else sensors, dtype=float)
    r = np.ascontiguousarray(sonar, dtype=float)
    gx, gy = goal_in_robot_frame(goal, pose)
    out = np.zeros(2)
    _kernels.potential_force(r, s, float(max_range), gx, gy, k_att, k_rep, d0, out)
    return out


class PotentialField(Controller):
    """Steer along the potential field's force; report a local minimum.

    Parameters
    ----------
    goal : array_like, optional
        Goal (odometry frame), m.
    k_att, k_rep, d0 : float
        See `potential_force`.
    turn_gain : float
        Turn rate per radian between the heading and the force, 1/s.
    patience : float
        Seconds without progress before a local minimum is declared.
    progress : float
        Progress that counts: the distance to the goal must shrink by this, m.
    radius : float
        ... while the robot stays within this distance of one place, m.
    force : callable, optional
        ``force(sonar, pose, goal) -> (fx, fy)`` instead of `potential_force`
        with the gains above (Lab 2 plugs the student's in here).
    tolerance, max_speed, max_turn : float
        See `Controller`.

    Attributes
    ----------
    last_force : numpy.ndarray, shape (2,)
        The last force, robot frame.
    """

    name = "potential field"

    def __init__(
        self,
        goal=None,
        k_att: float = 1.0,
        k_rep: float = 0.5,
        d0: float = 1.2,
        turn_gain: float = 1.5,
        patience: float = 15.0,
        progress: float = 0.3,
        radius: float = 1.0,
        force=None,
        tolerance: float = 0.3,
        max_speed: float = 0.5,
        max_turn: float = math.radians(90.0),
    ):
        self.k_att, self.k_rep, self.d0 = float(k_att), float(k_rep), float(d0)
        self.turn_gain = float(turn_gain)
        self.patience = float(patience)
        self.progress = float(progress)
        self.radius = float(radius)
        self.force_fn = force
        super().__init__(goal, tolerance, max_speed, max_turn)

    def _reset(self) -> None:
        self.last_force = np.zeros(2)
        self._out = np.zeros(2)
        self._cycle = 0
        self._best = math.inf
        self._best_cycle = 0
        self._recent: deque = deque(maxlen=max(1, int(round(self.patience / 0.1))))

    def _trapped(self, pose, dist: float) -> bool:
        self._cycle += 1
        self._recent.append((float(pose[0]), float(pose[1])))
        if dist < self._best - self.progress:
            self._best, self._best_cycle = dist, self._cycle
        if self._cycle - self._best_cycle < self._recent.maxlen:
            return False
        xy = np.array(self._recent)
        spread = np.hypot(*(xy - xy.mean(axis=0)).T).max()
        return bool(spread < self.radius)

    def _command(self, sonar, pose):
        if self.goal is None:
            return 0.0, 0.0
        if self.force_fn is not None:
            f = np.asarray(self.force_fn(sonar, pose, self.goal), dtype=float)
        else:
            gx, gy = goal_in_robot_frame(self.goal, pose)
            _kernels.potential_force(
                sonar,
                readonly(self.sensors),
                self.max_range,
                gx,
                gy,
                self.k_att,
                self.k_rep,
                self.d0,
                self._out,
            )
            f = self._out
        self.last_force = np.array(f[:2], dtype=float)
        _, dist = self.goal_direction(pose)
        if self._trapped(pose, dist):
            self.status = LOCAL_MINIMUM
            return 0.0, 0.0
        angle = wrap_angle(math.atan2(f[1], f[0]))
        w = self.turn_gain * angle
        v = self.max_speed * max(0.0, math.cos(angle)) * min(1.0, math.hypot(*f[:2]))
        return v, w


def force_field(
    world, goal, resolution: float = 0.4, heading: str = "goal", force=None, **gains
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Return the potential field's force over a world, as the sonars feel it.

    At each grid point the robot is placed facing the goal (``heading="goal"``)
    and the force of `potential_force` from the noise-free sonar readings
    there (`robotlib.sensing.expected_ranges`) is turned into the world frame.

    Parameters
    ----------
    world : robotlib.world.World
        The world.
    goal : array_like, shape (2,)
        Goal, m.
    resolution : float
        Grid spacing, m.
    heading : str
        ``"goal"``: each pose faces the goal.
    force : callable, optional
        ``force(sonar, pose, goal) -> (fx, fy)`` (robot frame) instead of
        `potential_force`.
    **gains
        ``k_att``, ``k_rep``, ``d0`` for `potential_force` (or ``force``).

    Returns
    -------
    x, y, fx, fy : numpy.ndarray, shape (ny, nx)
        Grid points (m) and the force there, world frame; nan where a robot
        would not fit or could not get to from the world's start (outside
        the outer walls, `World.free_space`).
    """
    from ..sensing import expected_ranges

    if heading != "goal":
        raise ValueError("only heading='goal' is supported")
    x0, y0, x1, y1 = world.bounds
    xs = np.arange(x0 + resolution / 2, x1, resolution)
    ys = np.arange(y0 + resolution / 2, y1, resolution)
    gx, gy = np.meshgrid(xs, ys)
    theta = np.arctan2(goal[1] - gy, goal[0] - gx)
    poses = np.column_stack([gx.ravel(), gy.ravel(), theta.ravel()])
    z = expected_ranges(world, poses)
    fn = potential_force if force is None else force
    f = np.array(
        [
            np.asarray(fn(zi, p, goal, **gains), dtype=float)
            for zi, p in zip(z, poses, strict=True)
        ]
    )
    c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
    fx, fy = c * f[:, 0] - s * f[:, 1], s * f[:, 0] + c * f[:, 1]
    free = world.is_free(poses[:, :2])
    # and reachable from the start: a robot fits outside the outer walls too
    reach = world.free_space()
    i, j = reach.cell_of(poses[:, :2])
    ny, nx = reach.shape
    on = (i >= 0) & (i < ny) & (j >= 0) & (j < nx)
    free &= on
    free[on] &= reach.data[i[on], j[on]]
    fx, fy = np.where(free, fx, np.nan), np.where(free, fy, np.nan)
    return gx, gy, fx.reshape(gx.shape), fy.reshape(gx.shape)
