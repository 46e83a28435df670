"""
The wavefront
=============

The wavefront planner floods the free space from the goal, one move at a
time: each cell learns how many moves it is from the goal. From any start,
stepping to a neighbour one move nearer leads to the goal along a path with
the fewest moves.
"""

import matplotlib.pyplot as plt
import numpy as np

from robotlib import load_world
from robotlib.planning import configuration_space, wavefront, wavefront_field
from robotlib.plotting.planning import plot_cspace, plot_path

office = load_world("office")
cs = configuration_space(office, 0.1)
goal = (17.5, 12.0)
field = wavefront_field(cs, goal)
plan = wavefront(cs, office.start[:2], goal)
print(f"the start is {plan.cost:.1f} m away; the farthest cell {field.max()} moves")

fig, ax = plt.subplots(figsize=(7, 5))
plot_cspace(ax, cs, cost=False, world=office)
shown = np.ma.masked_less(field, 0)
image = ax.imshow(shown, origin="lower", extent=cs.extent, cmap="viridis")
fig.colorbar(image, ax=ax, label="moves to the goal")
plot_path(ax, plan.path, "r-", lw=2)
plt.show()
