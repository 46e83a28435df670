"""PioneerRobot over an in-memory link to a simulated robot: handshake, faults."""

import math
import random
import threading
import time

import numpy as np
import pytest

from robotlib.pioneer.client import LinkTimeout, PioneerRobot, SyncError
from robotlib.pioneer.packets import PacketDecoder, frame
from robotlib.pioneer.server import Session
from robotlib.pioneer.transport import (
    LinkClosed,
    SerialTransport,
    Timeouts,
    memory_pair,
    open_transport,
)
from robotlib.sim import Simulator
from robotlib.world import load_world

FAST = Timeouts(
    connect=1.0, sync_reply=0.2, sync_total=1.5, link=0.4, poll=0.01, pulse=0.1,
    config=0.5, close=0.5,
)  # fmt: skip


class FakeRobot(threading.Thread):
    """A simulated robot behind a Session on one end of an in-memory link."""

    def __init__(self, end, period=0.005, open_already=False, **session):
        super().__init__(daemon=True)
        self.end = end
        self.sim = Simulator(load_world("corridor"), seed=1)
        self.body = self.sim.add_robot()
        self.sim.step()  # compile the simulator's kernels before timing starts
        self.session = Session(self.sim, self.body, **session)
        if open_already:
            self.session.open = True
        self.period = period
        self.halt = threading.Event()
        self.silent = False
        self.noise = None  # callable -> bytes sent before each SIP
        self.seen = []  # ids of the packets received, in order
        self._dec = PacketDecoder()

    def run(self):
        next_tick = time.monotonic()
        while not self.halt.is_set():
            try:
                data = self.end.read(0.002)
            except LinkClosed:
                return
            try:
                if data:
                    self.seen += [p.id for p in self._dec.feed(data)]
                    reply = self.session.receive(data)
                    if reply:
                        self.end.write(reply)
                if time.monotonic() >= next_tick and not self.silent:
                    next_tick += self.period
                    sip = self.session.tick()
                    if sip:
                        self.sim.step()
                        self.end.write((self.noise() if self.noise else b"") + sip)
            except LinkClosed:
                return

    def stop(self):
        self.halt.set()
        self.join(2)


@pytest.fixture
def link():
    a, b = memory_pair()
    robots = []

    def make(**kw):
        fake = FakeRobot(b, **kw)
        fake.start()
        robots.append(fake)
        return fake

    yield a, make
    for fake in robots:
        fake.stop()
    a.close()


def test_connect_handshake_then_open_config_enable_sonar(link):
    end, make = link
    fake = make()
    r = PioneerRobot(end, timeouts=FAST)
    try:
        assert (r.name, r.robot_class, r.subclass) == ("robotlib", "Pioneer", "p3dx")
        assert r.factors.dist == 0.485
        assert r.config is not None and r.config["serial"] == "SIM"
        assert fake.seen[:3] == [0, 1, 2]
        assert fake.seen[3:7] == [1, 18, 4, 28]  # OPEN, CONFIG, ENABLE, SONAR
        st = r.state
        np.testing.assert_allclose(st.pose, fake.body.state.pose, atol=0.001)
        assert st.sonar.shape == (8,) and st.motors_enabled
        t0 = r.state.time
        r.pose()
        assert r.state.time > t0  # each poll waits for the next SIP
    finally:
        r.disconnect()
    tail = [i for i in fake.seen if i != 0][-2:]
    assert tail == [4, 2]  # ENABLE 0, then CLOSE


def test_move_and_heading_done_as_aria(link):
    end, make = link
    make()
    with PioneerRobot(end, timeouts=FAST) as r:
        x0 = r.pose()[0]
        r.move(0.3)
        r.wait_move_done(timeout=20)
        assert abs(r.pose()[0] - x0 - 0.3) < 0.06
        r.setdeltaheading(math.pi / 2)
        r.wait_heading_done(timeout=20)
        assert abs(math.remainder(r.pose()[2] - math.pi / 2, 2 * math.pi)) < 0.06


def test_sip_during_sync_closes_the_old_connection(link):
    end, make = link
    fake = make(open_already=True)  # the robot is still sending SIPs
    r = PioneerRobot(end, timeouts=FAST)
    r.disconnect()
    assert 2 in fake.seen[: fake.seen.index(1)]  # CLOSE before the new SYNC1


def test_garbage_and_bad_packets_between_sips_are_skipped(link):
    end, make = link
    fake = make()
    rng = random.Random(3)

    def noise():
        bad = bytearray(frame(0x32, bytes(rng.randrange(256) for _ in range(30))))
        bad[-1] ^= 0x01
        cut = frame(0x32, b"\x01" * 40)[: rng.randrange(3, 20)]
        junk = bytes(rng.randrange(256) for _ in range(rng.randrange(20)))
        return junk + bytes(bad) + cut

    fake.noise = noise
    with PioneerRobot(end, timeouts=FAST) as r:
        for _ in range(30):
            z = r.readsonar()
            assert z.shape == (8,) and np.all((z >= 0.1) & (z <= 5.0))


def test_silent_robot_raises_within_the_link_timeout(link):
    end, make = link
    fake = make()
    r = PioneerRobot(end, timeouts=FAST)
    try:
        r.pose()
        fake.silent = True
        t0 = time.monotonic()
        with pytest.raises(LinkTimeout, match="dead"):
            for _ in range(1000):
                r.pose()
        assert time.monotonic() - t0 < 10 * FAST.link  # bounded, not a hang
        with pytest.raises(ConnectionError):  # and it stays raised
            r.readsonar()
    finally:
        r.disconnect()


def test_closed_link_raises_connection_error(link):
    end, make = link
    fake = make()
    r = PioneerRobot(end, timeouts=FAST)
    fake.end.close()
    with pytest.raises(ConnectionError):
        for _ in range(1000):
            r.pose()
    r.disconnect()  # safe after the link died


def test_no_robot_there_fails_the_handshake():
    a, b = memory_pair()  # nobody answers on b
    t0 = time.monotonic()
    with pytest.raises(SyncError, match="SYNC"):
        PioneerRobot(a, timeouts=FAST)
    assert time.monotonic() - t0 < 5 * FAST.sync_total
    b.close()


def test_pulse_keeps_an_idle_link_alive(link):
    end, make = link
    fake = make()
    with PioneerRobot(end, timeouts=FAST) as r:
        n = len(fake.seen)
        time.sleep(4 * FAST.pulse)
        assert fake.seen[n:].count(0) >= 2
        assert r.pose().shape == (3,)


def test_reader_errors_are_raised_on_the_next_poll(link):
    end, make = link
    make()
    r = PioneerRobot(end, timeouts=FAST)

    def broken(timeout):
        raise RuntimeError("driver bug")

    r.transport.read = broken
    with pytest.raises(RuntimeError, match="driver bug"):
        for _ in range(100):
            r.pose()
    r.disconnect()


def test_extra_commands_reach_the_robot(link):
    end, make = link
    fake = make()
    with PioneerRobot(end, timeouts=FAST) as r:
        r.sonar_on(False)
        r.pose()
        r.pose()
        assert np.all(r.readsonar() == 5.0)
        assert not r.state.extra["sonar_enabled"]
        r.sonar_on(True)
        r.sim_set_pose(3.0, 4.0, 0.0)
        r.pose()
        np.testing.assert_allclose(fake.body.true_pose, [3.0, 4.0, 0.0], atol=1e-9)
        r.reset_odometry()
        r.pose()
        np.testing.assert_allclose(r.pose(), 0.0, atol=0.002)
        r.vel2(0.1, 0.1)
        for _ in range(20):
            r.pose()
        assert r.state.velocity[0] == pytest.approx(0.1, abs=0.01)
        r.enable_motors(False)
        r.pose()
        r.pose()
        assert not r.state.motors_enabled


def test_open_transport_addresses():
    loop = open_transport("serial:loop://", FAST)
    try:
        assert isinstance(loop, SerialTransport)
        loop.write(b"abc")
        assert loop.read(0.5) == b"abc"
        assert loop.read(0.01) == b""
    finally:
        loop.close()
    with pytest.raises(ConnectionError):
        open_transport("tcp://127.0.0.1:1", FAST)  # nothing listens on port 1
    with pytest.raises(ConnectionError):
        open_transport("serial:///dev/does-not-exist", FAST)
    with pytest.raises(ValueError):
        open_transport("udp://x", FAST)
