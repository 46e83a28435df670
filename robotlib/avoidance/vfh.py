"""The Vector Field Histogram (Borenstein and Koren 1991), with VFH+'s refinements.

VFH keeps a certainty grid in the odometry frame, updated from each sonar
scan (an echo raises the cell at the measured range on the sonar's axis and
lowers the cells the axis crossed: histogramic in-motion mapping). Each cycle
the cells of the active window around the robot become a polar obstacle
density (`polar_histogram`): a cell of certainty ``c`` at distance ``d``
weighs ``c**2 (1 - d / window)``. Following VFH+ (Ulrich and Borenstein
1998) every cell is enlarged by the robot's radius plus a safety distance
(it counts in all sectors within ``asin(enlarge / d)`` of its direction) and
the histogram is made binary with two thresholds (hysteresis). The robot
steers to a free valley (`choose_direction`): straight to the goal if its
sector is free, else towards the nearest valley, keeping ``wide / 2``
sectors from a wide valley's border, or to a narrow valley's middle. Speed
falls with the density ahead and with the turn.

The grid's update is balanced (``increment == decrement``, ceiling 30): a
wide cone's echo off a door's jamb paints a cell inside the door on the
sonar's axis, and a sonar that later looks through the door clears it just
as fast, so a 0.8 m door opens once the robot is near it and facing it. With
the increment three times the decrement the door stayed painted shut (0 of
10 pairs of the doorway world; 9 of 10 balanced, ``robotlib bench avoid``).

The grid needs several echoes in a cell to block a sector, and a wall that
comes into view close (a partition's end met round a corner) may be reached
before then. A sonar brake backs the grid up: each echo's point on its
sonar's axis that lies in the disc's path (straight on, or turned by the
turn being commanded over the next half second) limits the forward speed to
the speed that stops the robot short of it at ``settings.brake`` m/s^2.
When every sector is blocked (boxed in between boxes) it steers into the
thinnest valley, the threshold raised two, four, eight times, rather than
turning in place for ever.

The public functions are what a student writes in Lab 2; `VFH` accepts
replacements for them (``histogram=``, ``direction=``).

Imports: numpy, the kernels, `robotlib.avoidance.base` and `.vfh_settings`;
never plotting.
"""

from __future__ import annotations

import math

import numpy as np

from .._config import readonly
from ..p3dx import ROBOT_RADIUS
from . import _kernels
from .base import Controller
from .vfh_settings import VFHSettings

__all__ = ["VFH", "polar_histogram", "choose_direction", "smooth_histogram"]


def _wrap(a: float) -> float:
    """Wrap one angle to (-pi, pi] (a fast scalar `robotlib.geometry.wrap_angle`)."""
    w = math.remainder(a, 2.0 * math.pi)
    return math.pi if w == -math.pi else w


def polar_histogram(
    points,
    certainty,
    pose,
    n_sectors: int = 72,
    window: float = 2.5,
    enlarge: float = ROBOT_RADIUS + 0.15,
) -> np.ndarray:
    """Polar obstacle density around ``pose`` (VFH+, robot frame).

    Parameters
    ----------
    points : array_like, shape (K, 2)
        Obstacle cells' centres in the odometry frame, m.
    certainty : array_like, shape (K,)
        Each cell's certainty value ``c`` (>= 0).
    pose : array_like, shape (3,)
        Robot pose ``(x, y, theta)``, m and rad.
    n_sectors : int
        Sectors over the full turn; sector ``k`` is centred on the robot-frame
        direction ``-pi + (k + 0.5) * 2 pi / n_sectors``.
    window : float
        Cells at ``d >= window`` from the robot do not count, m.
    enlarge : float
        Robot radius plus safety distance, m: a cell counts in every sector
        whose centre is within ``asin(enlarge / d)`` of the cell's direction
        (pi/2 when ``d <= enlarge``).

    Returns
    -------
    numpy.ndarray, shape (n_sectors,)
        The sum over cells of ``c**2 * (1 - d / window)`` per sector.
    """
    pts = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 2)
    c = np.ascontiguousarray(certainty, dtype=np.float64).reshape(-1)
    if len(c) != len(pts):
        raise ValueError(f"{len(pts)} points but {len(c)} certainty values")
    pose = np.ascontiguousarray(pose, dtype=np.float64)
    hist = np.zeros(int(n_sectors))
    _kernels.histogram_points(pts, c, pose, float(window), float(enlarge), hist)
    return hist


def smooth_histogram(hist, half: int = 2) -> np.ndarray:
    """Circular smoothing of a polar histogram (weights 1, 2, .., half+1, .., 1).

    Parameters
    ----------
    hist : array_like, shape (n,)
        Densities per sector.
    half : int
        Sectors on each side that take part.

    Returns
    -------
    numpy.ndarray, shape (n,)
    """
    h = np.ascontiguousarray(hist, dtype=np.float64)
    out = np.empty_like(h)
    _kernels.smooth(h, int(half), out)
    return out


def _valleys(free: np.ndarray) -> list[tuple[int, int]]:
    """Circular runs of free sectors as ``(start, length)``."""
    n = len(free)
    if free.all():
        return [(0, n)]
    if not free.any():
        return []
    first_blocked = int(np.argmin(free))
    out, k = [], 0
    while k < n:
        idx = (first_blocked + k) % n
        if free[idx]:
            length = 0
            while k < n and free[(first_blocked + k) % n]:
                length += 1
                k += 1
            out.append((idx, length))
        else:
            k += 1
    return out


def choose_direction(hist, threshold: float, target: float, wide: int = 16) -> float:
    """Pick the steering direction from a polar histogram (VFH's valley rule).

    Sectors with density below ``threshold`` are free; a valley is a run of
    free sectors (round the circle). If the target's sector is free, steer
    straight at the target. Otherwise take the valley whose nearer border
    sector is closest (in angle) to the target: a valley of at least ``wide``
    sectors is steered at ``wide // 2`` sectors in from that border, a
    narrower one at its middle.

    Parameters
    ----------
    hist : array_like, shape (n,)
        Polar densities, sector ``k`` centred on ``-pi + (k + 0.5) 2 pi / n``
        (robot frame).
    threshold : float
        Free below this density.
    target : float
        Direction of the goal, rad (robot frame).
    wide : int
        Sectors that make a valley wide.

    Returns
    -------
    float
        The direction to steer, rad, robot frame, in (-pi, pi]; ``nan`` if
        every sector is blocked.
    """
    h = np.asarray(hist, dtype=float)
    n = len(h)
    alpha = 2.0 * math.pi / n
    free = h < threshold
    target = _wrap(float(target))
    kt = int((target + math.pi) // alpha) % n
    if free[kt]:
        return target
    best, best_dist = math.nan, math.inf
    for start, length in _valleys(free):
        ends = (start, (start + length - 1) % n)
        for side, border in enumerate(ends):
            dist = abs(_wrap((border + 0.5) * alpha - math.pi - target))
            if dist >= best_dist:
                continue
            best_dist = dist
            if length >= wide:
                inward = wide // 2 if side == 0 else -(wide // 2)
                k = border + inward
            else:
                k = start + (length - 1) / 2.0
            best = _wrap((k + 0.5) * alpha - math.pi)
    return best


class VFH(Controller):
    """Vector Field Histogram controller on sonar and odometry (VFH+ style).

    Parameters
    ----------
    goal : array_like, shape (2,), optional
        Goal in the odometry frame, m; settable later (attribute ``goal``) or
        per call (``command(sonar, pose, goal)``).
    settings : VFHSettings, optional
        The grid, histogram, valley, escape and speed knobs, read here
        (default: `VFHSettings()`).
    histogram : callable, optional
        ``histogram(points, certainty, pose) -> (n_sectors,)`` to use instead
        of `polar_histogram` (Lab 2 plugs the student's in here).
    direction : callable, optional
        ``direction(hist, threshold, target) -> rad`` instead of
        `choose_direction` with the hysteresis.

    Attributes
    ----------
    settings : VFHSettings
        The knobs it was built with.
    grid : numpy.ndarray, shape (ny, nx)
        The certainty grid (odometry frame), rows are y.
    origin : numpy.ndarray, shape (2,)
        Lower-left corner of the grid, m (set on the first `command`).
    histogram : numpy.ndarray, shape (n_sectors,)
        The last (smoothed) polar histogram.
    steer : float
        The last chosen direction (robot frame, rad; nan: all blocked).
    following : int
        0 while heading for the goal; +1 or -1 while following a boundary
        (obstacle on the right, or on the left).
    escapes : int
        How many times the controller began following a boundary.
    """

    name = "VFH"

    def __init__(
        self,
        goal=None,
        settings: VFHSettings | None = None,
        *,
        histogram=None,
        direction=None,
    ):
        s = VFHSettings() if settings is None else settings
        if not isinstance(s, VFHSettings):
            raise TypeError(f"settings must be a VFHSettings, got {type(s).__name__}")
        self.settings = s
        self.resolution = s.resolution
        self.n_cells = int(math.ceil(s.extent / s.resolution))
        self.window = s.window
        self.enlarge = s.enlarge
        self.n_sectors = s.n_sectors
        self.threshold_low = s.threshold_low
        self.threshold_high = s.threshold_high
        self.wide = s.wide
        self.increment, self.decrement, self.cmax = s.increment, s.decrement, s.cmax
        self.turn_gain = s.turn_gain
        self.half_cone = 0.5 * s.cone
        self.clear_range = s.clear_range
        self.fade = s.fade
        self.escape = s.escape
        self.patience = s.patience
        self.progress = s.progress
        self.follow_margin = s.follow_margin
        self.mu_goal, self.mu_heading, self.mu_previous = s.mu
        self.brake = s.brake
        self.histogram_fn = histogram
        self.direction_fn = direction
        super().__init__(goal, s.tolerance, s.max_speed, s.max_turn)

    def _reset(self) -> None:
        self.grid = np.zeros((self.n_cells, self.n_cells))
        self.origin = None
        self.histogram = np.zeros(self.n_sectors)
        self._raw = np.zeros(self.n_sectors)
        self._blocked = np.zeros(self.n_sectors, dtype=bool)
        self.steer = 0.0
        self._spin = 0.0
        self._previous = 0.0
        self._heading = 0.0
        self._has_previous = False
        self.following = 0
        self.escapes = 0
        self._cycle = 0
        self._best = math.inf
        self._best_cycle = 0
        self._follow_from = math.inf
        self._aim = None

    def update_grid(self, sonar: np.ndarray, pose: np.ndarray) -> None:
        """Add one scan to the certainty grid (centred on the first pose seen)."""
        if self.origin is None:
            half = 0.5 * self.n_cells * self.resolution
            self.origin = np.array([pose[0] - half, pose[1] - half])
        if self.fade < 1.0:
            _kernels.fade(
                self.grid,
                self.origin[0],
                self.origin[1],
                self.resolution,
                pose[0],
                pose[1],
                self.max_range,
                self.fade,
            )
        _kernels.certainty_update(
            self.grid,
            self.origin[0],
            self.origin[1],
            self.resolution,
            pose,
            readonly(self.sensors),
            sonar,
            self.max_range,
            self.half_cone,
            self.clear_range,
            self.increment,
            self.decrement,
            self.cmax,
        )

    def window_cells(self, pose, window: float | None = None):
        """Return the occupied cells within ``window`` m of the robot.

        Returns
        -------
        points : numpy.ndarray, shape (K, 2)
            Cell centres, odometry frame, m.
        certainty : numpy.ndarray, shape (K,)
        """
        window = self.window if window is None else window
        res = self.resolution
        j0 = max(int((pose[0] - window - self.origin[0]) // res), 0)
        i0 = max(int((pose[1] - window - self.origin[1]) // res), 0)
        j1 = int((pose[0] + window - self.origin[0]) // res) + 1
        i1 = int((pose[1] + window - self.origin[1]) // res) + 1
        sub = self.grid[i0:i1, j0:j1]
        i, j = np.nonzero(sub)
        xy = np.column_stack(
            [
                self.origin[0] + (j + j0 + 0.5) * res,
                self.origin[1] + (i + i0 + 0.5) * res,
            ]
        )
        near = np.hypot(xy[:, 0] - pose[0], xy[:, 1] - pose[1]) < window
        return xy[near], sub[i, j][near]

    def polar(self, pose, window: float | None = None) -> np.ndarray:
        """Return the smoothed polar histogram at ``pose`` from the current grid.

        ``window``: the active window's radius (default: the controller's).
        """
        window = self.window if window is None else window
        if self.histogram_fn is not None:
            pts, cert = self.window_cells(pose, window)
            raw = np.asarray(self.histogram_fn(pts, cert, pose), dtype=float)
        else:
            _kernels.histogram_grid(
                self.grid,
                self.origin[0],
                self.origin[1],
                self.resolution,
                pose,
                window,
                self.enlarge,
                self._raw,
            )
            raw = self._raw
        out = np.empty(self.n_sectors)
        _kernels.smooth(np.ascontiguousarray(raw, dtype=np.float64), 2, out)
        return out

    def _choose(self, hist: np.ndarray, target: float) -> float:
        if self.direction_fn is not None:
            self._blocked = hist >= self.threshold_high
            return float(self.direction_fn(hist, self.threshold_high, target))
        # hysteresis: blocked above high, free below low, else as before
        _kernels.hysteresis(
            hist, self.threshold_low, self.threshold_high, self._blocked
        )
        previous = 0.0
        if self._has_previous:
            previous = _wrap(self._previous - self._heading)
        return _kernels.plus_direction(
            self._blocked,
            target,
            previous,
            self.wide,
            self.mu_goal,
            self.mu_heading,
            self.mu_previous,
        )

    def _relaxed(self, hist: np.ndarray, target: float) -> float:
        """Boxed in: steer into the thinnest valley (the threshold raised x2, x4, x8).

        Between boxes 0.8 m apart the enlarged cells block every sector,
        and a robot that only turns in place sees the same walls for ever
        (it spun for 90 s of a 120 s episode in the generated halls). The
        sonar brake still stops it short of any echo in its path.
        """
        for factor in (2.0, 4.0, 8.0):
            threshold = factor * self.threshold_high
            if self.direction_fn is not None:
                steer = float(self.direction_fn(hist, threshold, target))
            else:
                blocked = hist >= threshold
                if blocked.all():
                    continue
                previous = 0.0
                if self._has_previous:
                    previous = _wrap(self._previous - self._heading)
                steer = _kernels.plus_direction(
                    blocked, target, previous, self.wide, self.mu_goal,
                    self.mu_heading, self.mu_previous,
                )  # fmt: skip
            if not math.isnan(steer):
                return steer
        return math.nan

    def _escape(self, pose, dist: float, target: float, steer: float) -> float:
        """Trap escape: follow the obstacle's boundary until nearer the goal.

        When the distance to the goal has not shrunk by ``progress`` m for
        ``patience`` s (cycles of 0.1 s), follow the boundary on the side the
        histogram's choice leaned to, until the goal's sector is free and the
        robot is nearer the goal than where following began. A goal moved by
        more than 0.5 m (the next waypoint) starts the count afresh.
        """
        self._cycle += 1
        if self._aim is None or math.dist(self._aim, self.goal) > 0.5:
            # a new goal (a waypoint): progress towards it counts afresh
            self._aim = (float(self.goal[0]), float(self.goal[1]))
            self._best, self._best_cycle, self.following = math.inf, self._cycle, 0
        if dist < self._best - self.progress:
            self._best, self._best_cycle = dist, self._cycle
        if self.following == 0:
            if self._cycle - self._best_cycle > self.patience / 0.1:
                lean = _wrap(steer - target) if not math.isnan(steer) else 1.0
                self.following = 1 if lean >= 0 else -1
                self._follow_from = dist
                self.escapes += 1
            else:
                return steer
        n = self.n_sectors
        kt = int((_wrap(target) + math.pi) // (2 * math.pi / n)) % n
        if not self._blocked[kt] and dist < self._follow_from - self.progress:
            self.following = 0
            self._best, self._best_cycle = dist, self._cycle
            return steer
        return _kernels.follow_direction(
            self._blocked, target, self.following, self.follow_margin
        )

    def _fused(self, sonar, pose, window: float, target: float) -> float:
        """Grid, histogram and choice in one kernel call (the default parts)."""
        if self.origin is None:
            half = 0.5 * self.n_cells * self.resolution
            self.origin = np.array([pose[0] - half, pose[1] - half])
        previous = 0.0
        if self._has_previous:
            previous = _wrap(self._previous - self._heading)
        hist = np.empty(self.n_sectors)
        steer = _kernels.vfh_step(
            self.grid, self.origin[0], self.origin[1], self.resolution, pose,
            readonly(self.sensors), sonar, self.max_range, self.half_cone,
            self.clear_range,
            self.increment, self.decrement, self.cmax, self.fade, window,
            self.enlarge, 2, self._raw, hist, self.threshold_low,
            self.threshold_high, self._blocked, target, previous, self.wide,
            self.mu_goal, self.mu_heading, self.mu_previous,
        )  # fmt: skip
        self.histogram = hist
        return steer

    def _command(self, sonar: np.ndarray, pose: np.ndarray) -> tuple[float, float]:
        if self.goal is None:
            target, window, dist = 0.0, self.window, math.inf
        else:
            # what lies beyond the goal does not block the way to it
            target, dist = self.goal_direction(pose)
            window = min(self.window, dist + self.enlarge)
        self._heading = float(pose[2])
        if self.histogram_fn is None and self.direction_fn is None:
            steer = self._fused(sonar, pose, window, target)
            hist = self.histogram
        else:
            self.update_grid(sonar, pose)
            hist = self.polar(pose, window)
            self.histogram = hist
            steer = self._choose(hist, target)
        if self.goal is not None and self.escape:
            steer = self._escape(pose, dist, target, steer)
        if math.isnan(steer):
            steer = self._relaxed(hist, target)
        self.steer = steer
        if not math.isnan(steer):
            self._previous = _wrap(pose[2] + steer)
            self._has_previous = True
        if math.isnan(steer):  # boxed in: turn on the spot, one way
            if self._spin == 0.0:
                self._spin = 1.0
            return 0.0, self._spin * 0.5 * self.max_turn
        self._spin = 0.0
        w = self.turn_gain * steer
        n = self.n_sectors
        ahead = max(float(hist[n // 2 - 1]), float(hist[n // 2]))
        slow = 1.0 - min(ahead, self.threshold_high) / self.threshold_high
        turning = max(0.0, 1.0 - abs(steer) / (math.pi / 3))
        v = self.max_speed * max(slow, 0.2) * turning
        if self.goal is not None:
            v = min(v, 0.3 + 0.5 * dist)  # dist: the goal's, from above
        if self.brake > 0.0:
            v = min(v, self._braking_speed(sonar, w))
        return v, w

    def _braking_speed(self, sonar: np.ndarray, w: float) -> float:
        """Largest forward speed that stops short of any echo in the path, m/s."""
        s = self.sensors
        ok = sonar < self.max_range
        x = s[ok, 0] + sonar[ok] * np.cos(s[ok, 2])
        y = s[ok, 1] + sonar[ok] * np.sin(s[ok, 2])
        free = math.inf
        band = ROBOT_RADIUS + 0.03
        for turn in (0.0, 0.5 * w):  # straight on, and the heading in 0.5 s
            c, sn = math.cos(turn), math.sin(turn)
            ahead, side = c * x + sn * y, -sn * x + c * y
            hit = (np.abs(side) < band) & (ahead > 0.0)
            if hit.any():
                reach = ahead[hit] - np.sqrt(np.maximum(band**2 - side[hit] ** 2, 0.0))
                free = min(free, float(reach.min()))
        return math.sqrt(2.0 * self.brake * max(free - 0.05, 0.0))
