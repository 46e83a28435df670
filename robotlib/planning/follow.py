"""Path following: pure pursuit, a sonar stop-and-turn avoider, the follower.

- `pure_pursuit`: the steering law, ``(v, w)`` towards a look-ahead point.
- `PurePursuit`: tracks a path (progress along it, the look-ahead point,
  slowing in curves and at the end).
- `StopAndTurn`: a minimal sonar avoider with the controller interface
  (``reset()``, ``command(sonar, pose) -> (v, w)``, an optional ``goal``).
- `PathFollower`: pure pursuit on a path, handing control to an avoider (any
  object with that interface, e.g. `robotlib.avoidance.VFH`) while the
  sonar sees an obstacle the map does not explain.
- `cross_track`: distance of points to a path.

Controllers see only sonar and a pose (an estimate); they never plot and
never sleep. Imports `robotlib.geometry` and `robotlib.p3dx` only.
"""

from __future__ import annotations

import math

import numpy as np

from ..p3dx import SONAR_POSES
from ..world import wrap_angle

__all__ = ["pure_pursuit", "PurePursuit", "StopAndTurn", "PathFollower", "cross_track"]

FRONT = slice(2, 6)
"""The four front sonars (+-30 and +-10 degrees)."""


def pure_pursuit(pose, target, v: float, w_max: float = 1.0) -> tuple[float, float]:
    """Steer towards ``target`` along the arc through it (pure pursuit).

    The arc from the robot's pose tangent to its heading through the target
    has curvature ``kappa = 2 sin(alpha) / L`` (``alpha`` the target's
    bearing, ``L`` its distance); the robot drives it at ``v``, turning at
    ``w = v kappa``. A target behind the robot (``|alpha| > pi/2``) turns the
    robot in place towards it.

    Parameters
    ----------
    pose : array_like, shape (3,)
        ``(x, y, theta)``, m and rad.
    target : array_like, shape (2,)
        The look-ahead point, m.
    v : float
        Forward speed, m/s.
    w_max : float
        Largest turn rate, rad/s.

    Returns
    -------
    (float, float)
        ``(v, w)`` in m/s and rad/s.
    """
    dx = float(target[0]) - float(pose[0])
    dy = float(target[1]) - float(pose[1])
    dist = math.hypot(dx, dy)
    if dist < 1e-9:
        return 0.0, 0.0
    alpha = wrap_angle(math.atan2(dy, dx) - float(pose[2]))
    if abs(alpha) > math.pi / 2:
        return 0.0, math.copysign(w_max, alpha)
    w = v * 2.0 * math.sin(alpha) / dist
    return v, max(-w_max, min(w_max, w))


def _project(path, cum, xy, k0, k1):
    """Arc length of the point of ``path[k0:k1+1]`` nearest ``xy``."""
    best, best_s = np.inf, cum[k0]
    for k in range(k0, min(k1, len(path) - 1)):
        a, b = path[k], path[k + 1]
        e = b - a
        ee = float(e @ e)
        t = 0.0 if ee == 0 else min(1.0, max(0.0, float((xy - a) @ e) / ee))
        d = float(np.hypot(*(a + t * e - xy)))
        if d < best:
            best, best_s = d, cum[k] + t * math.sqrt(ee)
    return best_s, best


def cross_track(path, xy) -> np.ndarray:
    """Distance from each point ``xy`` (..., 2) to the polyline ``path`` (K, 2), m."""
    p = np.asarray(path, dtype=float)
    q = np.asarray(xy, dtype=float)
    flat = q.reshape(-1, 2)
    if len(p) == 1:
        return np.hypot(*(flat - p[0]).T).reshape(q.shape[:-1])
    a, b = p[:-1], p[1:]
    e = b - a
    ee = np.maximum((e * e).sum(axis=1), 1e-300)
    t = np.clip(((flat[:, None, :] - a) * e).sum(axis=2) / ee, 0.0, 1.0)
    near = a + t[..., None] * e
    d = np.hypot(*(near - flat[:, None, :]).transpose(2, 0, 1)).min(axis=1)
    return d.reshape(q.shape[:-1])


class PurePursuit:
    """Follow a path with pure pursuit.

    Parameters
    ----------
    path : array_like, shape (K, 2)
        Waypoints, m.
    lookahead : float
        Look-ahead distance along the path, m.
    speed : float
        Cruise speed, m/s.
    w_max : float
        Largest turn rate, rad/s.
    goal_tolerance : float
        The path is done within this distance of its end, m.
    slow_radius : float
        Slow down linearly within this distance of the end, m.
    law : callable, optional
        The steering law ``law(pose, target, v, w_max) -> (v, w)`` (default
        `pure_pursuit`).
    """

    def __init__(
        self,
        path,
        lookahead: float = 0.5,
        speed: float = 0.3,
        w_max: float = 0.8,
        goal_tolerance: float = 0.1,
        slow_radius: float = 0.6,
        law=None,
    ):
        self.law = pure_pursuit if law is None else law
        p = np.asarray(path, dtype=float)[:, :2]
        if p.ndim != 2 or len(p) < 1:
            raise ValueError("path must have shape (K, 2) with K >= 1")
        keep = np.concatenate([[True], np.hypot(*np.diff(p, axis=0).T) > 1e-12])
        self.path = p[keep]
        self.cum = np.concatenate(
            [[0.0], np.cumsum(np.hypot(*np.diff(self.path, axis=0).T))]
        )
        self.lookahead = float(lookahead)
        self.speed = float(speed)
        self.w_max = float(w_max)
        self.goal_tolerance = float(goal_tolerance)
        self.slow_radius = float(slow_radius)
        self.reset()

    def reset(self) -> None:
        """Start again from the beginning of the path."""
        self.s = 0.0
        self._k = 0
        self.done = False

    @property
    def length(self) -> float:
        """Path length, m."""
        return float(self.cum[-1])

    def target(self, pose) -> np.ndarray:
        """Update the progress from ``pose`` and return the look-ahead point."""
        xy = np.asarray(pose, dtype=float)[:2]
        # search a window ahead of the last progress only (never backwards)
        k1 = int(np.searchsorted(self.cum, self.s + 2.0 * self.lookahead + 1.0))
        s, _ = _project(self.path, self.cum, xy, self._k, max(k1, self._k + 1))
        self.s = max(self.s, s)
        self._k = max(0, int(np.searchsorted(self.cum, self.s, side="right")) - 1)
        return self.point_at(self.s + self.lookahead)

    def point_at(self, s: float) -> np.ndarray:
        """Return the point at arc length ``s`` (clamped to the path), m."""
        if len(self.path) == 1 or s >= self.cum[-1]:
            return self.path[-1].copy()
        k = int(np.searchsorted(self.cum, s, side="right")) - 1
        k = min(max(k, 0), len(self.path) - 2)
        seg = self.cum[k + 1] - self.cum[k]
        t = (s - self.cum[k]) / seg if seg > 0 else 0.0
        return self.path[k] + t * (self.path[k + 1] - self.path[k])

    def command(self, pose) -> tuple[float, float]:
        """Return ``(v, w)`` (m/s, rad/s) for the robot at ``pose``."""
        end = self.path[-1]
        to_end = float(np.hypot(*(end - np.asarray(pose, dtype=float)[:2])))
        if self.done or (to_end < self.goal_tolerance and self.s >= self.length - 0.5):
            self.done = True
            return 0.0, 0.0
        target = self.target(pose)
        v = self.speed * min(1.0, max(0.25, to_end / self.slow_radius))
        v, w = (float(u) for u in self.law(pose, target, v, self.w_max))
        if v > 0 and abs(w) > 0.5 * self.w_max:  # slow down in tight curves
            scale = 0.5 * self.w_max / abs(w)
            v *= scale
            w = float(self.law(pose, target, v, self.w_max)[1])
        return v, w


class StopAndTurn:
    """A minimal sonar avoider: slow near obstacles, stop and turn when blocked.

    Turns towards the side whose sonars read farther (keeping the choice
    until the way ahead is clear), steers away from near side readings and,
    if it has a ``goal``, towards it.

    Parameters
    ----------
    stop : float
        Front range below which the robot stops and turns, m.
    slow : float
        Front range below which it slows down, m.
    speed : float
        Top speed, m/s.
    turn : float
        Turn rate when blocked, rad/s.
    """

    def __init__(
        self,
        stop: float = 0.45,
        slow: float = 1.0,
        speed: float = 0.2,
        turn: float = 0.6,
    ):
        self.stop, self.slow, self.speed, self.turn = stop, slow, speed, turn
        self.goal = None
        self.reset()

    def reset(self) -> None:
        """Forget the turning side."""
        self._side = 0.0

    def command(self, sonar, pose) -> tuple[float, float]:
        """Return ``(v, w)`` from the eight sonar ranges (m) and a pose."""
        s = np.asarray(sonar, dtype=float)
        front = float(s[FRONT].min())
        left = float(min(s[0], s[1]))
        right = float(min(s[6], s[7]))
        if front < self.stop:
            if self._side == 0.0:
                self._side = 1.0 if left >= right else -1.0
            return 0.0, self._side * self.turn
        self._side = 0.0
        v = self.speed * min(1.0, (front - self.stop) / (self.slow - self.stop) + 0.3)
        w = 0.3 * (1.0 / max(right, 0.2) - 1.0 / max(left, 0.2))
        if self.goal is not None:
            p = np.asarray(pose, dtype=float)
            bearing = wrap_angle(
                math.atan2(self.goal[1] - p[1], self.goal[0] - p[0]) - p[2]
            )
            if front > self.slow:
                w += 0.8 * bearing
        return v, max(-self.turn, min(self.turn, w))


class PathFollower:
    """Pure pursuit on a path, an avoider for obstacles the map does not hold.

    Each cycle, `command` looks at the front sonars: a reading below
    ``danger`` that is shorter than the map's expected reading by more than
    ``unexplained`` (or any reading below ``too_close``) hands control to the
    avoider, with the look-ahead point as its ``goal`` when it has one. The
    follower takes control back once the front reads clear of
    ``danger + release`` for ``release_cycles`` cycles. The avoider is not
    reset at a hand-over (a VFH keeps its certainty grid); `reset` does.

    Parameters
    ----------
    pursuit : PurePursuit
        The path tracker.
    avoider : object, optional
        A controller with ``reset()`` and ``command(sonar, pose) -> (v, w)``
        (default `StopAndTurn`).
    danger, too_close, unexplained, release : float
        Ranges, m (see above).
    release_cycles : int
        Clear cycles before following again.
    """

    def __init__(
        self,
        pursuit: PurePursuit,
        avoider=None,
        danger: float = 0.6,
        too_close: float = 0.35,
        unexplained: float = 0.3,
        release: float = 0.3,
        release_cycles: int = 5,
    ):
        self.pursuit = pursuit
        self.avoider = StopAndTurn() if avoider is None else avoider
        self.danger = float(danger)
        self.too_close = float(too_close)
        self.unexplained = float(unexplained)
        self.release = float(release)
        self.release_cycles = int(release_cycles)
        self.avoiding = False
        self._clear = 0

    def reset(self) -> None:
        """Follow from the path's start; reset the avoider (its memory too)."""
        self.pursuit.reset()
        self.avoider.reset()
        self.avoiding = False
        self._clear = 0

    @property
    def done(self) -> bool:
        """The path's end is reached."""
        return self.pursuit.done

    def blocked(self, sonar, expected=None) -> bool:
        """Whether the front sonars see an obstacle to avoid.

        ``expected`` (8,) are the map's readings at the pose (None: every
        near reading counts).
        """
        s = np.asarray(sonar, dtype=float)[FRONT]
        if s.min() < self.too_close:
            return True
        near = s < self.danger
        if expected is not None:
            near &= s < np.asarray(expected, dtype=float)[FRONT] - self.unexplained
        return bool(near.any())

    def command(self, sonar, pose, expected=None) -> tuple[float, float]:
        """Return ``(v, w)`` for the robot at ``pose`` seeing ``sonar`` (8,), m."""
        if self.blocked(sonar, expected):
            self.avoiding = True
            self._clear = 0
        elif self.avoiding:
            s = np.asarray(sonar, dtype=float)[FRONT]
            self._clear = self._clear + 1 if s.min() > self.danger + self.release else 0
            if self._clear >= self.release_cycles:
                self.avoiding = False
        if not self.avoiding:
            return self.pursuit.command(pose)
        if hasattr(self.avoider, "goal"):
            self.avoider.goal = self.pursuit.target(pose)
        return self.avoider.command(sonar, pose)


def sonar_points(pose, sonar, max_range: float) -> np.ndarray:
    """World points ``(x, y)`` of the sonar echoes shorter than ``max_range``, m."""
    p = np.asarray(pose, dtype=float)
    s = np.asarray(sonar, dtype=float)
    keep = s < max_range
    sp = SONAR_POSES[keep]
    c, si = math.cos(p[2]), math.sin(p[2])
    x = p[0] + c * sp[:, 0] - si * sp[:, 1]
    y = p[1] + si * sp[:, 0] + c * sp[:, 1]
    a = p[2] + sp[:, 2]
    return np.column_stack([x + s[keep] * np.cos(a), y + s[keep] * np.sin(a)])
