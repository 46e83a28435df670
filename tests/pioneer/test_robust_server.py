"""The sim-server's open door: silent sockets, a class connecting at once,
per-session state, Ctrl-C, bad addresses, hostile packet streams (bounded)."""

import math
import os
import signal
import socket
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robotlib import robot
from robotlib.pioneer.client import SyncError
from robotlib.pioneer.commands import Command, command, encode_si
from robotlib.pioneer.packets import PacketDecoder, frame
from robotlib.pioneer.server import Session, SimServer
from robotlib.pioneer.transport import Timeouts, open_transport
from robotlib.sim import Simulator
from robotlib.world import World, load_world

FAST = Timeouts(
    connect=2.0, sync_reply=0.3, sync_total=3.0, link=1.0, poll=0.01, pulse=0.2,
    config=0.5, close=0.5,
)  # fmt: skip
ROOM = World(
    [[0, 0, 30, 0], [30, 0, 30, 30], [30, 30, 0, 30], [0, 30, 0, 0]],
    start=(20, 12, 0.5),  # far beyond the SIP's +-7.9 m: odometry starts at 0
)


@pytest.fixture
def server():
    with SimServer(ROOM, port=0, speed=20.0, seed=0, handshake_timeout=1.0) as srv:
        yield srv


def handshake(sock, timeout=2.0):
    """SYNC0-2 over a raw socket; returns the packets received."""
    dec = PacketDecoder()
    got = []
    sock.settimeout(timeout)
    for i in (0, 1, 2):
        sock.sendall(command(i))
        deadline = time.monotonic() + timeout
        while len(got) <= i and time.monotonic() < deadline:
            data = sock.recv(4096)
            if not data:
                return got
            got += dec.feed(data)
    return got


def test_silent_and_slow_sockets_do_not_lock_the_port(server):
    port = server.ports[0]
    idle = socket.create_connection(("127.0.0.1", port))
    half = socket.create_connection(("127.0.0.1", port))
    assert len(handshake(half)) == 3  # SYNC without OPEN
    slow = socket.create_connection(("127.0.0.1", port))
    slow.sendall(command(0)[:1])  # one byte, then (a byte a second) nothing more
    try:
        # a normal client is served at once, while all three hang on
        t0 = time.monotonic()
        r = robot(server.addresses[0], timeouts=FAST)
        assert time.monotonic() - t0 < 2.0
        r.move(0.2)
        r.wait_move_done(10)
        r.disconnect()
        # and the stuck ones are closed within the handshake timeout
        for s in (idle, half, slow):
            s.settimeout(3.0)
            for _ in range(4):
                try:
                    if s.recv(4096) == b"":
                        break
                except ConnectionResetError:
                    break
                slow.sendall(b"\xfb")
            else:
                pytest.fail("a socket that never opened was not closed")
    finally:
        for s in (idle, half, slow):
            s.close()
    assert server.error is None


def test_fifty_simultaneous_connections_are_served_or_refused(server):
    port = server.ports[0]
    outcome = [None] * 50
    go = threading.Event()

    def client(k):
        go.wait()
        t0 = time.monotonic()
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
                if len(handshake(s, timeout=4.0)) < 3:
                    outcome[k] = ("refused", time.monotonic() - t0)
                    return
                s.sendall(command(Command.OPEN, 1))
                dec = PacketDecoder()
                s.settimeout(5.0 - (time.monotonic() - t0))
                while True:
                    data = s.recv(4096)
                    if not data:
                        outcome[k] = ("refused", time.monotonic() - t0)
                        return
                    if any(p.id & 0xF0 == 0x30 for p in dec.feed(data)):  # a SIP
                        outcome[k] = ("served", time.monotonic() - t0)
                        s.sendall(command(Command.CLOSE))
                        return
        except (ConnectionError, TimeoutError, OSError) as exc:
            outcome[k] = ("error", repr(exc))

    threads = [threading.Thread(target=client, args=(k,)) for k in range(50)]
    for t in threads:
        t.start()
    go.set()
    for t in threads:
        t.join(10)
    kinds = [o[0] if o else "hung" for o in outcome]
    assert "hung" not in kinds and "error" not in kinds, outcome
    assert kinds.count("served") >= 1
    assert max(o[1] for o in outcome) < 5.0
    # and the robot is free again afterwards
    r = robot(server.addresses[0], timeouts=FAST)
    r.disconnect()


def test_a_second_live_client_is_refused_not_left_hanging(server):
    a = robot(server.addresses[0], timeouts=FAST)
    try:
        t0 = time.monotonic()
        with pytest.raises((SyncError, ConnectionError, OSError)):
            robot(server.addresses[0], timeouts=FAST)
        assert time.monotonic() - t0 < 4.0
        a.pose()  # the first one is untouched
    finally:
        a.disconnect()


def test_each_session_starts_from_the_defaults_and_zero_odometry(server):
    body = server.sim.bodies[0]
    a = robot(server.addresses[0], timeouts=FAST)
    np.testing.assert_array_equal(a.pose(), 0.0)  # a Pioneer's odometry at open
    a.set_max_velocity(0.0)
    a.setvel(0.3)
    a._send("SETA", 0.05)
    a.pose()
    a.disconnect()
    moved_to = body.true_pose.copy()
    b = robot(server.addresses[0], timeouts=FAST)
    try:
        np.testing.assert_array_equal(b.pose(), 0.0)
        b.move(0.3)
        b.wait_move_done(10)  # the old client's max velocity of 0 is gone
        x, y, th = b.pose()
        assert math.hypot(x, y) == pytest.approx(0.3, abs=0.04)
        # the true pose moved on from where the first client left it
        d = np.linalg.norm(body.true_pose[:2] - moved_to[:2])
        assert d == pytest.approx(0.3, abs=0.06)
    finally:
        b.disconnect()


def test_port_zero_in_an_address_is_an_error():
    with pytest.raises(ValueError, match="port 0"):
        robot("tcp://127.0.0.1:0")
    with pytest.raises(ValueError, match="port"):
        open_transport("tcp://127.0.0.1:99999")


def test_ctrl_c_stops_the_server_cleanly():
    code = "from robotlib.cli import main; raise SystemExit(main())"
    p = subprocess.Popen(
        [sys.executable, "-c", code, "sim-server", "--port", "0"],
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    try:
        deadline = time.monotonic() + 60
        lines = []
        while time.monotonic() < deadline:
            line = p.stderr.readline()
            lines.append(line)
            if "serving" in line or not line:
                break
        assert any("serving" in s for s in lines), lines
        time.sleep(0.3)
        p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=20)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 0, err
    assert "Traceback" not in err and "error" not in err.lower(), err


# -- hostile packet streams against one Session (no sockets), bounded -------------
@pytest.fixture(scope="module")
def sim():
    s = Simulator(load_world("corridor"), seed=0)
    s.add_robot()
    return s


ids = st.sampled_from([int(c) for c in Command] + [0x7F, 0xFF, 3, 0x50])
packets = st.builds(lambda i, a: frame(i, a), ids, st.binary(max_size=12)) | st.builds(
    lambda name, v: encode_si(name, v),
    st.sampled_from(["MOVE", "HEAD", "DHEAD", "VEL", "RVEL", "SETV", "SETRV"]),
    st.floats(-30, 30),
)


@settings(max_examples=80, deadline=None)
@given(
    st.lists(packets | st.binary(max_size=40), max_size=25),
    st.lists(st.integers(1, 9), min_size=1, max_size=5),
)
def test_hostile_streams_never_raise_and_leave_a_finite_robot(sim, stream, cuts):
    session = Session(sim, sim.bodies[0])
    data = command(0) + command(1) + command(2) + command(Command.OPEN, 1)
    data += b"".join(stream)
    k = 0
    while data:  # in odd-sized pieces, as TCP may deliver them
        n = cuts[k % len(cuts)] * 7
        session.receive(data[:n])
        data = data[n:]
        sim.step()
        session.tick()
        k += 1
    state = sim.bodies[0].state
    assert np.all(np.isfinite(state.pose)) and np.all(np.isfinite(state.velocity))
    sim.reset()
