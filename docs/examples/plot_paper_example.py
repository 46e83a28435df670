"""
The paper's example
===================

Frontoni et al.'s first program: move 0.5 m, turn around, ten times, busy
waiting on ``ismovedone`` and ``isheadingdone``. In the simulator each poll
is one 100 ms robot cycle, so the loop takes milliseconds. Odometry (what
the robot believes) and the truth part ways.
"""

import math

import matplotlib.pyplot as plt
import numpy as np

from robotlib import (
    disconnect,
    isheadingdone,
    ismovedone,
    move,
    pose,
    robot,
    setdeltaheading,
)

r = robot("sim:corridor", seed=1)
odometry, truth = [pose(r)], [r.true_pose()]
for _ in range(10):
    move(r, 0.5)
    while not ismovedone(r):
        pass
    setdeltaheading(r, math.pi)
    while not isheadingdone(r):
        pass
    odometry.append(pose(r))
    truth.append(r.true_pose())
disconnect(r)
odometry, truth = np.array(odometry), np.array(truth)
odometry[:, :2] += truth[0, :2] - odometry[0, :2]  # the same origin

fig, ax = plt.subplots(figsize=(6, 3))
ax.plot(truth[:, 0], truth[:, 1], "k.-", label="true")
ax.plot(odometry[:, 0], odometry[:, 1], "r.--", label="odometry")
ax.set(xlabel="x [m]", ylabel="y [m]", aspect="equal")
ax.legend()
print("end: odometry", odometry[-1].round(3), "truth", truth[-1].round(3))
plt.show()
