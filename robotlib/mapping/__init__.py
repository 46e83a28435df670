"""Mapping and SLAM: occupancy grids (sonar, laser), map metrics, FastSLAM, EKF-SLAM.

Estimators here never plot: drawing lives in `robotlib.plotting`.
"""

from .drive import ROUTES, DriveLog, perturbed_route, record_drive
from .metrics import MapScore, dilate, heading_rms, map_score, trajectory_rms
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

__all__ = [
    "ROUTES",
    "DriveLog",
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
