"""
A particle cloud converging
===========================

Monte Carlo localization from scratch in the paper's aliased corridor: the
particles start spread over the whole free space; each odometry step moves
them, each sonar scan weighs them, resampling keeps the likely ones. The
library's best filter (a tempered beam model, KLD-sampling) gathers around
the true pose (the robot outline) within about ten steps, and its particle
count falls as the cloud shrinks.
"""

import matplotlib.pyplot as plt

from robotlib import load_world
from robotlib.experiments import drive_route
from robotlib.plotting.mcl import plot_particle_snapshots
from robotlib.widgets.mcl import run_mcl

world = load_world("corridor")
route = drive_route(world, seed=0, n_steps=15)
history = run_mcl(
    route, preset="best (beam + KLD)", seed=0, snapshot_steps=(1, 4, 8, 15)
)
errors = history.arrays()["error"]
print("position error per step (m):", " ".join(f"{e:.2f}" for e in errors))

fig = plt.figure(figsize=(10, 4.5))
plot_particle_snapshots(fig, world, history.snapshots)
plt.show()
