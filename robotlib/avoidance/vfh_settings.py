"""`VFHSettings`: the knobs of `robotlib.avoidance.vfh.VFH`, with their defaults.

The certainty grid, the polar histogram, the valleys, the trap escape and the
command limits. Change one with `dataclasses.replace` or build a new one
(``VFH(settings=VFHSettings(threshold_high=200.0))``).

Imports only the Pioneer's constants; never plots.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..p3dx import ROBOT_RADIUS, SONAR_CONE

__all__ = ["VFHSettings"]


@dataclass(frozen=True)
class VFHSettings:
    """How `VFH` maps, weighs, chooses and drives (lengths m, angles rad).

    Attributes
    ----------
    resolution : float
        Certainty grid cell, m (0.1).
    extent : float
        Side of the square certainty grid, m, centred on the first pose seen
        (40).
    window : float
        Radius of the active window, m (1.8).
    enlarge : float
        Robot radius plus safety distance, m (`ROBOT_RADIUS` + 0.05).
    n_sectors : int
        Polar histogram sectors (72).
    threshold_low, threshold_high : float
        Binary histogram hysteresis: a sector becomes blocked above
        ``threshold_high`` and free again below ``threshold_low`` (75, 150).
    wide : int
        Sectors that make a valley wide (16).
    increment, decrement, cmax : float
        Certainty grid update: added at an echo, taken from each cell of the
        cone nearer than the echo, ceiling (1, 1, 30: balanced, so that a
        door painted shut by a jamb's echo opens again as fast).
    cone : float
        Full opening of a sonar's cone, rad (the grid clears inside it;
        `SONAR_CONE`).
    clear_range : float
        Cells further than this are never cleared, m (2.5).
    fade : float
        Each cycle the cells within the sonar's range are multiplied by this,
        so that what is no longer seen is forgotten (1: no fading).
    mu : tuple of float
        VFH+'s cost weights of a candidate direction's angle to the goal, to
        the current heading and to the previous choice ((5, 2, 2)).
    escape : bool
        Escape traps by following the obstacle's boundary (True).
    patience, progress : float
        A trap is declared when the distance to the goal has not shrunk by
        ``progress`` m in ``patience`` s (8 s, 0.3 m).
    follow_margin : int
        Sectors between the boundary and the direction followed (4).
    max_speed, max_turn : float
        Command limits, m/s and rad/s (0.5, 90 degrees/s).
    turn_gain : float
        Rotational velocity per radian of steering error, 1/s (1.5).
    tolerance : float
        Goal reached within this distance of the odometry pose, m (0.12).
        The odometry's drift is added to whatever is left to go: stopping
        0.3 m short spent most of the 0.5 m a true verdict allows (clutter
        arena, seeds 13, 101, 5, 7 of 10 pairs each: 8, 6, 7, 7 truly
        within 0.5 m at 0.3 m; 8, 9, 8, 9 at 0.12 m).
    brake : float
        The sonar brake's deceleration, m/s^2 (0.25; 0: no brake): whatever
        the grid says, the forward speed never exceeds what stops the robot
        (at this deceleration) short of an echo in its path, straight on or
        along the turn it is taking (`VFH` docs). The grid needs several
        echoes to block a sector; the brake acts on one.
    """

    resolution: float = 0.1
    extent: float = 40.0
    window: float = 1.8
    enlarge: float = ROBOT_RADIUS + 0.05
    n_sectors: int = 72
    threshold_low: float = 75.0
    threshold_high: float = 150.0
    wide: int = 16
    increment: float = 1.0
    decrement: float = 1.0
    cmax: float = 30.0
    cone: float = SONAR_CONE
    clear_range: float = 2.5
    fade: float = 1.0
    mu: tuple[float, float, float] = (5.0, 2.0, 2.0)
    escape: bool = True
    patience: float = 8.0
    progress: float = 0.3
    follow_margin: int = 4
    max_speed: float = 0.5
    max_turn: float = math.radians(90.0)
    turn_gain: float = 1.5
    tolerance: float = 0.12
    brake: float = 0.25

    def __post_init__(self):
        put = object.__setattr__
        # the kernels take exact types (no recompiling for an int given as 1)
        for name in ("resolution", "extent", "window", "enlarge", "threshold_low",
                     "threshold_high", "increment", "decrement", "cmax", "cone",
                     "clear_range", "fade", "patience", "progress", "max_speed",
                     "max_turn", "turn_gain", "tolerance", "brake"):  # fmt: skip
            put(self, name, float(getattr(self, name)))
        for name in ("n_sectors", "wide", "follow_margin"):
            put(self, name, int(getattr(self, name)))
        put(self, "escape", bool(self.escape))
        if len(self.mu) != 3:
            raise ValueError(f"mu holds three weights, got {self.mu!r}")
        put(self, "mu", tuple(float(m) for m in self.mu))
        if not (self.resolution > 0 and self.extent > 0 and self.window > 0):
            raise ValueError("resolution, extent and window must be > 0")
        if self.n_sectors < 4 or self.wide < 1:
            raise ValueError("n_sectors must be at least 4 and wide at least 1")
        if not 0 <= self.threshold_low <= self.threshold_high:
            raise ValueError("need 0 <= threshold_low <= threshold_high")
        if not 0.0 < self.fade <= 1.0:
            raise ValueError(f"fade must be in (0, 1], got {self.fade}")
