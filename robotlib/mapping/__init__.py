"""Mapping and SLAM: occupancy grids, map metrics, FastSLAM, EKF-SLAM, graph SLAM.

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
from .graphslam import GraphSLAMResult, GraphSLAMSettings, graph_slam
from .icp import ICPResult, icp, scan_to_points
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
from .posegraph import PoseGraph, optimize, prune_loops
from .relations import read_relations, relation_errors
from .sharing import MapDiff

__all__ = [
    "graph_slam",
    "GraphSLAMSettings",
    "GraphSLAMResult",
    "icp",
    "ICPResult",
    "scan_to_points",
    "PoseGraph",
    "optimize",
    "prune_loops",
    "read_relations",
    "relation_errors",
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
