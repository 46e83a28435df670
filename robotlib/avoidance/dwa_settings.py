"""`DWASettings`: the knobs of `robotlib.avoidance.dwa.DWA`, with their defaults.

The velocity window and its samples, the roll-out, the objective's weights,
the obstacle grid, its navigation function and the escape when stuck. Change one with
`dataclasses.replace` or build a new one
(``DWA(settings=DWASettings(clearance_weight=0.5))``).

Imports only the Pioneer's constants; never plots.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..p3dx import (
    CYCLE,
    DEFAULT_ACCELERATION,
    DEFAULT_ROT_ACCELERATION,
    ROBOT_RADIUS,
    SONAR_CONE,
)

__all__ = ["DWASettings"]


@dataclass(frozen=True)
class DWASettings:
    """How `DWA` samples, predicts, scores and remembers (m, rad, s).

    Attributes
    ----------
    max_speed, max_turn : float
        Velocity limits, m/s and rad/s (0.5, 90 degrees/s); no reversing.
    accel, rot_accel : float
        Accelerations the window allows and braking assumes, m/s^2 and
        rad/s^2 (the Pioneer's defaults: 0.3, 100 degrees/s^2).
    window_time : float
        The window holds the velocities reachable from the last command within
        this time, s (0.3).
    n_v, n_w : int
        Samples of the translational and rotational velocity in the window
        (7, 15; both ends included).
    horizon, step : float
        Each sample's arc is rolled out for ``horizon`` s in steps of
        ``step`` s (2.5, 0.1).
    radius : float
        The disc that must not touch an obstacle point: the robot's radius
        plus a safety margin, m (`ROBOT_RADIUS` + 0.05).
    latency : float
        Time a command runs before the next one can brake it, s (`CYCLE`);
        an admissible sample stops within its free distance after it.
    heading_weight, progress_weight, clearance_weight, velocity_weight : float
        The objective: weights of the goal alignment at the arc's end
        (``1 - |angle| / pi``), of the progress towards the goal (as a
        fraction of ``max_speed * horizon``), of the free distance along the
        arc (capped at ``clearance_cap``, as a fraction of it) and of the
        speed (as a fraction of ``max_speed``) (0.5, 1.0, 0.4, 0.2).
    gap_weight, gap_cap : float
        Weight of the side clearance, how near the disc passes to the points
        along the part of the arc it drives (capped at ``gap_cap`` m, as a
        fraction of it) (0.3, 0.3 m): the robot keeps off walls it passes.
    turn_weight : float
        Weight of the turn rate ``|w| / max_turn``, taken off the score
        (0.1): every radian turned adds to the odometry's heading error, so
        a robot that weaves drifts more.
    clearance_cap : float
        Free distance beyond this counts as this, m (1.0).
    resolution, extent : float
        The obstacle grid's cell and side, m (0.1, 40; centred on the first
        pose seen).
    memory : float
        The grid's cells within sonar range fade with this time constant, s
        (30): what the front ring saw stays in view beside the robot and
        while it turns about, and what moved away is forgotten.
    occupied, cmax : float
        Certainty at which a cell is an obstacle, and its ceiling (2, 10;
        an echo adds 1, a sonar looking through takes 1).
    arc : float
        Each echo stands for points spread over this angle about the
        sonar's axis where the arcs are rolled out, rad (half of `SONAR_CONE`).
    arc_points : int
        Points per echo (3).
    recent : float
        The arcs are also stopped by every echo point of the last ``recent``
        s (in the odometry frame; the grid may have cleared a corner since),
        s (2).
    echo_cell : float
        Of the recent echo points in one square of this side only the
        newest is kept, m (0.05).
    block, margin : float
        The navigation function's paths keep at least ``block`` m from an
        occupied cell and pay more within ``block + margin`` m (`ROBOT_RADIUS`,
        0.5).
    border : float
        The navigation function covers the robot and the goal with this
        much to spare, m (2.0).
    replan : float
        Seconds between navigation functions (0.5; at once on a new goal).
    lookahead : float
        The goal terms aim at the point this far along the descent of the
        navigation function, m (1.5).
    patience, progress : float
        Stuck when the path left to the goal (the navigation function at the
        robot) has not shrunk by ``progress`` m in ``patience`` s (10, 0.3)
        with nothing new seen.
    look_time : float
        When stuck, the robot stops and turns for this long, s (3), so the
        front ring sees what lies beside it.
    tolerance : float
        Goal reached within this distance of the odometry pose, m (0.15).
    """

    max_speed: float = 0.5
    max_turn: float = math.radians(90.0)
    accel: float = DEFAULT_ACCELERATION
    rot_accel: float = DEFAULT_ROT_ACCELERATION
    window_time: float = 0.3
    n_v: int = 7
    n_w: int = 15
    horizon: float = 2.5
    step: float = 0.1
    radius: float = ROBOT_RADIUS + 0.05
    latency: float = CYCLE
    heading_weight: float = 0.5
    progress_weight: float = 1.0
    clearance_weight: float = 0.4
    velocity_weight: float = 0.2
    turn_weight: float = 0.1
    gap_weight: float = 0.3
    gap_cap: float = 0.3
    clearance_cap: float = 1.0
    resolution: float = 0.1
    extent: float = 40.0
    memory: float = 30.0
    occupied: float = 2.0
    cmax: float = 10.0
    arc: float = 0.5 * SONAR_CONE
    arc_points: int = 3
    recent: float = 2.0
    echo_cell: float = 0.05
    block: float = ROBOT_RADIUS
    margin: float = 0.5
    border: float = 3.0
    replan: float = 0.5
    lookahead: float = 1.5
    patience: float = 10.0
    progress: float = 0.3
    look_time: float = 3.0
    tolerance: float = 0.15

    def __post_init__(self):
        put = object.__setattr__
        floats = ("max_speed", "max_turn", "accel", "rot_accel", "window_time",
                  "horizon", "step", "radius", "latency", "heading_weight",
                  "progress_weight", "clearance_weight", "velocity_weight",
                  "turn_weight", "gap_weight", "gap_cap", "clearance_cap",
                  "resolution", "extent", "memory", "occupied", "cmax", "arc",
                  "recent", "echo_cell", "block", "margin", "border", "replan",
                  "lookahead", "patience", "progress", "look_time",
                  "tolerance")  # fmt: skip
        for name in floats:
            put(self, name, float(getattr(self, name)))
        for name in ("n_v", "n_w", "arc_points"):
            put(self, name, int(getattr(self, name)))
        positive = ("max_speed", "max_turn", "accel", "rot_accel", "window_time",
                    "horizon", "step", "radius", "clearance_cap", "gap_cap",
                    "resolution", "extent", "occupied", "cmax", "echo_cell",
                    "block", "lookahead")  # fmt: skip
        for name in positive:
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)}")
        if self.n_v < 2 or self.n_w < 2 or self.arc_points < 1:
            raise ValueError("n_v and n_w must be at least 2, arc_points at least 1")
        weights = (self.heading_weight, self.progress_weight, self.clearance_weight,
                   self.velocity_weight, self.turn_weight, self.gap_weight)  # fmt: skip
        if min(weights) < 0:
            raise ValueError("the objective's weights must be >= 0")
        if min(self.latency, self.memory, self.arc, self.recent, self.margin,
               self.border, self.replan, self.patience, self.progress,
               self.look_time) < 0:  # fmt: skip
            raise ValueError(
                "latency, memory, arc, recent, margin, border, replan, patience, "
                "progress and look_time must be >= 0"
            )
