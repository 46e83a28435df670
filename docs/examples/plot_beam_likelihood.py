"""
One scan's likelihood over the corridor
=======================================

The beam model scores a sonar scan against the ranges expected from a pose.
Scored from every position of the corridor (at the robot's true heading),
one scan is about as likely in several places: the corridor is aliased, its
doors repeat, and that is why localization needs more than one scan.
"""

import matplotlib.pyplot as plt
import numpy as np

from robotlib import readsonar, robot
from robotlib.localization import BeamSensorModel
from robotlib.plotting.world import plot_world

r = robot("sim:corridor", seed=2)
r.move(4.0)
r.wait_move_done()
z, truth = readsonar(r), r.true_pose()
world = r.simulator.world
r.disconnect()

xs = np.arange(0.5, world.size[0] - 0.5, 0.1)
ys = np.arange(2.6, 5.4, 0.1)
gx, gy = np.meshgrid(xs, ys)
poses = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, truth[2])])
loglik = BeamSensorModel(world).log_likelihood(poses, z).reshape(gx.shape)

fig, ax = plt.subplots(figsize=(10, 3.2))
image = ax.imshow(
    loglik - loglik.max(),
    origin="lower",
    extent=(xs[0], xs[-1], ys[0], ys[-1]),
    vmin=-40,
    cmap="magma",
)
plot_world(ax, world)
ax.plot(*truth[:2], "c+", ms=12, mew=2, label="true position")
ax.set_ylim(1.5, 6.5)
ax.legend(loc="upper right")
fig.colorbar(image, ax=ax, label="log-likelihood - max")
best = poses[np.argmax(loglik)]
print(f"true position {truth[:2].round(2)}, most likely {best[:2].round(2)}")
plt.show()
