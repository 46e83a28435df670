"""Mapping and SLAM: occupancy grids (sonar, laser), map metrics, FastSLAM, EKF-SLAM.

Estimators here never plot: drawing lives in `robotlib.plotting`.
"""

from .drive import ROUTES, DriveLog, perturbed_route, record_drive
from .fastslam import (
    GridFastSLAM,
    normalise_log_weights,
    resample_maps,
    resample_parents,
)
from .fastslam_run import FastSLAMResult, run_fastslam
from .fastslam_settings import SONAR_SETTINGS, FastSLAMSettings
from .metrics import MapScore, dilate, heading_rms, map_score, trajectory_rms
from .motion import apply_arc, arc_increment, arc_noise_cov, sample_arc_motion
from .occupancy import (
    InverseLaserModel,
    InverseSonarModel,
    OccupancyGrid,
    inverse_sonar_model,
    log_odds,
    map_laser,
    map_sonar,
    probability,
)
from .sharing import MapDiff

__all__ = [
    "ROUTES",
    "DriveLog",
    "FastSLAMResult",
    "FastSLAMSettings",
    "SONAR_SETTINGS",
    "GridFastSLAM",
    "apply_arc",
    "arc_increment",
    "arc_noise_cov",
    "normalise_log_weights",
    "resample_maps",
    "resample_parents",
    "MapDiff",
    "run_fastslam",
    "sample_arc_motion",
    "InverseLaserModel",
    "InverseSonarModel",
    "MapScore",
    "OccupancyGrid",
    "dilate",
    "heading_rms",
    "inverse_sonar_model",
    "log_odds",
    "map_laser",
    "map_score",
    "map_sonar",
    "perturbed_route",
    "probability",
    "record_drive",
    "trajectory_rms",
]
