"""The sim-server end to end: TCP, pseudo-terminal, several robots, bad clients."""

import math
import random
import socket
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robotlib import (
    disconnect,
    isheadingdone,
    ismovedone,
    move,
    readsonar,
    robot,
    setdeltaheading,
)
from robotlib.cli import main as cli_main
from robotlib.pioneer.commands import Command, command, encode_si
from robotlib.pioneer.packets import PacketDecoder, frame
from robotlib.pioneer.server import Session, SimServer
from robotlib.pioneer.sip import decode_sip
from robotlib.pioneer.transport import Timeouts
from robotlib.sim import Simulator
from robotlib.world import load_world

FAST = Timeouts(
    connect=2.0, sync_reply=0.3, sync_total=3.0, link=1.0, poll=0.01, pulse=0.2,
    config=0.5, close=0.5,
)  # fmt: skip
SPEED = 20.0  # simulated seconds per wall-clock second in these tests


def table1(r, loops=2, max_polls=400):
    """The paper's Table-1 example (bounded); returns what it saw."""
    moves = headings = 0
    for _ in range(loops):
        move(r, 0.5)
        for _ in range(max_polls):
            if ismovedone(r):
                moves += 1
                break
        setdeltaheading(r, math.pi)
        for _ in range(max_polls):
            if isheadingdone(r):
                headings += 1
                break
    z = readsonar(r)
    disconnect(r)
    return moves, headings, z


def check_table1(result, loops=2):
    moves, headings, z = result
    assert moves == loops and headings == loops
    assert z.shape == (8,) and np.all((z >= 0.1) & (z <= 5.0))


@pytest.fixture(scope="module")
def server():
    with SimServer("corridor", robots=1, port=0, speed=SPEED, seed=0) as srv:
        srv.sim.step()  # compile the kernels once
        yield srv


def test_table1_same_behaviour_on_sim_tcp_and_pty(server):
    check_table1(table1(robot("sim:corridor", seed=0)))
    (tcp,) = server.addresses
    assert tcp.startswith("tcp://127.0.0.1:")
    check_table1(table1(robot(tcp, timeouts=FAST)))
    with SimServer("corridor", robots=0, ptys=1, speed=SPEED, seed=0) as srv:
        (pty,) = srv.addresses
        assert pty.startswith("serial:///dev/")
        check_table1(table1(robot(pty, timeouts=FAST)))
        check_table1(table1(robot(pty, timeouts=FAST)))  # and again on the same line


def test_pyserial_socket_url_reaches_the_tcp_server(server):
    port = server.ports[0]
    r = robot(f"serial:socket://127.0.0.1:{port}", timeouts=FAST)
    check_table1(table1(r, loops=1), loops=1)


def test_next_client_after_one_vanishes(server):
    addr = server.addresses[0]
    port = server.ports[0]
    r = robot(addr, timeouts=FAST)
    r.setvel(0.3)
    r.pose()
    r.transport.close()  # vanish without ENABLE 0 / CLOSE
    r._stop.set()
    # a client that sends garbage and a half packet, then hangs up
    with socket.create_connection(("127.0.0.1", port), timeout=2) as s:
        s.sendall(bytes(random.Random(1).randrange(256) for _ in range(500)))
        s.sendall(frame(Command.VEL, b"\x3b\xc8\x00")[:5])
    r2 = robot(addr, timeouts=FAST)
    try:
        assert abs(r2.pose()[0] - r2.pose()[0]) < 0.01  # the old VEL was stopped
        assert abs(r2.state.velocity[0]) < 0.05
    finally:
        r2.disconnect()
    assert server.error is None


def test_raw_socket_fuzz_then_a_normal_client(server):
    port = server.ports[0]
    rng = random.Random(7)
    with socket.create_connection(("127.0.0.1", port), timeout=2) as s:
        s.settimeout(1.0)
        dec = PacketDecoder()
        replies = []
        for sync in (0, 1, 2):
            junk = bytes(rng.randrange(256) for _ in range(rng.randrange(50)))
            bad = bytearray(command(sync))
            bad[-1] ^= 0x10
            s.sendall(junk + bytes(bad) + b"\xfa" + command(sync))
            deadline = time.monotonic() + 1.0
            while time.monotonic() < deadline and len(replies) <= sync:
                replies += dec.feed(s.recv(4096))
        assert [p.id for p in replies[:3]] == [0, 1, 2]
        assert replies[2].data.split(b"\0")[:3] == [b"robotlib", b"Pioneer", b"p3dx"]
        s.sendall(command(Command.OPEN, 1) + command(Command.CONFIG, 1))
        ids = set()
        deadline = time.monotonic() + 1.0
        while time.monotonic() < deadline and not {0x20, 0x32} <= ids:
            ids |= {p.id for p in dec.feed(s.recv(4096))}
        assert {0x20, 0x32} <= ids
        for _ in range(50):  # random well-framed packets of every id
            s.sendall(
                frame(rng.randrange(256), bytes(rng.randrange(256) for _ in range(9)))
            )
    r = robot(server.addresses[0], timeouts=FAST)
    check_table1(table1(r, loops=1), loops=1)


def free_base_port(n):
    rng = random.Random()
    for _ in range(50):
        base = rng.randrange(20000, 60000)
        socks = []
        try:
            for i in range(n):
                s = socket.socket()
                socks.append(s)
                s.bind(("127.0.0.1", base + i))
            return base
        except OSError:
            continue
        finally:
            for s in socks:
                s.close()
    pytest.skip("no free consecutive ports")


def consecutive_ports_server(n: int) -> tuple[SimServer, int]:
    """A server of ``n`` robots asked for consecutive ports found free; the first.

    Another suite on the machine may take one of them before the server
    binds it: then other ports are tried.
    """
    for _ in range(10):
        base = free_base_port(n)
        try:
            srv = SimServer("corridor", robots=n, port=base, speed=SPEED, seed=0)
        except OSError:
            continue
        return srv, base
    pytest.skip("no free consecutive ports")


def test_several_robots_on_consecutive_ports():
    srv, base = consecutive_ports_server(2)
    with srv:
        assert srv.ports == [base, base + 1]
        a = robot(f"tcp://127.0.0.1:{base}", timeouts=FAST)
        b = robot(f"tcp://127.0.0.1:{base + 1}", timeouts=FAST)
        try:
            # each session's odometry starts at (0, 0, 0), as a Pioneer's does;
            # the robots themselves stand apart
            np.testing.assert_array_equal(a.pose(), 0.0)
            np.testing.assert_array_equal(b.pose(), 0.0)
            ta, tb = (body.true_pose for body in srv.sim.bodies)
            assert np.linalg.norm(ta[:2] - tb[:2]) > 0.5
            a.move(0.3)
            a.wait_move_done(10)
            assert b.ismovedone()
        finally:
            a.disconnect()
            b.disconnect()


def test_the_port_opens_only_after_the_kernels_are_warm(monkeypatch):
    # an ARIA client that connects while kernels compile gets no replies and
    # fails its handshake: the simulator steps once before any port listens
    order = []
    real_step, real_listen = Simulator.step, SimServer._listen

    def step(sim, *args, **kwargs):
        order.append("step")
        return real_step(sim, *args, **kwargs)

    def listen(srv, ep, port):
        order.append("listen")
        return real_listen(srv, ep, port)

    monkeypatch.setattr(Simulator, "step", step)
    monkeypatch.setattr(SimServer, "_listen", listen)
    with SimServer("corridor", robots=2, port=0, seed=0):
        pass
    assert order == ["step", "listen", "listen"]


def test_cli_serves_for_a_duration():
    assert cli_main(["sim-server", "--port", "0", "--duration", "0.3"]) == 0


def test_bad_server_arguments():
    with pytest.raises(ValueError):
        SimServer("corridor", port=0, speed=0)
    with pytest.raises(ValueError):
        SimServer("corridor", robots=0)


# -- the Session alone: no sockets -------------------------------------------------
@pytest.fixture(scope="module")
def sim():
    s = Simulator(load_world("corridor"), seed=0)
    s.add_robot()
    return s


def open_session(sim, **kw):
    s = Session(sim, sim.bodies[0], **kw)
    for i in (0, 1, 2):
        assert s.receive(command(i))
    s.receive(command(Command.OPEN, 1))
    assert s.open
    return s


def test_session_commands_in_si(sim):
    s = open_session(sim)
    body = sim.bodies[0]
    s.receive(encode_si("SETO"))
    np.testing.assert_allclose(body.state.pose, 0.0)
    s.receive(encode_si("VEL", 0.2) + encode_si("RVEL", 0.1))
    for _ in range(20):
        sim.step()
    v, w = body.state.velocity
    assert v == pytest.approx(0.2, abs=1e-6) and w == pytest.approx(0.1, abs=0.01)
    sip = decode_sip(s.tick()[4:-2])
    assert sip.left_vel < 200 < sip.right_vel
    s.receive(encode_si("STOP"))
    for _ in range(20):
        sim.step()
    assert body.state.velocity == (0.0, 0.0)
    s.receive(encode_si("SONAR", False))
    assert decode_sip(s.tick()[4:-2]).sonar == ()
    s.receive(encode_si("SONAR", True) + encode_si("CLOSE"))
    assert not s.open and s.tick() == b""
    sim.reset()


def test_session_watchdog_stops_a_silent_client(sim):
    clock = [0.0]
    s = open_session(sim, watchdog=2.0, clock=lambda: clock[0])
    s.receive(encode_si("VEL", 0.3))
    for _ in range(10):
        sim.step()
        s.tick()
    assert sim.bodies[0].state.velocity[0] > 0.2
    clock[0] = 2.5
    s.tick()
    for _ in range(20):
        sim.step()
    assert sim.bodies[0].state.velocity[0] == 0.0
    sim.reset()


@settings(max_examples=60, deadline=None)
@given(
    chunks=st.lists(st.binary(max_size=64), max_size=12),
    ids=st.lists(st.integers(0, 255), max_size=12),
    args=st.lists(st.binary(max_size=14), max_size=12),
)
def test_session_fuzz_never_raises(sim, chunks, ids, args):
    s = Session(sim, sim.bodies[0])
    stream = [command(0), command(1), command(2), command(1, 1)]
    stream += [frame(i, a) for i, a in zip(ids, args, strict=False)]
    for i, c in enumerate(chunks):
        stream.insert(i % len(stream), c)
    for piece in stream:
        s.receive(piece)
        s.tick()
    sim.reset()
