"""
Avoiding obstacles with VFH
===========================

An episode: the robot drives from a start to a goal through the clutter
world, seeing only its eight sonars and its odometry; VFH builds a certainty
grid from the echoes (orange) and steers through the free valleys of its
polar histogram. The verdict comes from the true pose.
"""

import matplotlib.pyplot as plt

from robotlib import load_world
from robotlib.avoidance import VFH, run_episode, start_goal_pairs
from robotlib.plotting.avoidance import plot_clearance, plot_episode

world = load_world("clutter")
pair = start_goal_pairs(world, n=1, seed=3)[0]
episode = run_episode(world, VFH(), pair.goal, start=pair.start, seed=0)
print(f"{episode.outcome} in {episode.duration:.1f} s")

fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 4), width_ratios=(3, 2))
plot_episode(ax, episode, world)
plot_clearance(bx, episode)
plt.show()
