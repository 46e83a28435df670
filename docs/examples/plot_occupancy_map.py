"""
An occupancy grid from sonar
============================

Mapping with known poses: each sonar reading marks its cone free up to the
echo and the arc at the echo occupied (the inverse sonar model), adding
log-odds cell by cell. With the true poses the office appears; with the
odometry's poses the same readings smear as the odometry drifts.
"""

import matplotlib.pyplot as plt

from robotlib import load_world
from robotlib.mapping import map_score, map_sonar, record_drive
from robotlib.plotting.mapping import plot_logodds

office = load_world("office")
log = record_drive(office, seed=0, every=4, laser=False)
fig, axes = plt.subplots(1, 2, figsize=(11, 4))
runs = ((log.truth, "true poses"), (log.odometry, "odometry"))
for ax, (poses, title) in zip(axes, runs, strict=True):
    grid = map_sonar(office, poses, log.sonar, resolution=0.1)
    plot_logodds(ax, grid)
    ax.set_title(f"{title}: F1 {map_score(grid, office, 0.1).f1:.2f}")
print(len(log), "scans over", round(float(log.time[-1])), "s of driving")
plt.show()
