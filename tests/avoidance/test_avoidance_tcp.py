"""The same VFH controller, unchanged, reaches a goal through the sim-server."""

from __future__ import annotations

import socket
import subprocess
import sys
import time

import numpy as np

from robotlib import robot
from robotlib.avoidance import VFH, run_episode
from robotlib.pioneer.transport import Timeouts
from robotlib.world import compose, load_world, relative

FAST = Timeouts(
    connect=2.0, sync_reply=0.3, sync_total=3.0, link=1.0, poll=0.01, pulse=0.2,
    config=0.5, close=0.5,
)  # fmt: skip
SPEED = 10.0  # simulated seconds per wall-clock second


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_vfh_reaches_a_goal_over_tcp():
    port = _free_port()
    cmd = [sys.executable, "-m", "robotlib.cli", "sim-server", "--world", "clutter",
           "--port", str(port), "--speed", str(SPEED), "--seed", "0",
           "--duration", "120"]  # fmt: skip
    server = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=0.2).close()
                break
            except OSError:
                assert server.poll() is None, server.stderr.read().decode()
                assert time.monotonic() < deadline, "sim-server did not start"
                time.sleep(0.1)
        r = robot(f"tcp://127.0.0.1:{port}", timeouts=FAST)
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
