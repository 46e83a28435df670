"""Running grid FastSLAM over a recorded drive: `run_fastslam` and its result.

`run_fastslam` builds a `robotlib.mapping.fastslam.GridFastSLAM` on the
drive's world (for the sonar with `SONAR_SETTINGS`), steps it through every
record and scores its trajectory and map against the truth. Imports the
filter and the metrics; never plots.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .fastslam import GridFastSLAM
from .fastslam_settings import SONAR_SETTINGS, FastSLAMSettings
from .metrics import MapScore, map_score, trajectory_rms
from .occupancy import OccupancyGrid

__all__ = ["FastSLAMResult", "run_fastslam"]


@dataclass(frozen=True, eq=False)
class FastSLAMResult:
    """What `run_fastslam` returns.

    Attributes
    ----------
    path : numpy.ndarray, shape (T, 3)
        The trajectory, one row per record: the best particle's lineage, or
        the posterior mean (the filter's ``estimate``).
    map : OccupancyGrid
        The best particle's map, or the map of the mean trajectory.
    rms : float
        Position RMS error of ``path`` against the true poses, m.
    score : MapScore
        ``map`` against the world.
    odometry_rms : float
        The odometry's RMS error on the same log, m.
    filter : GridFastSLAM
        The filter after the run.
    """

    path: np.ndarray
    map: OccupancyGrid
    rms: float
    score: MapScore
    odometry_rms: float
    filter: GridFastSLAM


def run_fastslam(
    log,
    n_particles: int = 30,
    sensor: str = "laser",
    resolution: float | None = None,
    rng=0,
    settings: FastSLAMSettings | None = None,
) -> FastSLAMResult:
    """Run grid FastSLAM over a `robotlib.mapping.drive.DriveLog`.

    Parameters
    ----------
    log : DriveLog
        The drive (its world gives only the grid's cells and the start pose).
    n_particles : int
        Particles.
    sensor : {"laser", "sonar"}
        Which readings to use.
    resolution : float, optional
        Cell side, m (default 0.05 for the laser, 0.1 for the sonar).
    rng : numpy.random.Generator, int or None
        The filter's randomness.
    settings : FastSLAMSettings, optional
        The filter's knobs (default: `FastSLAMSettings()` for the laser,
        `SONAR_SETTINGS` for the sonar, marking walls with every sonar when
        the ring is not a P3-DX's eight).

    Returns
    -------
    FastSLAMResult
    """
    res = (0.05 if sensor == "laser" else 0.1) if resolution is None else resolution
    if settings is None:
        settings = FastSLAMSettings()
        if sensor == "sonar":
            settings = SONAR_SETTINGS
            if len(log.sonar_model.sensors) != 8:
                # (the default names a P3-DX ring's sonars)
                settings = replace(settings, sonar_walls=None)
    f = GridFastSLAM.for_world(
        log.world, res, start=log.odometry[0], n_particles=n_particles,
        sensor=sensor, settings=settings, laser=log.laser_model,
        sonar=log.sonar_model, rng=rng,
    )  # fmt: skip
    scans = log.laser if sensor == "laser" else log.sonar
    for t in range(len(log)):
        f.step(log.odometry[t], scans[t])
    if f.settings.estimate == "mean":
        path, m = f.mean_path()[1:], f.mean_map(scans)
    else:
        path, m = f.best_path()[1:], f.best_map()
    return FastSLAMResult(
        path=path,
        map=m,
        rms=trajectory_rms(path, log.truth),
        score=map_score(m, log.world, res),
        odometry_rms=trajectory_rms(log.odometry, log.truth),
        filter=f,
    )
