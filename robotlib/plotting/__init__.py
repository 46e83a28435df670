"""Matplotlib drawing, one module per topic, each function on the ``ax`` it is given.

- `world` (re-exported here): worlds, robots, sonar cones, trajectories,
  particles, grids, `animate`
- `mcl`: the paper's Figs. 2-4 from a `robotlib.localization.History`

Topic modules are imported by path (``from robotlib.plotting.mcl import
plot_error``). Plotting sits on top of the estimators and never computes
robotics; estimators, controllers and planners never import it.
"""

from .world import (
    animate,
    plot_grid,
    plot_particles,
    plot_robot,
    plot_sonar,
    plot_trajectory,
    plot_world,
)

__all__ = [
    "animate",
    "plot_grid",
    "plot_particles",
    "plot_robot",
    "plot_sonar",
    "plot_trajectory",
    "plot_world",
]
