"""`ExploreSettings`: the knobs of an exploration, with their defaults.

Change one with `dataclasses.replace` or build a new one
(``explore(world, settings=ExploreSettings(sensor="sonar"))``). Imports
nothing of robotlib but the frontier choices; never plots.
"""

from __future__ import annotations

from dataclasses import dataclass

from .choice import STRATEGIES

__all__ = ["ExploreSettings", "SENSORS", "POSES"]

SENSORS = ("laser", "sonar")
"""The sensors a robot maps with."""

POSES = ("true", "slam")
"""Where the poses a robot maps from come from: the simulator's truth, or
each robot's own grid FastSLAM (`robotlib.mapping.GridFastSLAM`)."""


@dataclass(frozen=True)
class ExploreSettings:
    """How robots map, choose frontiers, drive and stop (lengths m, times s).

    Attributes
    ----------
    sensor : {"laser", "sonar"}
        What each robot maps with.
    pose : {"true", "slam"}
        Map from the true pose or from SLAM's estimate.
    strategy : {"nearest", "utility", "coordinated"}
        The frontier choice (`robotlib.exploration.choose`).
    resolution : float
        Map cell side (0.1).
    beta : float
        Weight of the path cost against the information gain, m^2 per m (0.5).
    gain_radius : float
        Half-side of the window in which unknown area counts as gain (1.5).
    discount_radius : float
        Range of the coordination discount (6; of 4, 6 and 8 m, three
        robots reached 90 % soonest with 6 on generated halls and offices).
    free_level, occupied_level : float
        Log-odds below ``-free_level`` are free, above ``occupied_level``
        occupied, unknown between (0.2, 0.2).
    min_frontier : int
        Smallest frontier region, cells (4).
    margin : float
        Clearance beyond the robot's radius kept from known walls (0.1).
    speed, w_max, lookahead : float
        Pure pursuit's cruise speed (m/s, 0.5), largest turn rate (rad/s,
        1.0), look-ahead distance (0.5).
    goal_tolerance : float
        A target is reached within this distance (0.3).
    decide_period : float
        How often frontiers are found again, paths checked against the new
        map and robots that need a target given one (1.0).
    keep_out : float
        A robot stops while a teammate's centre is closer than this plus
        its own stopping distance (at 0.3 m/s^2) and ahead of it (0.9).
    wait_time : float
        How long a robot blocked by a teammate waits before it re-plans
        around its teammates (2.0; twice as long for every later robot, so
        two robots facing each other do not move off at once).
    max_time : float
        Simulated time limit (1800).
    coverage_period : float
        Coverage sampled this often (1.0).
    snapshot_period : float
        Keep the map and poses this often for animations (0: never).
    particles : int
        FastSLAM particles per robot when ``pose`` is ``"slam"`` (15).
    go_home : bool
        Drive back to the start once nothing is left to explore (True).
    """

    sensor: str = "laser"
    pose: str = "true"
    strategy: str = "coordinated"
    resolution: float = 0.1
    beta: float = 0.5
    gain_radius: float = 1.5
    discount_radius: float = 6.0
    free_level: float = 0.2
    occupied_level: float = 0.2
    min_frontier: int = 4
    margin: float = 0.1
    speed: float = 0.5
    w_max: float = 1.0
    lookahead: float = 0.5
    goal_tolerance: float = 0.3
    decide_period: float = 1.0
    keep_out: float = 0.9
    wait_time: float = 2.0
    max_time: float = 1800.0
    coverage_period: float = 1.0
    snapshot_period: float = 0.0
    particles: int = 15
    go_home: bool = True

    def __post_init__(self):
        if self.sensor not in SENSORS:
            raise ValueError(f"sensor must be one of {SENSORS}, got {self.sensor!r}")
        if self.pose not in POSES:
            raise ValueError(f"pose must be one of {POSES}, got {self.pose!r}")
        if self.strategy not in STRATEGIES:
            raise ValueError(
                f"strategy must be one of {STRATEGIES}, got {self.strategy!r}"
            )
        positive = (
            "resolution", "gain_radius", "discount_radius", "speed", "w_max",
            "lookahead", "goal_tolerance", "decide_period", "max_time",
            "coverage_period", "keep_out",
        )  # fmt: skip
        for name in positive:
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be positive")
        if self.beta < 0 or self.margin < 0 or self.wait_time < 0:
            raise ValueError("beta, margin and wait_time must be >= 0")
        if self.snapshot_period < 0 or self.particles < 1 or self.min_frontier < 1:
            raise ValueError(
                "need snapshot_period >= 0, particles >= 1, min_frontier >= 1"
            )
