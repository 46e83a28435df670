"""
A FastSLAM map
==============

Grid FastSLAM: each particle is a guess of the whole trajectory and carries
its own occupancy map; a laser scan weighs each particle by how well it fits
that particle's map, and resampling keeps the maps that agree with the
readings. The best particle's map is much sharper than the map drawn from
odometry alone.
"""

import matplotlib.pyplot as plt

from robotlib import load_world
from robotlib.mapping import map_laser, map_score, record_drive, run_fastslam
from robotlib.plotting.mapping import plot_logodds

world = load_world("loop")
log = record_drive(world, [(19.5, 1.5), (19.5, 14.5)], seed=23, every=4)
slam = run_fastslam(log, 20, "laser", rng=0)
odometry_map = map_laser(world, log.odometry, log.laser, resolution=0.05)

fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
plot_logodds(axes[0], odometry_map)
axes[0].plot(*log.odometry[:, :2].T, "r-", lw=1)
axes[0].set_title(f"odometry: F1 {map_score(odometry_map, world, 0.05).f1:.2f}")
plot_logodds(axes[1], slam.map)
axes[1].plot(*slam.path[:, :2].T, "r-", lw=1)
axes[1].set_title(f"FastSLAM, 20 particles: F1 {slam.score.f1:.2f}")
print(f"trajectory RMS: odometry {slam.odometry_rms:.2f} m, FastSLAM {slam.rms:.2f} m")
plt.show()
