"""
VFH's polar histogram
=====================

The Vector Field Histogram turns the obstacles near the robot into a polar
histogram: each obstacle cell adds to the sectors it covers (enlarged by the
robot's radius), more when it is near. Sectors under the threshold are free;
VFH steers into the free valley nearest to the goal's direction. Here the
obstacles are the cells of the clutter world's occupancy grid (10 cm) that
walls cross, as a certainty grid built from sonar would mark them.
"""

import math

import matplotlib.pyplot as plt
import numpy as np

from robotlib import load_world
from robotlib.avoidance import choose_direction, polar_histogram, smooth_histogram
from robotlib.plotting.avoidance import plot_polar_histogram
from robotlib.plotting.world import plot_robot, plot_world

world = load_world("clutter")
pose = np.array([4.4, 4.4, 0.0])
goal = np.array([9.0, 4.5])
grid = world.occupancy_grid(0.1)
points = grid.centres()[grid.data > 0]
hist = smooth_histogram(polar_histogram(points, np.ones(len(points)), pose))
threshold = 0.5 * hist.max()
target = math.atan2(*(goal - pose[:2])[::-1]) - pose[2]
steer = choose_direction(hist, threshold, target)
print(f"goal at {math.degrees(target):.0f} deg, steer {math.degrees(steer):.0f} deg")

fig = plt.figure(figsize=(10, 4))
ax = fig.add_subplot(1, 2, 1)
plot_world(ax, world)
plot_robot(ax, pose)
ax.plot(*goal, "r*", ms=12)
ahead = pose[:2] + 1.5 * np.array([math.cos(steer), math.sin(steer)])
ax.plot(*np.transpose([pose[:2], ahead]), "b-", lw=2, label="steer")
ax.legend(loc="lower right")
polar = fig.add_subplot(1, 2, 2, projection="polar")
plot_polar_histogram(polar, hist, threshold=threshold, steer=steer, target=target)
plt.show()
