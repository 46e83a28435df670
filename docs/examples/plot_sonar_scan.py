"""
A sonar scan
============

The robot stands in the paper's aliased corridor and reads its eight sonars
once. Each reading is a range in metres along the centre of a 30 degree cone;
5 m means no echo.
"""

import matplotlib.pyplot as plt

from robotlib import disconnect, readsonar, robot
from robotlib.plotting.world import plot_robot, plot_sonar, plot_world

r = robot("sim:corridor", seed=2)
z = readsonar(r)
pose = r.true_pose()
print("ranges (m):", z.round(2))

fig, ax = plt.subplots(figsize=(8, 3))
plot_world(ax, r.simulator.world)
plot_sonar(ax, pose, z)
plot_robot(ax, pose)
ax.set_xlim(pose[0] - 4, pose[0] + 4)
disconnect(r)
plt.show()
