"""The dynamic window approach (Fox, Burgard and Thrun 1997) on sonar and odometry.

Each cycle the controller samples the velocities ``(v, w)`` it can reach
from its last command within ``window_time`` s at the Pioneer's
accelerations (`dynamic_window`), rolls every sample out along its arc for
``horizon`` s against the obstacle points it knows (`evaluate_window`: the
distance it drives before its disc touches one, how well it then faces the
goal, how much nearer the goal it gets), keeps the admissible ones (those that
can still brake to a stop, after one cycle of latency, before touching
anything: ``v * latency + v**2 / (2 accel) <= free``) and picks the best of
the objective (`choose_velocity`: heading, progress, free distance, side
clearance and speed, less the turn rate, weighted, each about [0, 1]).

The obstacle points are the occupied cells of a short-memory certainty grid
(`robotlib.avoidance.dwa_grid.ObstacleGrid`, filled from the sonar as
VFH's is, fading with a time constant of ``memory`` s) and the echoes of
the last ``recent`` s, each standing for a few points across the middle of
its cone (a sonar does not say where in its cone the echo came from): the
grid keeps a wall end seen earlier beside the robot, the recent echoes a
corner the grid may have cleared since.

The goal terms do not aim at the goal itself but at the point ``lookahead``
m along the steepest descent of a navigation function over the grid (the
shortest way to the goal round everything seen; Brock and Khatib 1999), so
the robot heads for the door it has seen, and out of a U-shaped trap
round its arm, instead of circling in front of the wall between it and the
goal. Unseen cells count as free, so it still drives into a trap it has
not seen; once inside, the grid shows the way out. When the length of that
way has not shrunk by ``progress`` m in ``patience`` s the robot is stuck:
it stops and turns for ``look_time`` s, and the front ring sees what lies
beside it. At rest with no admissible way forward it turns to the open
direction nearest its aim (`open_directions`).

Imports: numpy, the kernels, `robotlib.avoidance.base`, `.dwa_grid` and
`.dwa_settings`; never plotting.
"""

from __future__ import annotations

import math

import numpy as np

from ..p3dx import CYCLE
from . import _kernels
from .base import Controller, goal_in_robot_frame
from .dwa_grid import ObstacleGrid
from .dwa_settings import DWASettings

__all__ = [
    "DWA",
    "dynamic_window",
    "evaluate_window",
    "choose_velocity",
    "open_directions",
]


def dynamic_window(v0: float, w0: float, settings: DWASettings):
    """Velocity samples reachable from ``(v0, w0)`` within ``window_time``.

    Parameters
    ----------
    v0, w0 : float
        The current (last commanded) velocities, m/s and rad/s.
    settings : DWASettings

    Returns
    -------
    vs : numpy.ndarray, shape (n_v,)
        Translational samples in ``[0, max_speed]``, m/s, ascending (equal
        samples where the window is clipped to a point).
    ws : numpy.ndarray, shape (n_w,)
        Rotational samples in ``[-max_turn, max_turn]``, rad/s, ascending;
        0 is among them whenever the window reaches it.
    """
    s = settings
    dv, dw = s.accel * s.window_time, s.rot_accel * s.window_time
    v_lo, v_hi = max(0.0, v0 - dv), min(s.max_speed, v0 + dv)
    if v_lo > v_hi:  # above the limit (a setting changed): brake towards it
        v_lo = v_hi = max(0.0, min(v0 - dv, s.max_speed))
    w_lo, w_hi = max(-s.max_turn, w0 - dw), min(s.max_turn, w0 + dw)
    if w_lo > w_hi:
        w_lo = w_hi = min(max(w0, -s.max_turn), s.max_turn)
    vs = np.linspace(v_lo, v_hi, s.n_v)
    ws = np.linspace(w_lo, w_hi, s.n_w)
    if w_lo < 0.0 < w_hi:  # driving straight is always among the choices
        ws[np.argmin(np.abs(ws))] = 0.0
    return vs, ws


def evaluate_window(points, vs, ws, goal, settings: DWASettings):
    """Roll out each ``(v, w)`` sample against obstacle points (robot frame).

    Parameters
    ----------
    points : array_like, shape (P, 2)
        Obstacle points in the robot frame (x ahead, y left), m.
    vs, ws : array_like, shape (V,) and (W,)
        Velocity samples, m/s and rad/s.
    goal : array_like, shape (2,)
        The goal in the robot frame, m.
    settings : DWASettings
        ``horizon``, ``step``, ``radius`` and ``gap_cap`` are read.

    Returns
    -------
    free : numpy.ndarray, shape (V, W)
        Distance driven along each arc before the disc of ``radius`` touches
        a point it approaches, m (inf: not within the horizon).
    heading : numpy.ndarray, shape (V, W)
        Absolute angle between the heading at the end of the part driven and
        the direction from there to the goal, rad, in [0, pi].
    togo : numpy.ndarray, shape (V, W)
        Distance from the end of the part driven to the goal, m.
    gap : numpy.ndarray, shape (V, W)
        Smallest distance between the disc and a point along the part
        driven (up to the pose that touched), m, at most ``gap_cap``
        (negative: a point already inside the disc).
    """
    pts = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 2)
    vs = np.ascontiguousarray(vs, dtype=np.float64).reshape(-1)
    ws = np.ascontiguousarray(ws, dtype=np.float64).reshape(-1)
    goal = np.ascontiguousarray(goal, dtype=np.float64).reshape(-1)
    if goal.shape != (2,):
        raise ValueError(f"goal must have shape (2,), got {goal.shape}")
    if not (np.isfinite(pts).all() and np.isfinite(vs).all() and np.isfinite(ws).all()):
        raise ValueError("points and velocity samples must be finite")
    steps = int(math.ceil(settings.horizon / settings.step - 1e-9))
    shape = (len(vs), len(ws))
    free, heading, togo, gap = (np.empty(shape) for _ in range(4))
    _kernels.dwa_evaluate(
        pts, vs, ws, steps, settings.step, settings.radius, settings.gap_cap, goal,
        free, heading, togo, gap,
    )  # fmt: skip
    return free, heading, togo, gap


def choose_velocity(
    vs, ws, free, heading, togo, gap, goal_distance, settings: DWASettings
):
    """Pick the best admissible sample of the objective.

    A sample is admissible when it can brake to a stop, after
    ``settings.latency`` s, within its free distance:
    ``v * latency + v**2 / (2 accel) <= free``. Its score is the weighted sum
    of these terms: the goal alignment ``1 - heading / pi``; the progress
    ``(goal_distance - togo) / (max_speed * horizon)``; the free distance
    ``min(free, clearance_cap) / clearance_cap`` (Fox et al.'s "dist"); the
    side clearance ``max(gap, 0) / gap_cap`` (how far the arc passes from
    what it does not hit); the speed ``v / max_speed``; minus the turn
    ``|w| / max_turn`` (turning makes the odometry drift). A sample at rest,
    ``v == 0``, counts the free distance and the side clearance of the
    slowest sample moving off along its turn.

    Parameters
    ----------
    vs, ws : array_like, shape (V,) and (W,)
        Velocity samples, m/s and rad/s.
    free, heading, togo, gap : array_like, shape (V, W)
        From `evaluate_window`.
    goal_distance : float
        The goal's distance now, m.
    settings : DWASettings

    Returns
    -------
    v, w : float
        The chosen sample; ``(0, 0)`` when none is admissible (stop).
    score : numpy.ndarray, shape (V, W)
        The objective, ``-inf`` where inadmissible.
    """
    s = settings
    vs = np.asarray(vs, dtype=float)
    ws = np.asarray(ws, dtype=float)
    free = np.asarray(free, dtype=float)
    v = vs[:, None]
    admissible = v * s.latency + v**2 / (2.0 * s.accel) <= free
    clear = np.minimum(free, s.clearance_cap) / s.clearance_cap
    side = np.clip(np.asarray(gap, dtype=float), 0.0, s.gap_cap) / s.gap_cap
    if len(vs) > 1 and vs[0] == 0.0 < vs[1]:
        # at rest a sample is as clear as setting off along its turn: were
        # standing still always clearest, DWA would stall beside a box
        clear[0], side[0] = clear[1], side[1]
    score = (
        s.heading_weight * (1.0 - np.asarray(heading) / math.pi)
        + s.progress_weight
        * (goal_distance - np.asarray(togo))
        / (s.max_speed * s.horizon)
        + s.clearance_weight * clear
        + s.gap_weight * side
        + s.velocity_weight * v / s.max_speed
        - s.turn_weight * np.abs(ws)[None, :] / s.max_turn
    )
    score = np.where(admissible, score, -np.inf)
    if not admissible.any():
        return 0.0, 0.0, score
    i, j = np.unravel_index(int(np.argmax(score)), score.shape)
    return float(vs[i]), float(ws[j]), score


def open_directions(points, radius: float, n: int = 72) -> tuple:
    """Free straight-line distance in ``n`` directions round the robot.

    Parameters
    ----------
    points : array_like, shape (P, 2)
        Obstacle points, robot frame, m.
    radius : float
        The disc swept along each direction, m.
    n : int
        Directions, ``-pi + (k + 0.5) 2 pi / n``.

    Returns
    -------
    angles : numpy.ndarray, shape (n,)
        The directions, rad (robot frame).
    free : numpy.ndarray, shape (n,)
        Distance the disc can move along each before touching a point it
        approaches, m (inf: none).
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    angles = -math.pi + (np.arange(n) + 0.5) * 2.0 * math.pi / n
    along = np.cos(angles)[:, None] * pts[:, 0] + np.sin(angles)[:, None] * pts[:, 1]
    perp = -np.sin(angles)[:, None] * pts[:, 0] + np.cos(angles)[:, None] * pts[:, 1]
    blocks = (np.abs(perp) < radius) & (along > 0.0)
    dist = along - np.sqrt(np.maximum(radius**2 - perp**2, 0.0))
    free = np.where(blocks, np.maximum(dist, 0.0), np.inf).min(axis=1, initial=np.inf)
    return angles, free


class DWA(Controller):
    """Dynamic window approach on the sonar ring and odometry.

    Parameters
    ----------
    goal : array_like, shape (2,), optional
        Goal in the odometry frame, m.
    settings : DWASettings, optional
        Window, roll-out, objective, grid and escape (default: `DWASettings()`).

    Attributes
    ----------
    settings : DWASettings
    grid : ObstacleGrid
        The short-memory certainty grid and its navigation function.
    last : tuple of float
        The last command ``(v, w)``, the centre of the next window.
    aim : numpy.ndarray, shape (2,)
        The point the goal terms aimed at last (odometry frame, m): the
        navigation function's carrot, or the goal.
    score : numpy.ndarray, shape (n_v, n_w)
        The last objective (``-inf``: inadmissible), for plotting.
    window : tuple of numpy.ndarray
        The last samples ``(vs, ws)``.
    escapes : int
        How often the robot found itself stuck and turned to look round.
    """

    name = "DWA"

    def __init__(self, goal=None, settings: DWASettings | None = None):
        s = DWASettings() if settings is None else settings
        if not isinstance(s, DWASettings):
            raise TypeError(f"settings must be a DWASettings, got {type(s).__name__}")
        self.settings = s
        offsets = np.linspace(-0.5 * s.arc, 0.5 * s.arc, s.arc_points)
        self._offsets = offsets if s.arc_points > 1 else np.zeros(1)
        self.grid = ObstacleGrid(s.resolution, s.extent, s.memory, s.occupied, s.cmax)
        super().__init__(goal, s.tolerance, s.max_speed, s.max_turn)

    def _reset(self) -> None:
        self.grid.reset()
        self._recent = np.zeros((0, 3))  # echo points (x, y odometry, time seen)
        self._clock = 0.0
        self.last = (0.0, 0.0)
        self.aim = np.zeros(2)
        self.score = np.zeros((0, 0))
        self.window = (np.zeros(0), np.zeros(0))
        self.escapes = 0
        self._planned_for, self._next_plan = None, 0.0
        self._best, self._best_time = math.inf, 0.0
        self._turn_until = -1.0

    def echo_points(self, sonar: np.ndarray) -> np.ndarray:
        """Return this scan's echoes, a few across each cone's middle, robot frame, m.

        Returns
        -------
        numpy.ndarray, shape (P, 2)
        """
        echo = sonar < self.max_range
        sens, r = self.sensors[echo], sonar[echo]
        ang = sens[:, 2:3] + self._offsets[None, :]
        px = sens[:, 0:1] + r[:, None] * np.cos(ang)
        py = sens[:, 1:2] + r[:, None] * np.sin(ang)
        return np.column_stack([px.ravel(), py.ravel()])

    def _echoes(self, sonar: np.ndarray, pose: np.ndarray, reach: float) -> np.ndarray:
        """Return the echo points of the last ``recent`` s nearer than ``reach`` m.

        Robot frame, m, shape (P, 2). The grid lets a sonar looking past a
        corner clear it; these are never cleared, so a corner seen a moment
        ago still stops the arcs.
        Of the points in one ``echo_cell`` square only the newest is kept
        (a robot at rest hears the same echoes every cycle).
        """
        local = self.echo_points(sonar)
        c, si = math.cos(pose[2]), math.sin(pose[2])
        now = np.column_stack([
            pose[0] + c * local[:, 0] - si * local[:, 1],
            pose[1] + si * local[:, 0] + c * local[:, 1],
            np.full(len(local), self._clock),
        ])  # fmt: skip
        keep = self._recent[:, 2] > self._clock - self.settings.recent - 1e-9
        recent = np.concatenate([now, self._recent[keep]])
        key = np.floor(recent[:, :2] / self.settings.echo_cell).astype(np.int64)
        _, first = np.unique(key, axis=0, return_index=True)  # the newest of each
        self._recent = recent[np.sort(first)]
        d = self._recent[:, :2] - pose[:2]
        d = d[np.hypot(d[:, 0], d[:, 1]) < reach]
        return np.column_stack(
            [c * d[:, 0] + si * d[:, 1], -si * d[:, 0] + c * d[:, 1]]
        )

    def _target(self, pose: np.ndarray) -> tuple[np.ndarray, float]:
        """Return the point to aim at and the path length left to the goal, m."""
        s = self.settings
        goal = tuple(float(g) for g in self.goal)
        if goal != self._planned_for or self._clock >= self._next_plan:
            self.grid.plan(pose, self.goal, s.block, s.margin, s.border)
            self._planned_for, self._next_plan = goal, self._clock + s.replan
        carrot, togo = self.grid.carrot(pose, self.goal, s.lookahead)
        if carrot is None:  # no known path: straight for the goal
            return np.asarray(self.goal, dtype=float), math.dist(pose[:2], self.goal)
        return carrot, togo

    def _open_towards(self, points: np.ndarray, target: float) -> float:
        """Return the open direction nearest ``target`` (robot frame, rad).

        A direction is open when the disc can drive ``clearance_cap`` m along
        it; ``target`` itself is returned when it is open (or nothing is).
        """
        s = self.settings
        angles, free = open_directions(points, s.radius)
        k = int((target + math.pi) // (2 * math.pi / len(angles))) % len(angles)
        open_ = free >= s.clearance_cap
        if open_[k] or not open_.any():
            return target
        off = np.abs(np.remainder(angles - target + math.pi, 2 * math.pi) - math.pi)
        return float(angles[open_][np.argmin(off[open_])])

    def _stuck(self, togo: float) -> bool:
        """Whether the path left has not shrunk by ``progress`` in ``patience`` s."""
        s = self.settings
        if togo < self._best - s.progress or not math.isfinite(self._best):
            self._best, self._best_time = min(togo, self._best), self._clock
        return self._clock - self._best_time > s.patience

    def _command(self, sonar: np.ndarray, pose: np.ndarray) -> tuple[float, float]:
        s = self.settings
        if self.goal is None:
            raise ValueError("DWA needs a goal (DWA(goal=...) or command(..., goal))")
        self._clock += CYCLE  # one command per robot cycle
        self.grid.update(sonar, pose)
        self.aim, togo = self._target(pose)
        ax, ay = goal_in_robot_frame(self.aim, pose)
        bearing = math.atan2(ay, ax)
        if self._stuck(togo):
            self.escapes += 1
            self._best, self._best_time = math.inf, self._clock
            self._turn_until = self._clock + s.look_time
        reach = s.max_speed * s.horizon + s.radius + s.clearance_cap
        seen = self.grid.points(pose, reach)
        points = np.concatenate([seen, self._echoes(sonar, pose, reach)])
        vs, ws = dynamic_window(*self.last, s)
        if self._clock < self._turn_until:  # escape: stop and turn to look round
            vs = np.zeros_like(vs)
        free, heading, togo_arc, gap = evaluate_window(points, vs, ws, (ax, ay), s)
        dist = math.hypot(ax, ay)
        v, w, self.score = choose_velocity(
            vs, ws, free, heading, togo_arc, gap, dist, s
        )
        if v == 0.0 and self.last[0] == 0.0:  # at rest: turn to the open way
            turn = min(s.max_turn, s.rot_accel * s.window_time + abs(self.last[1]))
            w = float(np.clip(2.0 * self._open_towards(points, bearing), -turn, turn))
        self.window = (vs, ws)
        self.last = (v, w)
        return v, w
