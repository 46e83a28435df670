"""Bug2 (Lumelsky and Stepanov 1987) on sonar and odometry, without a map.

The m-line runs from where the robot is when it gets its goal (its first
odometry pose, or where it is when the goal moves by more than 0.5 m: the
next waypoint of a planned path, `robotlib.planning.Localized`) to the
goal. Bug2 drives along it towards the goal until the front sonars see an
obstacle (the hit point), then follows the obstacle's boundary (a
`WallFollower`, the obstacle on the left) until it meets the m-line again
nearer the goal than the hit point, with the way to the goal open, and
leaves the boundary there. If it comes back to the hit point without
leaving, having followed the boundary for at least ``round_trip`` m (not
just turned about in a pocket), the goal is unreachable and it reports a
local minimum.

Imports: `robotlib.avoidance.base` and `reactive`; never plotting.
"""

from __future__ import annotations

import math

import numpy as np

from .base import LOCAL_MINIMUM, Controller
from .reactive import WallFollower

__all__ = ["Bug2"]


class Bug2(Controller):
    """Bug2 on the front sonars.

    Parameters
    ----------
    goal : array_like, optional
        Goal (odometry frame), m.
    hit : float
        The front sonars (+-10, +-30 deg) closer than this make a hit point, m.
    line_tolerance : float
        On the m-line within this distance, m.
    speed : float
        Speed along the m-line, m/s.
    follow_distance : float
        Distance kept from the boundary, m.
    round_trip : float
        Boundary followed, m, before a return to the hit point counts as
        having gone round the obstacle (3.0: in a U-trap's pocket the wall
        follower turned about within 2 m and came back past the hit point).
    tolerance, max_speed, max_turn : float
        See `Controller`.

    Attributes
    ----------
    mode : str
        ``"goal"`` (on the m-line) or ``"follow"`` (on a boundary).
    hit_point : numpy.ndarray or None
        Where the current boundary was met.
    """

    name = "Bug2"

    def __init__(
        self,
        goal=None,
        hit: float = 0.7,
        line_tolerance: float = 0.15,
        speed: float = 0.4,
        follow_distance: float = 0.6,
        round_trip: float = 3.0,
        tolerance: float = 0.3,
        max_speed: float = 0.5,
        max_turn: float = math.radians(90.0),
    ):
        self.hit = float(hit)
        self.line_tolerance = float(line_tolerance)
        self.speed = float(speed)
        self.round_trip = float(round_trip)
        self.follower = WallFollower(
            side="left",
            distance=follow_distance,
            speed=speed * 0.75,
            front=hit,
            max_speed=max_speed,
            max_turn=max_turn,
        )
        super().__init__(goal, tolerance, max_speed, max_turn)

    def _reset(self) -> None:
        self.mode = "goal"
        self.start = None
        self._aim = None
        self.hit_point = None
        self._left_hit = False
        self._followed = 0.0
        self._last = None
        self.follower.reset()

    def _on_m_line(self, xy: np.ndarray) -> bool:
        a, b = self.start, self.goal
        ab = b - a
        t = float(np.dot(xy - a, ab) / max(np.dot(ab, ab), 1e-12))
        foot = a + min(max(t, 0.0), 1.0) * ab
        return bool(np.hypot(*(xy - foot)) < self.line_tolerance)

    def _command(self, sonar, pose):
        if self.goal is None:
            return 0.0, 0.0
        xy = np.array(pose[:2])
        bearing, dist = self.goal_direction(pose)
        if self._aim is None or np.hypot(*(self._aim - self.goal)) > 0.5:
            # a new goal (a waypoint): a new m-line from here; on a boundary,
            # here is its hit point (leaving at once drove into side walls)
            self._aim, self.start = self.goal.copy(), xy.copy()
            self.hit_point, self._hit_dist = xy.copy(), dist
            self._left_hit, self._followed, self._last = False, 0.0, xy.copy()
        ahead = min(sonar[2], sonar[3], sonar[4], sonar[5])
        if self.mode == "goal":
            # an echo beyond the goal does not block the way to it
            if ahead < min(self.hit, dist - 0.1) and abs(bearing) < math.pi / 2:
                self.mode = "follow"
                self.hit_point = xy.copy()
                self._hit_dist = dist
                self._left_hit = False
                self._followed, self._last = 0.0, xy.copy()
                self.follower.reset()
            else:
                w = 1.5 * bearing
                v = self.speed * max(0.0, math.cos(bearing)) * min(1.0, dist)
                return v, w
        # following the boundary
        self._followed += float(np.hypot(*(xy - self._last)))
        self._last = xy.copy()
        away = float(np.hypot(*(xy - self.hit_point)))
        if away > 0.5:
            self._left_hit = True
        elif self._left_hit and away < 0.3 and self._followed > self.round_trip:
            self.status = LOCAL_MINIMUM  # round the obstacle and back: no way
            return 0.0, 0.0
        if (
            self._left_hit
            and dist < self._hit_dist - 0.3
            and self._on_m_line(xy)
            and self._goal_side_free(sonar, bearing)
        ):
            self.mode = "goal"
            return 0.0, 1.5 * bearing
        return self.follower.command(sonar, pose)

    def _goal_side_free(self, sonar, bearing: float) -> bool:
        """Whether the robot can turn from the boundary towards the goal.

        The boundary is on the left: a goal to the right (or behind) lies
        away from it, and rounding an obstacle the robot meets the m-line
        again with the goal square to its right (at -90 degrees, where a
        test on ``|bearing| < 90`` degrees failed about half the time and
        sent it round the obstacle back to the hit point). A goal ahead or
        to the left needs the sonars facing it (within 25 degrees) clear
        beyond ``hit``; one further round to the left, no sonar sees.
        """
        if bearing <= 0.0:
            return True
        facing = np.abs(self.sensors[:, 2] - bearing) <= math.radians(25.0)
        return bool(facing.any() and np.all(sonar[facing] > self.hit))
