"""The fault-injecting link: packets delayed in order, SIPs dropped, sessions work."""

import time

import numpy as np

from robotlib import robot
from robotlib.pioneer.faults import FaultyLink
from robotlib.pioneer.server import SimServer


def _poll_gaps(address, n=12):
    r = robot(address, timeout=5.0)
    try:
        r.pose()
        t = []
        for _ in range(n):
            r.pose()
            t.append(time.monotonic())
        return np.diff(t), r
    finally:
        r.disconnect()


def test_a_clean_link_passes_everything_and_a_lossy_one_drops_sips():
    with SimServer("corridor", port=0, seed=0, speed=4.0) as server:
        with FaultyLink(server.ports[0]) as clean:
            gaps, _ = _poll_gaps(clean.address)
            assert clean.dropped == 0 and clean.forwarded > 10
        with FaultyLink(server.ports[0], loss=0.5, seed=1) as lossy:
            lossy_gaps, _ = _poll_gaps(lossy.address)
            assert lossy.dropped > 3
    # a lost SIP makes the next poll wait a cycle longer (25 ms at 4x)
    assert np.median(gaps) < 0.04 and lossy_gaps.mean() > gaps.mean()


def test_delay_holds_every_packet_and_keeps_commands_working():
    with SimServer("corridor", port=0, seed=0, speed=4.0) as server:
        with FaultyLink(server.ports[0], delay=0.08, jitter=0.02, seed=2) as link:
            r = robot(link.address, timeout=5.0)
            try:
                x0 = r.pose()[0]
                t0 = time.monotonic()
                r.setvel(0.3)
                while abs(r.state.velocity[0]) < 1e-3 and time.monotonic() - t0 < 3:
                    r.pose()
                latency = time.monotonic() - t0
                for _ in range(20):
                    r.pose()
                assert r.pose()[0] > x0 + 0.05
            finally:
                r.disconnect()
    assert 0.16 <= latency < 2.0  # the command's way there and the SIP's way back
