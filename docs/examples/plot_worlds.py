"""
The shipped worlds
==================

Worlds are wall segments in metres, read from ActivMedia ``.wld`` or
MobileSim ``.map`` files. ``load_world(name)`` finds a shipped one by name;
the robot's start pose is part of the world.
"""

import math

import matplotlib.pyplot as plt

import robotlib
from robotlib.plotting.world import plot_robot, plot_world

names = ["corridor", "office", "maze", "clutter", "utrap", "loop"]
cols = 3
fig, axes = plt.subplots(math.ceil(len(names) / cols), cols, figsize=(10, 6))
for ax, name in zip(axes.flat, names, strict=True):
    world = robotlib.load_world(name)
    plot_world(ax, world)
    plot_robot(ax, world.start)
    ax.set_title(f"{name}: {world.size[0]:.0f} m x {world.size[1]:.0f} m")
print("shipped:", ", ".join(robotlib.world_names()))
plt.show()
