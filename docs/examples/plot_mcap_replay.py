"""
Recording a run and replaying it
================================

Any robot can be recorded to an MCAP file with ROS 2 message types (odometry,
sonar, commands, and the simulator's ground truth), then replayed as a robot:
``robot("log:run.mcap")`` answers the same calls from the file, so a
localizer written against the live robot runs unchanged on the recording.
"""

import math
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

from robotlib import robot
from robotlib.logs import read_log, record

path = Path(tempfile.mkdtemp()) / "run.mcap"
r = record(robot("sim:corridor", seed=1), path)
for heading in (0.0, math.pi, 0.0, math.pi):  # up and down the corridor
    r.setheading(heading)
    r.wait_heading_done()
    r.move(3.0)
    r.wait_move_done()
r.disconnect()

run = read_log(path)
size = path.stat().st_size / 1024
print(
    f"{len(run.states)} polls over {run.times[-1]:.1f} s of robot time, {size:.0f} KiB"
)
replay = robot(f"log:{path}")
first = replay.readsonar()
replay.disconnect()
print("the replay's first scan (m):", " ".join(f"{z:.2f}" for z in first))

fig, (ax, bx) = plt.subplots(2, 1, figsize=(8, 5), height_ratios=(1, 1))
ax.plot(*run.true_poses[:, :2].T, "k-", label="true")
start = run.true_poses[0, :2] - run.odometry[0, :2]
ax.plot(*(run.odometry[:, :2] + start).T, "r--", label="odometry")
ax.set(xlabel="x [m]", ylabel="y [m]", title="the recorded poses")
ax.legend()
bx.plot(run.times, run.sonar.min(axis=1))
bx.set(xlabel="robot time [s]", ylabel="nearest sonar [m]")
plt.show()
