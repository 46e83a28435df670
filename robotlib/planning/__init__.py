"""Navigation: configuration space, grid and sampling planners, path following.

- `configuration_space` / `CSpace`: an occupancy grid inflated by the robot's
  radius and a cost map that keeps away from walls; `inflate`, `cost_map`.
- Grid planners returning a `Plan` (path in m, cost, nodes expanded):
  `wavefront`, `dijkstra`, `astar`, `weighted_astar` (4- or 8-connected);
  `cost_field`, `wavefront_field` for whole fields.
- Sampling planners against the wall segments: `rrt`, `rrt_star`, `shortcut`.
- Following: `pure_pursuit` (the steering law), `PurePursuit`, the
  `PathFollower` that hands unmapped obstacles to an avoider (`StopAndTurn`
  here, or `robotlib.avoidance`'s controllers), `cross_track`.
- `navigate`: localize with MCL from sonar and odometry, plan with A*,
  follow, avoid, re-plan; returns a `Navigation` record. `GOALS`,
  `office_with_boxes` for its scenarios.
- `Localized`: an avoidance controller aimed by MCL tracking on the map
  instead of by the drifting odometry (no planner).

Planners never plot; `robotlib.plotting` draws what they return.
"""

from .cspace import CSpace, configuration_space, cost_map, inflate
from .follow import PathFollower, PurePursuit, StopAndTurn, cross_track, pure_pursuit
from .grid import (
    Plan,
    astar,
    cost_field,
    dijkstra,
    octile,
    path_length,
    wavefront,
    wavefront_field,
    weighted_astar,
)
from .localized import Localized
from .navigate import Navigation, Navigator, NavSettings, navigate
from .rrt import Tree, edge_free, path_free, rrt, rrt_star, shortcut
from .scenarios import GOALS, OFFICE_BOXES, office_with_boxes, with_boxes

__all__ = [
    "GOALS",
    "OFFICE_BOXES",
    "CSpace",
    "Localized",
    "Navigation",
    "Navigator",
    "NavSettings",
    "PathFollower",
    "PurePursuit",
    "StopAndTurn",
    "cross_track",
    "navigate",
    "office_with_boxes",
    "pure_pursuit",
    "with_boxes",
    "Plan",
    "Tree",
    "astar",
    "configuration_space",
    "cost_field",
    "cost_map",
    "dijkstra",
    "edge_free",
    "inflate",
    "octile",
    "path_free",
    "path_length",
    "rrt",
    "rrt_star",
    "shortcut",
    "wavefront",
    "wavefront_field",
    "weighted_astar",
]
