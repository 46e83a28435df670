"""Obstacle avoidance on sonar: controllers, the episode runner, the worlds.

A controller has ``reset()`` and ``command(sonar, pose) -> (v, w)`` and sees
only what a real robot sees (eight sonar ranges, the odometry pose, a goal):

- `VFH`: the Vector Field Histogram (certainty grid, polar histogram, valleys),
  with VFH+'s enlarged cells, hysteresis and cost, and a boundary-following
  escape from traps;
- `PotentialField`: attraction to the goal, repulsion from sonar echoes; it
  detects and reports its local minima;
- `Braitenberg` (the vehicles of `BRAITENBERG` as weight matrices) and
  `WallFollower`: reactive, no memory;
- `DWA`: the dynamic window approach (velocity samples within the
  accelerations, rolled out against a short-memory sonar grid, an objective
  of heading, progress, clearance and speed aimed along a navigation
  function over that grid, and a look round when stuck);
- `Bug2`: the m-line and boundary following, on sonar and odometry.

`run_episode` drives any `robotlib.robot.Robot` with one until it reaches
its goal, collides, times out or reports a local minimum; `run_episodes`
runs seeded start/goal pairs (`start_goal_pairs`) of the avoidance worlds
(`AVOID_WORLDS`).
"""

from .base import Controller, goal_in_robot_frame, sonar_endpoints
from .bug2 import Bug2
from .dwa import DWA, choose_velocity, dynamic_window, evaluate_window
from .dwa_settings import DWASettings
from .episode import OUTCOMES, TRUE_TOLERANCE, Episode, run_episode, run_episodes
from .potential import PotentialField, force_field, potential_force
from .reactive import BRAITENBERG, Braitenberg, WallFollower, sonar_activation
from .vfh import VFH, choose_direction, polar_histogram, smooth_histogram
from .vfh_settings import VFHSettings
from .worlds import AVOID_WORLDS, StartGoal, pair_regions, start_goal_pairs

__all__ = [
    "Controller",
    "VFH",
    "VFHSettings",
    "DWA",
    "DWASettings",
    "dynamic_window",
    "evaluate_window",
    "choose_velocity",
    "polar_histogram",
    "choose_direction",
    "smooth_histogram",
    "PotentialField",
    "potential_force",
    "force_field",
    "Braitenberg",
    "BRAITENBERG",
    "WallFollower",
    "sonar_activation",
    "Bug2",
    "CONTROLLERS",
    "sonar_endpoints",
    "goal_in_robot_frame",
    "Episode",
    "run_episode",
    "run_episodes",
    "OUTCOMES",
    "TRUE_TOLERANCE",
    "AVOID_WORLDS",
    "StartGoal",
    "start_goal_pairs",
    "pair_regions",
]

CONTROLLERS = {
    "VFH": VFH,
    "DWA": DWA,
    "potential field": PotentialField,
    "Bug2": Bug2,
    "Braitenberg": Braitenberg,
    "wall follower": WallFollower,
}
"""The controllers by name (classes; build with default settings)."""
