"""Measure the Pioneer protocol: codec, poll latency, dead-link detection time.

Run: ``.venv/bin/python bench/bench_pioneer.py``. Prints numbers; asserts nothing.
"""

import math
import statistics
import time

from robotlib.pioneer.client import PioneerRobot
from robotlib.pioneer.commands import encode_si
from robotlib.pioneer.packets import PacketDecoder
from robotlib.pioneer.server import SimServer
from robotlib.pioneer.sip import decode_sip, encode_sip, factors_for, sip_from_si
from robotlib.pioneer.transport import TcpTransport, Timeouts


def codec():
    f = factors_for("p3dx")
    raw = sip_from_si((1.0, 2.0, 0.5), 0.3, 0.1, enumerate([1.0] * 8), factors=f)
    n = 20000
    t0 = time.perf_counter()
    for _ in range(n):
        pkt = encode_sip(raw)
    t1 = time.perf_counter()
    dec = PacketDecoder()
    for _ in range(n):
        (p,) = dec.feed(pkt)
        decode_sip(p.data)
    t2 = time.perf_counter()
    for _ in range(n):
        encode_si("VEL", 0.3)
    t3 = time.perf_counter()
    print(
        f"SIP encode {1e6 * (t1 - t0) / n:.1f} us, frame+decode "
        f"{1e6 * (t2 - t1) / n:.1f} us, command encode {1e6 * (t3 - t2) / n:.1f} us"
    )


def polls(speed, n=50):
    with SimServer("corridor", port=0, speed=speed, seed=0) as srv:
        t0 = time.perf_counter()
        r = PioneerRobot.from_address(srv.addresses[0])
        t_connect = time.perf_counter() - t0
        dts = []
        for _ in range(n):
            t = time.perf_counter()
            r.pose()
            dts.append(time.perf_counter() - t)
        # round trip: command out, its effect in a SIP
        t = time.perf_counter()
        r.setvel(0.2)
        while r.pose() is not None and abs(r.state.velocity[0]) < 1e-3:
            pass
        t_effect = time.perf_counter() - t
        r.disconnect()
    print(
        f"speed {speed:>4}: connect {1e3 * t_connect:.0f} ms, poll (next SIP) "
        f"mean {1e3 * statistics.mean(dts):.1f} ms max {1e3 * max(dts):.1f} ms, "
        f"VEL -> moving in a SIP {1e3 * t_effect:.0f} ms"
    )


def _poll_until_link_error(r):
    """Poll ``r`` until its link fails; return the error's name and seconds taken."""
    kind = "no error"
    t0 = time.perf_counter()
    try:
        for _ in range(10000):
            r.pose()
    except ConnectionError as exc:
        kind = type(exc).__name__
    return kind, time.perf_counter() - t0


def dead_link(link):
    t = Timeouts(link=link)
    with SimServer("corridor", port=0, speed=1.0, seed=0) as srv:
        r = PioneerRobot.from_address(srv.addresses[0], timeouts=t)
        r.pose()
        srv._stop.set()  # the server goes silent (its sockets close as it stops)
        kind, took = _poll_until_link_error(r)
        r.disconnect()
    print(f"server gone: {kind} after {1e3 * took:.0f} ms")

    # a silent peer that keeps the socket open
    import socket
    import threading

    lst = socket.socket()
    lst.bind(("127.0.0.1", 0))
    lst.listen(1)
    port = lst.getsockname()[1]
    with SimServer("corridor", port=0, speed=1.0, seed=0) as srv:
        up = srv.ports[0]
        stop = threading.Event()

        def proxy():
            conn, _ = lst.accept()
            back = socket.create_connection(("127.0.0.1", up))
            conn.settimeout(0.01)
            back.settimeout(0.01)
            while not stop.is_set():
                for a, b in ((conn, back), (back, conn)):
                    try:
                        data = a.recv(4096)
                    except TimeoutError:
                        continue
                    if data and not (a is back and frozen.is_set()):
                        b.sendall(data)
            conn.close()
            back.close()

        frozen = threading.Event()
        th = threading.Thread(target=proxy, daemon=True)
        th.start()
        r = PioneerRobot(TcpTransport("127.0.0.1", port, t), timeouts=t)
        r.pose()
        frozen.set()  # robot -> client bytes stop, the socket stays open
        kind, took = _poll_until_link_error(r)
        r.disconnect()
        stop.set()
        th.join(2)
    lst.close()
    print(f"silent link (timeout {link} s): {kind} after {1e3 * took:.0f} ms")


def table1_wall(speed):
    with SimServer("corridor", port=0, speed=speed, seed=0) as srv:
        r = PioneerRobot.from_address(srv.addresses[0])
        t0 = time.perf_counter()
        for _ in range(2):
            r.move(0.5)
            while not r.ismovedone():
                pass
            r.setdeltaheading(math.pi)
            while not r.isheadingdone():
                pass
        print(
            f"speed {speed:>4}: Table-1 loop x2 in {time.perf_counter() - t0:.2f} s "
            f"wall, {r.state.time:.1f} s robot time"
        )
        r.disconnect()


if __name__ == "__main__":
    codec()
    for speed in (1.0, 10.0, 50.0):
        polls(speed)
    dead_link(3.0)
    for speed in (1.0, 20.0):
        table1_wall(speed)
