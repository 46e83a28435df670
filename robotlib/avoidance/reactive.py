"""Reactive controllers without memory of the world: Braitenberg vehicles, walls.

- `Braitenberg`: each wheel's speed is a base speed plus a weighted sum of
  the eight sonars' activations (``1 - r / reach``, 0 beyond ``reach``); the
  ``(2, 8)`` weight matrix is the vehicle. `BRAITENBERG` holds Braitenberg's
  four: fear (2a, same side, excitatory: flees), aggression (2b, crossed,
  excitatory: charges), love (3a, same side, inhibitory: stops facing it) and
  explorer (3b, crossed, inhibitory: slows and turns away). A goal acts as a
  light seen by two light sensors wired crossed and excitatory (a 2b towards
  the light), so that a vehicle can be sent somewhere.
- `WallFollower`: keeps a wall at ``distance`` on one side with the side
  sonars (PD on the distance, plus the wall's angle from the two side
  sonars), turning away when the way ahead is blocked.

Imports: numpy and `robotlib.avoidance.base`; never plotting.
"""

from __future__ import annotations

import math

import numpy as np

from ..p3dx import AXLE_TRACK
from .base import Controller

__all__ = ["Braitenberg", "BRAITENBERG", "WallFollower", "sonar_activation"]

_SIDE = np.array([1.0, 1.0, 1.0, 1.0, -1.0, -1.0, -1.0, -1.0])
"""+1 for the left sonars (0-3), -1 for the right ones (4-7)."""
_W = np.array([0.2, 0.6, 1.0, 1.4, 1.4, 1.0, 0.6, 0.2])
"""How much each sonar weighs (front ones most), for the vehicles below."""


def _vehicle(same: float, crossed: float) -> np.ndarray:
    left = np.where(_SIDE > 0, same, crossed) * _W
    right = np.where(_SIDE < 0, same, crossed) * _W
    return np.vstack([left, right])


BRAITENBERG = {
    "fear": _vehicle(0.4, 0.0),
    "aggression": _vehicle(0.0, 0.4),
    "love": _vehicle(-0.4, 0.0),
    "explorer": _vehicle(0.0, -0.4),
}
"""Braitenberg's vehicles as (2, 8) weight matrices: row 0 drives the left
wheel, row 1 the right; columns are the sonars from +90 (left) to -90 deg."""


def sonar_activation(sonar, reach: float = 1.5) -> np.ndarray:
    """Return each sonar's activation ``max(0, 1 - r / reach)``, shape (8,)."""
    r = np.asarray(sonar, dtype=float)
    return np.clip(1.0 - r / reach, 0.0, 1.0)


class Braitenberg(Controller):
    """A Braitenberg vehicle on the eight front sonars.

    Parameters
    ----------
    weights : str or array_like, shape (2, 8)
        A name in `BRAITENBERG` or the matrix (m/s per unit activation) from
        the sonar activations to the left and right wheel speeds.
    base_speed : float
        Wheel speed with nothing in sight, m/s.
    reach : float
        Sonar range at which the activation starts, m.
    goal_gain : float
        Wheel speed difference per radian of the goal's bearing (the light
        sensors), m/s; 0 ignores the goal.
    goal : array_like, optional
        Goal (odometry frame), m.
    tolerance, max_speed, max_turn : float
        See `Controller`.
    """

    name = "Braitenberg"

    def __init__(
        self,
        weights="explorer",
        base_speed: float = 0.35,
        reach: float = 1.5,
        goal_gain: float = 0.15,
        goal=None,
        tolerance: float = 0.3,
        max_speed: float = 0.5,
        max_turn: float = math.radians(90.0),
    ):
        if isinstance(weights, str):
            self.name = f"Braitenberg {weights}"
            weights = BRAITENBERG[weights]
        w = np.asarray(weights, dtype=float)
        if w.shape != (2, 8):
            raise ValueError(f"weights must have shape (2, 8), got {w.shape}")
        self.weights = w
        self.base_speed = float(base_speed)
        self.reach = float(reach)
        self.goal_gain = float(goal_gain)
        super().__init__(goal, tolerance, max_speed, max_turn)

    def wheel_speeds(self, sonar, pose) -> tuple[float, float]:
        """Return the left and right wheel speeds, m/s."""
        left, right = self.base_speed + self.weights @ sonar_activation(
            sonar, self.reach
        )
        if self.goal is not None and self.goal_gain:
            bearing, _ = self.goal_direction(pose)
            # two light sensors, crossed and excitatory: turn towards the light
            left -= self.goal_gain * bearing / 2
            right += self.goal_gain * bearing / 2
        return float(left), float(right)

    def _command(self, sonar, pose):
        left, right = self.wheel_speeds(sonar, pose)
        return (left + right) / 2, (right - left) / AXLE_TRACK


class WallFollower(Controller):
    """Follow a wall on one side at a set distance, with the side sonars.

    Parameters
    ----------
    side : str
        ``"left"`` or ``"right"``: where the wall is kept.
    distance : float
        Wanted distance from the wall, m (as the side sonar reads it).
    speed : float
        Cruising speed, m/s.
    gain, angle_gain : float
        Turn rate per metre of distance error and per radian of the wall's
        angle, rad/s.
    front : float
        Turn away on the spot when the front sonars read less than this, m.
    goal, tolerance, max_speed, max_turn
        See `Controller` (a wall follower ignores the goal's direction; it
        stops there).
    """

    name = "wall follower"

    def __init__(
        self,
        side: str = "left",
        distance: float = 0.6,
        speed: float = 0.3,
        gain: float = 1.5,
        angle_gain: float = 1.0,
        front: float = 0.7,
        goal=None,
        tolerance: float = 0.3,
        max_speed: float = 0.5,
        max_turn: float = math.radians(90.0),
    ):
        if side not in ("left", "right"):
            raise ValueError(f"side must be 'left' or 'right', got {side!r}")
        self.side = side
        self.distance = float(distance)
        self.speed = float(speed)
        self.gain = float(gain)
        self.angle_gain = float(angle_gain)
        self.front = float(front)
        super().__init__(goal, tolerance, max_speed, max_turn)

    def _command(self, sonar, pose):
        s = 1.0 if self.side == "left" else -1.0
        side, diag = (sonar[0], sonar[1]) if s > 0 else (sonar[7], sonar[6])
        ahead = min(sonar[2], sonar[3], sonar[4], sonar[5])
        if ahead < self.front:
            return 0.0, -s * 0.6 * self.max_turn  # turn away from the wall
        if min(side, diag * math.cos(math.radians(40.0))) > 2.0 * self.distance:
            # lost the wall: round its end on a circle of the wanted distance
            return self.speed * 0.6, s * self.speed * 0.6 / self.distance
        # the wall's angle from the side and diagonal (50 deg) sonars
        est = diag * math.cos(math.radians(40.0))
        angle = math.atan2(est - side, diag * math.sin(math.radians(40.0)))
        err = min(side, est) - self.distance
        w = s * (self.gain * err + self.angle_gain * angle)
        return self.speed * max(0.3, 1.0 - abs(w) / self.max_turn), w
