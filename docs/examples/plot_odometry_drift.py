"""
Odometry drifts from the truth
==============================

The robot integrates its wheel encoders into an odometry pose; slip and
uneven wheels make it drift from where the robot really is. The simulator
knows the truth, so the drift can be measured: here over four laps of a
1.5 m square in the arena, for five seeds.
"""

import math

import matplotlib.pyplot as plt
import numpy as np

from robotlib import disconnect, robot

fig, ax = plt.subplots(figsize=(7, 3.5))
for seed in range(5):
    r = robot("sim:arena", seed=seed)
    r.body.set_true_pose((2.0, 4.5, 0.0))
    r.body.reset_odometry()  # odometry (0, 0, 0) here: truth - (2, 4.5, 0)
    distance, errors = [0.0], [0.0]
    for k in range(16):
        r.move(1.5)
        r.wait_move_done()
        r.setheading(math.remainder((k + 1) * math.pi / 2, 2 * math.pi))
        r.wait_heading_done()
        distance.append(distance[-1] + 1.5)
        errors.append(float(np.hypot(*(r.pose()[:2] + (2.0, 4.5) - r.true_pose()[:2]))))
    disconnect(r)
    ax.plot(distance, errors, ".-", label=f"seed {seed}")
ax.set(xlabel="distance driven [m]", ylabel="odometry position error [m]")
ax.legend()
plt.show()
