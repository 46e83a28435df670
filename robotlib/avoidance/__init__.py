"""Obstacle avoidance on sonar: controllers, the episode runner, the worlds.

A controller has ``reset()`` and ``command(sonar, pose) -> (v, w)`` and sees
only what a real robot sees (eight sonar ranges, the odometry pose, a goal):

- `VFH`: the Vector Field Histogram (certainty grid, polar histogram, valleys),
  with VFH+'s enlarged cells and hysteresis;

`run_episode` drives any `robotlib.robot.Robot` with one until it reaches
its goal, collides, times out or reports a local minimum; `run_episodes`
runs seeded start/goal pairs (`start_goal_pairs`) of the avoidance worlds
(`AVOID_WORLDS`).
"""

from .base import Controller, goal_in_robot_frame, sonar_endpoints
from .episode import OUTCOMES, Episode, run_episode, run_episodes
from .vfh import VFH, choose_direction, polar_histogram, smooth_histogram
from .worlds import AVOID_WORLDS, StartGoal, pair_regions, start_goal_pairs

__all__ = [
    "Controller",
    "VFH",
    "polar_histogram",
    "choose_direction",
    "smooth_histogram",
    "sonar_endpoints",
    "goal_in_robot_frame",
    "Episode",
    "run_episode",
    "run_episodes",
    "OUTCOMES",
    "AVOID_WORLDS",
    "StartGoal",
    "start_goal_pairs",
    "pair_regions",
]
