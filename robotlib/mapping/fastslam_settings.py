"""Grid FastSLAM's knobs: `FastSLAMSettings` and the sonar's tuned defaults.

`robotlib.mapping.fastslam.GridFastSLAM` takes the map's cells, the start
pose, the particle count, the sensor and one `FastSLAMSettings`; every
research knob (weighing, scan matching, the sonar's beam model and wall
marking, the estimate reported) lives here with its default. The
measurements behind `SONAR_SETTINGS` and `SONAR_PARTICLES` are in
``bench/results/fastslam_sonar.md`` (``robotlib bench map``).

Imports the inverse sensor models and the simulator's odometry noise model
only; never plots.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..sim import OdometryNoise
from .occupancy import InverseLaserModel, InverseSonarModel

__all__ = [
    "FastSLAMSettings",
    "SONAR_PARTICLES",
    "SONAR_SETTINGS",
    "SONAR_WALL_SENSORS",
]

SONAR_WALL_SENSORS = (0, 3, 4, 7)
"""The P3-DX ring's sonars at +-90 and +-10 degrees: along a corridor or a
wall they meet the side walls and the walls ahead near their normal, where
the echo comes from the cone's axis (the +-30 and +-50 degree ones meet the
side walls 40-60 degrees off their normal, and echo from the cone's edge)."""

_CHOICES = {
    "sonar_likelihood": ("beam", "endpoint"),
    "window_weigh": ("window", "last"),
    "best_by": ("weight", "path"),
    "sonar_range_to": ("entry", "centre"),
    "estimate": ("best", "mean"),
    "proposal": ("fit", "gaussian"),
}


@dataclass(frozen=True)
class FastSLAMSettings:
    """How `GridFastSLAM` moves, weighs, matches, maps and reports.

    Change one with `dataclasses.replace` (``replace(SONAR_SETTINGS,
    temperature=0.1)``).

    Attributes
    ----------
    laser_model, sonar_model : InverseLaserModel, InverseSonarModel
        The inverse sensor models (the particles' map updates).
    motion : OdometryNoise
        Slip assumed by the prediction (default: the simulator's).
    inflate : float
        Motion noise standard deviations times this (1.5).
    beam_step : int
        Weigh with every ``beam_step``-th laser beam (2).
    p_rand : float
        Floor of each beam's likelihood, a random reading (0.1).
    temperature : float
        Log-likelihoods times this before they are added to the weights,
        because beams are not independent (0.5).
    resample_below : float
        Resample when the effective sample size is below this share of N (0.5).
    match : bool
        Laser only: after the motion sample, fit each particle's pose to its
        own map by hill-climbing on the scan's end points
        (`GridFastSLAM.match_laser`), a cheap version of GMapping's
        scan-matched proposal (True).
    match_step : tuple of float
        First hill-climbing steps, m and rad, halved ``match_levels`` times
        ((0.04, 0.02)).
    match_levels : int
        How many times the steps are halved (3).
    match_beam_step : int
        Fit with every ``match_beam_step``-th beam (4).
    match_prior : tuple of float
        ``(w_xy, w_th)``: the fit's score less ``w_xy d^2 + w_th a^2`` for a
        move ``d`` m and a turn ``a`` rad from the motion's sample, so that a
        scan which does not pin the pose along a corridor leaves it where the
        motion put it ((0, 0): none; default (300, 300)).
    match_degenerate : float
        Keep a fit's move only along the position directions whose score
        curvature is at least this share of the sharpest one's
        (`robotlib.mapping.fastslam.constrained_fit`): along a blank
        corridor the pose stays the motion's sample (0, the default: keep
        every fit whole). The whole fit drags the pose back along a blank
        corridor (8.5-9.3 m behind after 20 m, seeds 1-3; 0.2 here: within
        0.2 m of the odometry). 0.2 suits buildings of long blank corridors
        (generated rings, 10 seeds, in the issue-31 note); on the loop world,
        whose doors pin the fit along its corridors, it costs accuracy
        (RMS 0.037 to 0.2 m), hence off by default.
    proposal : {"fit", "gaussian"}
        Laser only, with ``match``: how a particle's new pose is drawn.
        "fit" (the default): the motion's sample, hill-climbed on the map
        (above), weighed by `GridFastSLAM.weigh_laser` there. "gaussian":
        GMapping's improved proposal (`robotlib.mapping.proposal`): the
        odometry's prediction fitted by the scan's likelihood field (every
        ``beam_step``-th return, each scored by its distance to the nearest
        occupied cell along its surface's normal) plus the motion prior, a
        draw from the Gaussian of the posterior about that fit, the weight
        times the proposal's normaliser.
    proposal_sigma : float
        "gaussian": standard deviation of a return's end point about the
        nearest occupied cell centre (along its normal), m (0.05).
    proposal_floor : tuple of float
        "gaussian": ``(m, rad)``, the least standard deviations of the motion
        prior (for a robot standing still) along and across its heading and
        in heading ((0.005, 0.005)); the proposal's grid is spaced by the
        prior's deviations and its draw's deviations are at least a quarter
        of them.
    sonar_likelihood : {"beam", "endpoint"}
        Sonar weighing: the beam model (`_kernels.sonar_beam_loglik`) or the
        end-point model over the arc, as the laser's ("beam").
    sonar_sigma : float
        Beam model: standard deviation of an echo about the expected range,
        m (0.15).
    sonar_occ : float
        Beam model: log-odds above which a cell is a wall, confirmed by
        several echoes so that the arcs' stray cells do not count (2.0).
    sonar_unknown : float
        Beam model: weight of an echo from cells the map has not seen (0.5).
    sonar_walls : tuple of int or None
        Sonar only: the sonars (indexes into the sonar model's ``sensors``)
        whose echoes mark the arc occupied; the others' readings free their
        cones only. None (the default): all. A cone that meets a wall
        obliquely echoes from its edge nearest the wall's normal and puts
        occupied cells in free space; `SONAR_WALL_SENSORS` are the P3-DX
        sonars that meet the walls it drives along or towards near their
        normal.
    sonar_incidence : float or None
        Sonar only: choose per reading and particle which echoes mark walls,
        those whose wall in the particle's map (the log-odds gradient at the
        echo) is within this angle (rad) of facing the sonar; where the map
        shows no wall yet, ``sonar_walls`` decides. None (the default): off.
    window : int
        Sonar only: keep each particle's last ``window`` records out of its
        map and weigh by them in the map of the records before them (0, the
        default: none).
    window_weigh : {"window", "last"}
        Weigh by every record of the window (their log-likelihoods summed) or
        by the newest only ("window").
    best_by : {"weight", "path"}
        Which particle `GridFastSLAM.best` picks: the largest weight (the
        evidence since the last resampling) or the largest summed
        log-likelihood along its lineage, the whole run's evidence ("weight").
    sonar_range_to : {"entry", "centre"}
        Sonar beam model: a ray's expected range is where it enters its first
        wall cell, or that cell's centre ("entry").
    estimate : {"best", "mean"}
        What `robotlib.mapping.run_fastslam` reports: the best particle's
        lineage and map, or the posterior mean trajectory and its map ("best").
    """

    laser_model: InverseLaserModel = field(default_factory=InverseLaserModel)
    sonar_model: InverseSonarModel = field(default_factory=InverseSonarModel)
    motion: OdometryNoise = field(default_factory=OdometryNoise)
    inflate: float = 1.5
    beam_step: int = 2
    p_rand: float = 0.1
    temperature: float = 0.5
    resample_below: float = 0.5
    match: bool = True
    match_step: tuple[float, float] = (0.04, 0.02)
    match_levels: int = 3
    match_beam_step: int = 4
    match_prior: tuple[float, float] = (300.0, 300.0)
    match_degenerate: float = 0.0
    proposal: str = "fit"
    proposal_sigma: float = 0.05
    proposal_floor: tuple[float, float] = (0.005, 0.005)
    sonar_likelihood: str = "beam"
    sonar_sigma: float = 0.15
    sonar_occ: float = 2.0
    sonar_unknown: float = 0.5
    sonar_walls: tuple[int, ...] | None = None
    sonar_incidence: float | None = None
    window: int = 0
    window_weigh: str = "window"
    best_by: str = "weight"
    sonar_range_to: str = "entry"
    estimate: str = "best"

    def __post_init__(self):
        for name, choices in _CHOICES.items():
            if getattr(self, name) not in choices:
                raise ValueError(
                    f"{name} must be one of {choices}, got {getattr(self, name)!r}"
                )
        for name in ("inflate", "p_rand", "temperature", "resample_below",
                     "match_degenerate"):  # fmt: skip
            if not float(getattr(self, name)) >= 0.0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)!r}")
        for name in ("beam_step", "match_beam_step"):
            if int(getattr(self, name)) < 1:
                raise ValueError(f"{name} must be at least 1")
        if int(self.window) < 0:
            raise ValueError("window must be >= 0")
        # the kernels take exact types (no recompiling for an int given as 1)
        put = object.__setattr__
        for name in ("inflate", "p_rand", "temperature", "resample_below",
                     "sonar_sigma", "sonar_occ", "sonar_unknown",
                     "match_degenerate", "proposal_sigma"):  # fmt: skip
            put(self, name, float(getattr(self, name)))
        for name in ("beam_step", "match_levels", "match_beam_step", "window"):
            put(self, name, int(getattr(self, name)))
        if not (self.proposal_sigma > 0 and min(self.proposal_floor) > 0):
            raise ValueError("proposal_sigma and proposal_floor must be positive")
        for name in ("match_step", "match_prior", "proposal_floor"):
            a, b = getattr(self, name)
            put(self, name, (float(a), float(b)))
        put(self, "match", bool(self.match))
        if self.sonar_incidence is not None:
            put(self, "sonar_incidence", float(self.sonar_incidence))
        if self.sonar_walls is not None:
            put(self, "sonar_walls", tuple(int(k) for k in self.sonar_walls))


SONAR_SETTINGS = FastSLAMSettings(
    temperature=0.03,
    inflate=1.0,
    resample_below=0.5,
    p_rand=0.2,
    sonar_sigma=0.1,
    sonar_walls=SONAR_WALL_SENSORS,
    best_by="path",
    estimate="mean",
)
"""`robotlib.mapping.run_fastslam`'s settings for the sonar (tuned on the loop
world): eight wide cones tell little per record, so each weighs little; only
the sonars that meet walls near their normal mark walls; an echo's range is
trusted to 0.1 m about the map's; the run reports the posterior mean
trajectory and its map."""

SONAR_PARTICLES = 200
"""Particles the bench gives sonar FastSLAM (see the results file)."""
