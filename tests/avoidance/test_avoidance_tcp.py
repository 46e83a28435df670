"""The same VFH controller, unchanged, reaches a goal through the sim-server.

The server is the command line's, in lock-step (``--lockstep``): the episode
is the same however busy the machine is, and takes no wall-clock time of
its own.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np

from robotlib import robot
from robotlib.avoidance import VFH, run_episode
from robotlib.pioneer.transport import Timeouts
from robotlib.world import compose, load_world, relative

FAST = Timeouts(
    connect=2.0, sync_reply=0.3, sync_total=3.0, link=5.0, poll=0.01, pulse=0.2,
    config=0.5, close=0.5,
)  # fmt: skip


def _address(server: subprocess.Popen) -> str:
    """The ``tcp://`` address the server logs once it listens (its own free port)."""
    for line in server.stderr:
        if "serving tcp://" in line:
            return line.split("serving ", 1)[1].strip()
    raise AssertionError(f"sim-server exited ({server.wait(10)}) before serving")


def test_vfh_reaches_a_goal_over_tcp():
    cmd = [sys.executable, "-m", "robotlib.cli", "sim-server", "--world", "clutter",
           "--port", "0", "--lockstep", "--seed", "0", "--duration", "300"]  # fmt: skip
    server = subprocess.Popen(
        cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
    )
    try:
        r = robot(_address(server), timeouts=FAST, lockstep=True)
        try:
            start = np.asarray(load_world("clutter").start)
            goal_world = np.array([9.3, 4.5, 0.0])
            # the goal in the robot's odometry frame, from its first pose
            goal = compose(r.pose(), relative(start, goal_world))[:2]
            ep = run_episode(r, VFH(), goal=goal, max_time=60)
        finally:
            r.disconnect()
    finally:
        server.terminate()
        server.wait(10)
    assert ep.truth is None and ep.clearance is None  # a real robot's view
    assert ep.outcome == "reached", (ep.outcome, ep.odometry[-1])
    assert ep.collisions == 0
    assert np.hypot(*(ep.odometry[-1, :2] - goal)) <= 0.3
