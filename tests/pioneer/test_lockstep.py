"""The sim-server in lock-step: the client's pace does not change the run."""

import random
import threading
import time

import numpy as np
import pytest

from robotlib import robot
from robotlib.cli import main as cli_main
from robotlib.p3dx import CYCLE
from robotlib.pioneer.commands import Command, command, encode_si
from robotlib.pioneer.server import SimServer
from robotlib.pioneer.transport import Timeouts

FAST = Timeouts(
    connect=2.0, sync_reply=0.3, sync_total=3.0, link=5.0, poll=0.01, pulse=0.2,
    config=0.5, close=0.5,
)  # fmt: skip


def drive(address, pause=None):
    """A fixed programme of commands and polls; ``pause()`` s between each."""
    wait = pause or (lambda: 0.0)
    r = robot(address, timeouts=FAST, lockstep=True)
    seen = []
    try:
        for k in range(30):
            r.setvel(0.4 if k < 20 else 0.0)
            time.sleep(wait())  # a busy client: VEL and RVEL far apart
            r.setrotvel(0.3 if k % 10 < 5 else -0.3)
            time.sleep(wait())
            r.readsonar()
            st = r.state
            seen.append(np.concatenate([st.pose, st.sonar, [st.time]]))
    finally:
        r.disconnect()
    return np.array(seen)


def test_a_slow_client_sees_exactly_the_run_of_a_fast_one():
    runs = []
    pace = random.Random(0)
    for pause in (None, lambda: pace.uniform(0.0, 0.03)):
        with SimServer("corridor", port=0, lockstep=True, seed=0) as srv:
            runs.append(drive(srv.addresses[0], pause))
            truth = srv.sim.bodies[0].true_pose
        runs.append(truth)
    fast, fast_truth, slow, slow_truth = runs
    np.testing.assert_array_equal(fast, slow)
    np.testing.assert_array_equal(fast_truth, slow_truth)
    assert np.ptp(fast[:, 0]) > 0.5  # it did drive
    # one poll is one cycle: 30 polls after the connection's first one
    np.testing.assert_allclose(np.diff(fast[:, -1]), CYCLE)


def test_the_server_steps_only_when_asked():
    with SimServer("corridor", port=0, lockstep=True, speed=50.0, seed=0) as srv:
        r = robot(srv.addresses[0], timeouts=FAST, lockstep=True)
        try:
            r.setvel(0.5)
            t0, seen = srv.sim.time, r.latest.time
            time.sleep(0.3)  # 150 cycles at this speed, were it free-running
            assert srv.sim.time == t0 and r.latest.time == seen  # no step, no SIP
            r.pose()
            assert srv.sim.time == pytest.approx(t0 + CYCLE)
        finally:
            r.disconnect()


def test_two_clients_in_lock_step_wait_for_each_other():
    with SimServer("corridor", robots=2, port=0, lockstep=True, seed=0) as srv:
        a, b = (robot(addr, timeouts=FAST, lockstep=True) for addr in srv.addresses)
        try:
            t0 = srv.sim.time
            polled = threading.Thread(target=a.pose, daemon=True)
            polled.start()
            polled.join(0.3)
            assert polled.is_alive() and srv.sim.time == t0  # a waits for b
            b.pose()
            polled.join(FAST.link)
            assert not polled.is_alive()
            assert srv.sim.time == pytest.approx(t0 + CYCLE)
        finally:
            a.disconnect()
            b.disconnect()


def test_a_free_running_server_ignores_sim_step():
    with SimServer("corridor", port=0, speed=20.0, seed=0) as srv:
        r = robot(srv.addresses[0], timeouts=FAST, lockstep=True)
        try:
            before = r.state.time
            for _ in range(3):
                r.pose()  # each still waits for the next SIP
            assert r.state.time > before
        finally:
            r.disconnect()
    assert command(Command.SIM_STEP) == encode_si("SIM_STEP")


def test_cli_serves_in_lock_step():
    args = ["sim-server", "--port", "0", "--lockstep", "--duration", "0.2"]
    assert cli_main(args) == 0
