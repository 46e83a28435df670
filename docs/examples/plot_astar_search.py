"""
An A* search
============

A* on the office's configuration space (the map's grid, inflated by the
robot's radius so that the robot can be planned as a point). The cells are
coloured in the order A* expanded them: the octile heuristic pulls the search
towards the goal, so it expands far fewer cells than Dijkstra's search would.
"""

import matplotlib.pyplot as plt

from robotlib import load_world
from robotlib.planning import astar, configuration_space, dijkstra
from robotlib.plotting.planning import plot_cspace, plot_expansion, plot_path

office = load_world("office")
cs = configuration_space(office, 0.1)
start, goal = office.start[:2], (17.5, 12.0)
plan = astar(cs, start, goal, record=True)
print(
    f"A*: {plan.cost:.1f} m, {plan.expanded} cells expanded; "
    f"Dijkstra: {dijkstra(cs, start, goal).expanded}"
)

fig, ax = plt.subplots(figsize=(7, 5))
plot_cspace(ax, cs, cost=False, world=office)
plot_expansion(ax, cs, plan.order)
plot_path(ax, plan.path, "r-", lw=2, label="A* path")
ax.legend(loc="lower right")
plt.show()
