"""Monte Carlo localization: the paper's filter and the standard alternatives.

Procedural pieces (what a lab asks students to write) are in
`robotlib.localization.paper`; the grid filters before particles
(`HistogramFilter1D`, `GridFilter`) in `robotlib.localization.histogram`.
`MCL` composes a motion model
(`OdometryMotionModel`), a sensor model (`PaperSensorModel`,
`BeamSensorModel`, `LikelihoodFieldSensorModel`) and a resampling policy
(`PaperResampling`, `ThresholdResampling`, `KLDResampling`), optionally with
augmented MCL's `AugmentedInjection`, and reports the weighted mean or
(`mode_estimate`) the heaviest place. `History` records a run from outside.
"""

from . import histogram, paper
from .cones import ConeTable, cone_table, expected_readings
from .estimates import mode_estimate
from .histogram import GridFilter, HistogramFilter1D
from .history import History, localized_step
from .kld import kld_bound, kld_resample
from .mcl import BEST, MCL, StepInfo
from .motion import OdometryMotionModel, odometry_increment, sample_motion_odometry
from .policies import (
    AugmentedInjection,
    KLDResampling,
    PaperResampling,
    ThresholdResampling,
)
from .resampling import (
    RESAMPLERS,
    effective_sample_size,
    multinomial_resample,
    residual_resample,
    stratified_resample,
    systematic_resample,
)
from .sensors import (
    BeamParameters,
    BeamSensorModel,
    LikelihoodFieldSensorModel,
    PaperSensorModel,
    innovation_loglik,
)

__all__ = [
    "BEST",
    "MCL",
    "RESAMPLERS",
    "AugmentedInjection",
    "BeamParameters",
    "BeamSensorModel",
    "ConeTable",
    "GridFilter",
    "HistogramFilter1D",
    "History",
    "KLDResampling",
    "LikelihoodFieldSensorModel",
    "OdometryMotionModel",
    "PaperResampling",
    "PaperSensorModel",
    "StepInfo",
    "ThresholdResampling",
    "cone_table",
    "effective_sample_size",
    "histogram",
    "expected_readings",
    "innovation_loglik",
    "kld_bound",
    "kld_resample",
    "localized_step",
    "mode_estimate",
    "multinomial_resample",
    "odometry_increment",
    "paper",
    "residual_resample",
    "sample_motion_odometry",
    "stratified_resample",
    "systematic_resample",
]
