"""
RRT
===

A rapidly-exploring random tree grows from the start towards random samples
(and now and then towards the goal), one step of 0.5 m at a time, never
through a wall. The first branch to reach the goal is the path: found fast,
far from the shortest.
"""

import matplotlib.pyplot as plt

from robotlib import load_world
from robotlib.planning import path_length, rrt, shortcut
from robotlib.plotting.planning import plot_path, plot_tree
from robotlib.plotting.world import plot_world

office = load_world("office")
tree = rrt(office, office.start[:2], (17.5, 12.0), rng=0)
short = shortcut(office, tree.path, rng=0)
print(f"{tree.expanded} vertices, {tree.iterations} samples")

fig, ax = plt.subplots(figsize=(7, 5))
plot_world(ax, office)
plot_tree(ax, tree)
plot_path(ax, short, "g-", lw=2, label=f"shortcut: {path_length(short):.1f} m")
ax.set_title(f"RRT path: {tree.cost:.1f} m")
ax.legend(loc="lower right")
plt.show()
