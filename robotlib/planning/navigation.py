"""The navigation loop's settings and record: `NavSettings`, `Navigation`.

`robotlib.planning.navigate.Navigator` takes a `NavSettings` and returns a
`Navigation`; both are plain data. Imports numpy only; never plots.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Navigation", "NavSettings", "LOCALIZE", "FOLLOW", "AVOID", "MODES"]

LOCALIZE, FOLLOW, AVOID = 0, 1, 2

MODES = ("localize", "follow", "avoid")
"""Names of the per-cycle modes in `Navigation.mode`."""


@dataclass(frozen=True)
class NavSettings:
    """The navigation loop's knobs (`Navigator`), with their defaults.

    Attributes
    ----------
    speed, lookahead : float
        Pure pursuit's cruise speed (m/s, 0.3) and look-ahead (m, 0.5).
    goal_tolerance : float
        Stop within this distance of the goal (by the estimate), m (0.15).
    filter_every : int
        Cycles (0.1 s each) between filter steps (2).
    spread : float
        The filter has converged when the particles' position spread is below
        this, m (and the heading spread below 0.15 rad) (0.15).
    min_filter_steps : int
        Filter steps before convergence is trusted (15).
    window, consistent, mode_share, mode_radius : int or float
        The belief must be settled over the last ``window`` filter steps
        (10) before the robot leaves LOCALIZE and before it says "reached":
        at every one of them the cloud was tight (``spread``) and unimodal
        (``mode_share`` of its weight within ``mode_radius`` m of the
        estimate: 0.95 and 0.5; the spread alone lets 9 % lie beyond 0.5 m),
        and each step's estimate, carried forward by the odometry since,
        lies within ``consistent`` m (0.25) and 0.1 rad of the newest. At
        the goal without it, the robot localizes again.
    spin : float
        Turn rate while localizing, rad/s (0.5).
    hit_range, unexplained : float
        A front echo shorter than ``hit_range`` and than the map's expected
        reading by ``unexplained`` is an unmapped obstacle, m (1.5, 0.3).
    replan_period : float
        New marks re-plan at most this often, s (1.0).
    off_track : float
        Re-plan when the estimate is this far off the path, m (0.7).
    lost_agreement : float
        The robot counts itself lost, and localizes again from scratch, when
        the share of sonar readings that agree with the map at the estimate
        (within 0.25 m + 10 %), smoothed over about 4 s, falls below this
        (0.62).
    no_progress : float
        It counts itself lost, too, when its plans have not got 0.5 m shorter
        for this long, s (it may be driving a look-alike place's plan) (30).
    confirm : float
        Before it says "reached", a second filter, run on the same readings
        from its own global start and seed, must have a tight cloud whose
        estimate lies within this of the first's, m (0.5; 0: no second
        filter). In a building of look-alike places a filter can settle in
        the wrong one, tight and agreeing with the sonar; two filters
        settling independently in the same wrong place is much rarer. When
        they disagree at the goal, both start again (LOCALIZE). Only with
        the navigator's own filters (a filter handed to it, e.g. one told
        the start pose, is trusted alone).
    rival_radius, rival_margin : float
        At the goal the estimate is also weighed by the whole drive
        (`robotlib.planning.aliasing.drive_score`) against the places given
        up earlier (at the goal in doubt, or lost) and the second filter's,
        each carried to now by the odometry, unless within ``rival_radius``
        m of it (1.0). If one of them explains the drive better by
        ``rival_margin`` (0.05), it does not say "reached": both filters
        start again around the best of them. Two filters can settle in
        the same look-alike room after a fresh start (an office floor: 8.6
        m off); the drive behind the robot, laid out from there, runs
        through walls.
    """

    speed: float = 0.3
    lookahead: float = 0.5
    goal_tolerance: float = 0.15
    filter_every: int = 2
    spread: float = 0.15
    min_filter_steps: int = 15
    window: int = 10
    consistent: float = 0.25
    mode_share: float = 0.95
    mode_radius: float = 0.5
    spin: float = 0.5
    hit_range: float = 1.5
    unexplained: float = 0.3
    replan_period: float = 1.0
    off_track: float = 0.7
    lost_agreement: float = 0.62
    no_progress: float = 30.0
    confirm: float = 0.5
    rival_radius: float = 1.0
    rival_margin: float = 0.05

    def __post_init__(self):
        if int(self.filter_every) < 1 or int(self.min_filter_steps) < 0:
            raise ValueError("filter_every must be >= 1 and min_filter_steps >= 0")
        if int(self.window) < 1 or not 0.0 <= self.mode_share <= 1.0:
            raise ValueError("window must be >= 1 and mode_share in [0, 1]")
        if self.confirm < 0:
            raise ValueError(f"confirm must be >= 0, got {self.confirm!r}")
        for name in ("speed", "lookahead", "goal_tolerance", "spread", "spin"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)!r}")


@dataclass
class Navigation:
    """What a `Navigator` did, cycle by cycle (plain arrays).

    Attributes
    ----------
    time : numpy.ndarray, shape (T,)
        Robot clock since the start, s.
    truth : numpy.ndarray, shape (T, 3)
        True pose where the backend reports one (else NaN), m and rad.
    odometry, estimate : numpy.ndarray, shape (T, 3)
        Odometry pose and the MCL estimate (advanced by odometry between
        filter steps), m and rad.
    command : numpy.ndarray, shape (T, 2)
        ``(v, w)`` sent, m/s and rad/s.
    mode : numpy.ndarray of int8, shape (T,)
        `LOCALIZE`, `FOLLOW` or `AVOID`.
    sonar : numpy.ndarray, shape (T, 8)
        Ranges, m.
    stalled : numpy.ndarray of bool, shape (T,)
        The robot reported a stall (it touched something).
    plans : list of numpy.ndarray
        Every path planned, (K, 2) each, m.
    plan_times : numpy.ndarray, shape (P,)
        When each was planned, s.
    hits : numpy.ndarray, shape (H, 2)
        Sonar echoes marked as unmapped obstacles, m.
    goal : numpy.ndarray, shape (2,)
        The goal, m.
    outcome : str
        ``"reached"`` (the estimate within the tolerance of the goal),
        ``"ambiguous"`` (at the goal by the estimate, but the map looks the
        same turned and the drive since localizing fits the turned place as
        well: `robotlib.planning.aliasing`), ``"collision"``, ``"timeout"``
        or ``"no_path"``.
    localized_at : float
        When the filter first converged, s (NaN if never).
    agreement : numpy.ndarray, shape (T,)
        Smoothed share of sonar readings that agree with the map at the
        estimate.
    lost_times : numpy.ndarray
        When the robot counted itself lost and localized again, s.
    doubt_times : numpy.ndarray
        When the robot stood at the goal by its estimate but the second
        filter disagreed (`NavSettings.confirm`), so it localized again, s.
    """

    time: np.ndarray
    truth: np.ndarray
    odometry: np.ndarray
    estimate: np.ndarray
    command: np.ndarray
    mode: np.ndarray
    sonar: np.ndarray
    stalled: np.ndarray
    plans: list = field(default_factory=list)
    plan_times: np.ndarray = field(default_factory=lambda: np.zeros(0))
    hits: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    goal: np.ndarray = field(default_factory=lambda: np.zeros(2))
    outcome: str = ""
    localized_at: float = float("nan")
    agreement: np.ndarray = field(default_factory=lambda: np.zeros(0))
    lost_times: np.ndarray = field(default_factory=lambda: np.zeros(0))
    doubt_times: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def reached(self) -> bool:
        """The loop stopped at the goal (by its own estimate)."""
        return self.outcome == "reached"

    @property
    def final_error(self) -> float:
        """Distance from the final true position to the goal, m (NaN: no truth)."""
        return float(np.hypot(*(self.truth[-1, :2] - self.goal)))

    @property
    def false_reached(self) -> bool:
        """Said "reached" while truly more than 0.5 m from the goal."""
        return self.reached and not self.final_error <= 0.5

    @property
    def success(self) -> bool:
        """Reached, no stall, and truly within 0.3 m of the goal."""
        return self.reached and not self.stalled.any() and self.final_error <= 0.3

    @property
    def duration(self) -> float:
        """Simulated (robot) time used, s."""
        return float(self.time[-1]) if len(self.time) else 0.0
