"""What every avoidance controller shares: the interface and the sonar geometry.

A controller turns what a real robot sees (the eight sonar ranges and its
odometry pose, plus a goal where it has one) into a velocity command
``(v, w)`` (m/s, rad/s): `Controller.command`. It keeps whatever memory it
needs between calls and forgets it in `Controller.reset`. It never plots,
never sleeps and never talks to a robot: the episode runner
(`robotlib.avoidance.episode`) does that, so the same object drives
``sim:``, ``tcp://`` and ``serial://`` robots unchanged.

Imports only robotlib's geometry helpers and the Pioneer's constants.
"""

from __future__ import annotations

import math

import numpy as np

from ..p3dx import (
    DEFAULT_MAX_ROT_VELOCITY,
    SONAR_MAX_RANGE,
    SONAR_POSES,
)

__all__ = ["Controller", "sonar_endpoints", "goal_in_robot_frame", "OK"]

OK = "ok"
"""`Controller.status` while nothing is wrong."""
REACHED = "reached"
"""`Controller.status` once the goal is within `Controller.tolerance`."""
LOCAL_MINIMUM = "local_minimum"
"""`Controller.status` when a controller finds itself trapped."""


def sonar_endpoints(sonar, sensors=SONAR_POSES, max_range: float = SONAR_MAX_RANGE):
    """Return where each sonar's echo lies, in the robot frame.

    Parameters
    ----------
    sonar : array_like, shape (S,)
        Ranges, m.
    sensors : array_like, shape (S, 3)
        Sonar poses ``(x, y, heading)`` in the robot frame, m and rad.
    max_range : float
        Range meaning "no echo", m.

    Returns
    -------
    points : numpy.ndarray, shape (S, 2)
        Echo points on each sonar's axis, m (robot frame: x ahead, y left).
    echo : numpy.ndarray of bool, shape (S,)
        True where the sonar echoed (range below ``max_range``).
    """
    r = np.asarray(sonar, dtype=float)
    s = np.asarray(sensors, dtype=float)
    pts = s[:, :2] + r[:, None] * np.column_stack([np.cos(s[:, 2]), np.sin(s[:, 2])])
    return pts, r < max_range


def goal_in_robot_frame(goal, pose) -> tuple[float, float]:
    """Return the goal ``(x, y)`` as seen from ``pose`` (robot frame), m."""
    dx, dy = float(goal[0]) - float(pose[0]), float(goal[1]) - float(pose[1])
    c, s = math.cos(float(pose[2])), math.sin(float(pose[2]))
    return c * dx + s * dy, -s * dx + c * dy


class Controller:
    """Base of the avoidance controllers: goal bookkeeping and the interface.

    Subclasses implement `_command` (and `_reset` if they keep memory).

    Parameters
    ----------
    goal : array_like, shape (2,), optional
        Goal position in the odometry frame, m (None: no goal).
    tolerance : float
        The goal counts as reached within this distance, m.
    max_speed : float
        Top translational speed commanded, m/s.
    max_turn : float
        Top rotational speed commanded, rad/s.

    Attributes
    ----------
    goal : numpy.ndarray or None
        The goal, settable at any time (or per call of `command`).
    status : str
        ``"ok"``, ``"reached"`` or ``"local_minimum"`` (a controller that
        detects that it is trapped says so; the runner ends the episode).
    sensors : numpy.ndarray, shape (8, 3)
        The sonar ring's poses in the robot frame (a Pioneer 3-DX's front ring).
    max_range : float
        The range that means "no echo", m.
    """

    name = "controller"

    def __init__(
        self,
        goal=None,
        tolerance: float = 0.3,
        max_speed: float = 0.5,
        max_turn: float = DEFAULT_MAX_ROT_VELOCITY,
    ):
        self.tolerance = float(tolerance)
        self.max_speed = float(max_speed)
        self.max_turn = float(max_turn)
        self.sensors = np.ascontiguousarray(SONAR_POSES, dtype=np.float64)
        self.max_range = SONAR_MAX_RANGE
        self.goal = None if goal is None else np.asarray(goal, dtype=float)[:2]
        self.status = OK
        self.reset()

    def reset(self) -> None:
        """Forget everything learned during an episode (keeps the goal)."""
        self.status = OK
        self._reset()

    def _reset(self) -> None:
        """Clear a subclass's memory."""

    def command(self, sonar, pose, goal=None) -> tuple[float, float]:
        """Return the velocity command for this cycle.

        Parameters
        ----------
        sonar : array_like, shape (8,)
            The eight front sonar ranges, m (5 m: no echo).
        pose : array_like, shape (3,)
            Odometry pose ``(x, y, theta)``, m and rad.
        goal : array_like, shape (2,), optional
            A new goal (odometry frame, m); kept for later calls.

        Returns
        -------
        v : float
            Translational velocity, m/s.
        w : float
            Rotational velocity, rad/s (positive: left).
        """
        if goal is not None:
            self.goal = np.asarray(goal, dtype=float)[:2]
            if self.status == REACHED:
                self.status = OK
        sonar = np.ascontiguousarray(sonar, dtype=np.float64)
        pose = np.ascontiguousarray(pose, dtype=np.float64)
        if sonar.shape != (len(self.sensors),) or pose.shape != (3,):
            raise ValueError(
                f"sonar must have shape ({len(self.sensors)},) and pose (3,), "
                f"got {sonar.shape} and {pose.shape}"
            )
        if self.goal is not None:
            dist = math.hypot(self.goal[0] - pose[0], self.goal[1] - pose[1])
            if dist <= self.tolerance:
                self.status = REACHED
                return 0.0, 0.0
        v, w = self._command(sonar, pose)
        v = min(max(float(v), -self.max_speed), self.max_speed)
        w = min(max(float(w), -self.max_turn), self.max_turn)
        return v, w

    def _command(self, sonar: np.ndarray, pose: np.ndarray) -> tuple[float, float]:
        raise NotImplementedError

    def goal_direction(self, pose) -> tuple[float, float]:
        """Return the goal's bearing (rad, robot frame) and distance (m)."""
        gx, gy = goal_in_robot_frame(self.goal, pose)
        return math.atan2(gy, gx), math.hypot(gx, gy)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(goal={self.goal})"
