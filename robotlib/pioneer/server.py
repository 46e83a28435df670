"""``robotlib sim-server``: the simulator over the Pioneer protocol, as MobileSim.

Each simulated robot listens on its own TCP port (8101, 8102, ... on
127.0.0.1 by default) or on a pseudo-terminal (the serial path). A client
runs the SYNC handshake, sends OPEN and then gets a SIP every 100 ms of
simulated time; the simulator runs in real time, or ``speed`` times faster,
or in lock-step: one cycle each time every open client has asked for it
(``SIM_STEP``, robotlib's own command; connect with
``robotlib.robot(address, lockstep=True)``), so a slow or busy client sees
exactly the run a fast one sees.
`robotlib.pioneer.session.Session` is the protocol of one link, bytes in
and bytes out, with no I/O (re-exported here); `SimServer` moves bytes
between sessions and sockets in one thread with a selector. Garbage, bad
checksums, truncated or malformed packets are skipped; a client that
vanishes or misbehaves is dropped, its robot stopped, and the next client
is accepted on the same port.

Every connection is accepted at once (the backlog fits a class connecting
together) and runs its own handshake; the first to OPEN drives the robot,
a second one is refused (closed) while the first is alive, and one that
does not open within ``handshake_timeout`` is closed, so a silent socket
cannot hold a port. Each session starts from a freshly opened Pioneer's
state: defaults for speeds and accelerations, odometry (0, 0, 0); the true
pose is the simulator's (``SIM_SET_POSE``, ``SIM_RESET``).
"""

from __future__ import annotations

import argparse
import logging
import math
import os
import selectors
import socket
import threading
import time
import tty

import numpy as np

from ..p3dx import CYCLE
from .session import Session
from .transport import DEFAULT_PORT

__all__ = ["Session", "SimServer", "add_arguments", "run"]

log = logging.getLogger(__name__)

_MAX_OUTBOX = 64 * 1024


class _Conn:
    """One accepted TCP connection: its socket, session and unsent bytes."""

    def __init__(self, sock: socket.socket, session: Session, now: float):
        self.sock = sock
        self.session = session
        self.outbox = bytearray()
        self.accepted = now


class _Endpoint:
    """One robot's link: a TCP listener or a pseudo-terminal, and its sessions.

    A TCP robot accepts every connection; each runs its own handshake, and
    the first to send OPEN drives the robot (`owner`) until it leaves, goes
    silent or closes. Connections that do not open within the handshake
    timeout are dropped, so none can hold the port.
    """

    def __init__(self, server: SimServer, body, kind: str):
        self.server = server
        self.body = body
        self.kind = kind
        self.listener: socket.socket | None = None
        self.conns: list[_Conn] = []
        self.owner: _Conn | None = None
        self.fd: int | None = None  # pty master
        self.slave_fd: int | None = None
        self.path: str | None = None
        self.port: int | None = None
        self.session: Session | None = None  # the pty's
        self.clients = 0

    def new_session(self, claim=None) -> Session:
        return Session(
            self.server.sim, self.body, claim=claim, **self.server.session_options
        )

    @property
    def active(self) -> Session | None:
        """The open session driving this robot, if any."""
        if self.kind == "pty":
            return self.session if self.session and self.session.open else None
        owner = self.owner
        return owner.session if owner is not None and owner.session.open else None


class SimServer:
    """Serve simulated Pioneers over the protocol.

    Parameters
    ----------
    world : str or World
        World name or file (ignored if ``sim`` is given).
    robots : int
        Robots served over TCP, on ports ``port``, ``port + 1``, ...
    ptys : int
        Further robots served over pseudo-terminals (see `pty_paths`).
    port : int
        First TCP port; 0 picks free ports (see `ports`).
    host : str
        Address to bind (loopback by default).
    speed : float
        Simulated seconds per wall-clock second (1 = real time); ignored in
        lock-step.
    lockstep : bool
        Step the simulator only when every client that drives a robot has
        asked for the next cycle (``SIM_STEP``), whatever the wall clock says.
        Clients that do not ask (MobileSim's) then get no SIP.
    seed : Generator, int or None
        The simulator's randomness.
    sim : robotlib.sim.Simulator, optional
        Serve robots of this simulator (new bodies are added to it).
    drop_after : float
        Close an open session whose client sent nothing for this long, s.
    handshake_timeout : float
        Close a connection that has not opened (SYNC0-2, OPEN) this long
        after it was accepted, s.
    max_pending : int
        Connections per robot at most at once; one more is accepted and
        closed at once (a clean refusal rather than a hang).
    backlog : int
        The listening sockets' backlog (a class connecting at once).
    session_options
        Passed to each `Session` (``name``, ``subclass``, ``watchdog``...).
    """

    def __init__(
        self,
        world="corridor",
        *,
        robots: int = 1,
        ptys: int = 0,
        port: int = DEFAULT_PORT,
        host: str = "127.0.0.1",
        speed: float = 1.0,
        lockstep: bool = False,
        seed=None,
        sim=None,
        drop_after: float = 10.0,
        handshake_timeout: float = 3.0,
        max_pending: int = 64,
        backlog: int = 128,
        **session_options,
    ):
        if not speed > 0 or not math.isfinite(speed):
            raise ValueError(f"speed must be a positive number, got {speed!r}")
        if robots < 0 or ptys < 0 or robots + ptys < 1:
            raise ValueError("serve at least one robot")
        if sim is None:
            from ..sim import Simulator
            from ..world import World, load_world

            if not isinstance(world, World):
                world = load_world(world)
            sim = Simulator(world, seed)
            created = True
        else:
            created = False
        self.sim = sim
        self.host = host
        self.period = CYCLE / float(speed)
        self.lockstep = bool(lockstep)
        self.drop_after = drop_after
        self.handshake_timeout = float(handshake_timeout)
        self.max_pending = int(max_pending)
        self.backlog = int(backlog)
        self.session_options = session_options
        self.error: BaseException | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._sel = selectors.DefaultSelector()
        self.endpoints: list[_Endpoint] = []
        bodies = [_add_body(sim, i) for i in range(robots + ptys)]
        if created:  # compile the simulator's kernels before any client can connect
            sim.step()
            sim.reset()
        try:
            for i, body in enumerate(bodies):
                ep = _Endpoint(self, body, "tcp" if i < robots else "pty")
                self.endpoints.append(ep)
                if ep.kind == "tcp":
                    self._listen(ep, port + i if port else 0)
                else:
                    self._open_pty(ep)
        except BaseException:
            self._close_all()
            raise

    # -- setup ------------------------------------------------------------
    def _listen(self, ep: _Endpoint, port: int) -> None:
        s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        ep.listener = s
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        s.bind((self.host, port))
        s.listen(self.backlog)
        s.setblocking(False)
        ep.port = s.getsockname()[1]
        self._sel.register(s, selectors.EVENT_READ, ("accept", ep, None))

    def _open_pty(self, ep: _Endpoint) -> None:
        master, slave = os.openpty()
        tty.setraw(slave)
        os.set_blocking(master, False)
        ep.fd, ep.slave_fd, ep.path = master, slave, os.ttyname(slave)
        ep.session = ep.new_session()
        self._sel.register(master, selectors.EVENT_READ, ("pty", ep, None))

    @property
    def ports(self) -> list[int]:
        """The TCP ports, one per TCP robot."""
        return [ep.port for ep in self.endpoints if ep.kind == "tcp"]

    @property
    def pty_paths(self) -> list[str]:
        """The pseudo-terminal device paths (``/dev/pts/N``), one per pty robot."""
        return [ep.path for ep in self.endpoints if ep.kind == "pty"]

    @property
    def addresses(self) -> list[str]:
        """Robot addresses for `robotlib.robot`: ``tcp://...`` then ``serial://...``."""
        tcp = [f"tcp://{self.host}:{p}" for p in self.ports]
        return tcp + [f"serial://{p}" for p in self.pty_paths]

    # -- running ------------------------------------------------------------
    def start(self) -> SimServer:
        """Serve in a background thread; return self."""
        self._thread = threading.Thread(
            target=self._serve, name="sim-server", daemon=True
        )
        self._thread.start()
        return self

    def serve(self, duration: float | None = None) -> None:
        """Serve in this thread for ``duration`` s (None: until `stop`)."""
        if duration is not None:
            timer = threading.Timer(duration, self._stop.set)
            timer.daemon = True
            timer.start()
        self._serve()

    def stop(self, timeout: float = 2.0) -> None:
        """Stop serving, close every socket and pty (idempotent)."""
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout)
        self._close_all()

    def __enter__(self) -> SimServer:
        return self.start() if self._thread is None else self

    def __exit__(self, *exc) -> None:
        self.stop()

    def _serve(self) -> None:
        next_tick = time.monotonic() + self.period
        try:
            while not self._stop.is_set():
                wait = max(0.0, min(0.1, next_tick - time.monotonic()))
                for key, _ in self._sel.select(wait):
                    kind, ep, conn = key.data
                    try:
                        if kind == "accept":
                            self._accept(ep)
                        elif kind == "conn":
                            self._read_conn(ep, conn)
                        else:
                            self._read_pty(ep)
                    except Exception as exc:  # a misbehaving client, not the server
                        log.warning("robot %s: dropping client: %s", ep.port, exc)
                        if conn is not None:
                            self._drop(ep, conn)
                        elif ep.session is not None:
                            ep.session.close()
                now = time.monotonic()
                self._expire(now)
                if self.lockstep:
                    self._step_when_asked()
                elif now >= next_tick:
                    self._tick()
                    next_tick += self.period
                    if now - next_tick > 5 * self.period:  # fell behind: do not burst
                        next_tick = now + self.period
        except KeyboardInterrupt:
            log.info("interrupted: stopping")
        except BaseException as exc:
            self.error = exc
            log.exception("sim-server stopped on an error")
        finally:
            self._close_all()

    def _expire(self, now: float) -> None:
        """Drop connections that did not open in time, or that closed."""
        for ep in self.endpoints:
            for c in list(ep.conns):
                s = c.session
                if s.open:
                    continue
                if s.refused or s.was_open:  # refused, or sent CLOSE
                    self._drop(ep, c)
                elif now - c.accepted > self.handshake_timeout:
                    log.info("robot %s: no handshake in time, closing", ep.port)
                    self._drop(ep, c)

    def _step_when_asked(self) -> None:
        """Lock-step: step once every driving client has asked for its next cycle.

        A client that has just opened gets the present state at once (no
        step), so it can join while the others wait for it.
        """
        active = [ep for ep in self.endpoints if ep.active is not None]
        for ep in active:
            if ep.active.step_asked and ep.active.fresh:
                self._send_sip(ep)
        if active and all(ep.active.step_asked for ep in active):
            self._tick()

    def _tick(self) -> None:
        active = [ep for ep in self.endpoints if ep.active is not None]
        if not active:
            return
        self.sim.step()
        now = time.monotonic()
        for ep in active:
            if now - ep.active.last_packet > self.drop_after:
                log.info("robot %s: client silent, closing its session", ep.port)
                if ep.kind == "tcp":
                    self._drop(ep, ep.owner)
                else:
                    ep.active.close()
                continue
            self._send_sip(ep)

    def _send_sip(self, ep: _Endpoint) -> None:
        if ep.kind == "tcp":
            self._send(ep, ep.active.tick(), ep.owner)
        else:
            self._send(ep, ep.active.tick())

    # -- TCP ------------------------------------------------------------------
    def _claim(self, ep: _Endpoint, conn_ref: list) -> bool:
        """May the connection in ``conn_ref`` take the robot? (on its OPEN)."""
        conn = conn_ref[0]
        owner = ep.owner
        if owner is not None and owner is not conn:
            # a CLOSE or a hang-up the previous client already sent comes first
            self._read_conn(ep, owner)
            owner = ep.owner
        if owner is not None and owner is not conn:
            s = owner.session
            if s.open and s.silent_for <= s.watchdog:
                log.info("robot %s: busy, refusing a second client", ep.port)
                return False
            log.info("robot %s: previous client gone or silent, replacing it", ep.port)
            self._drop(ep, owner)
        ep.owner = conn
        ep.clients += 1
        return True

    def _accept(self, ep: _Endpoint) -> None:
        for _ in range(self.backlog):
            try:
                sock, _ = ep.listener.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError as exc:  # e.g. out of file descriptors: try later
                log.warning("robot %s: accept failed: %s", ep.port, exc)
                return
            if len(ep.conns) >= self.max_pending:
                log.info("robot %s: too many connections, refusing one", ep.port)
                sock.close()
                continue
            sock.setblocking(False)
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            ref: list = []
            conn = _Conn(
                sock,
                ep.new_session(lambda _s, r=ref: self._claim(ep, r)),
                time.monotonic(),
            )
            ref.append(conn)
            ep.conns.append(conn)
            self._sel.register(sock, selectors.EVENT_READ, ("conn", ep, conn))

    def _read_conn(self, ep: _Endpoint, conn: _Conn) -> None:
        try:
            data = conn.sock.recv(4096)
        except BlockingIOError:
            return
        except OSError:
            data = b""
        if not data:
            self._drop(ep, conn)
            return
        self._send(ep, conn.session.receive(data), conn)

    def _send(self, ep: _Endpoint, data: bytes, conn: _Conn | None = None) -> None:
        if not data:
            return
        if ep.kind == "pty":
            try:
                os.write(ep.fd, data)
            except BlockingIOError:
                pass  # nobody reads the line: the bytes are lost, as on a cable
            return
        if conn is None or conn not in ep.conns:
            return
        conn.outbox += data
        try:
            sent = conn.sock.send(conn.outbox)
            del conn.outbox[:sent]
        except BlockingIOError:
            pass
        except OSError:
            self._drop(ep, conn)
            return
        if len(conn.outbox) > _MAX_OUTBOX:
            log.info("robot %s: client does not read, dropping it", ep.port)
            self._drop(ep, conn)

    def _drop(self, ep: _Endpoint, conn: _Conn | None) -> None:
        """Forget one client: stop its robot if it drove it, close its socket."""
        if conn is None or conn not in ep.conns:
            return
        conn.session.close()
        ep.conns.remove(conn)
        if ep.owner is conn:
            ep.owner = None
        try:
            self._sel.unregister(conn.sock)
        except (KeyError, ValueError):
            pass
        conn.sock.close()

    # -- pty --------------------------------------------------------------------
    def _read_pty(self, ep: _Endpoint) -> None:
        try:
            data = os.read(ep.fd, 4096)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            return  # EIO while no process holds the slave open
        self._send(ep, ep.session.receive(data))

    def _close_all(self) -> None:
        for ep in self.endpoints:
            socks = [c.sock for c in ep.conns] + [ep.listener]
            ep.conns.clear()
            ep.owner = None
            for sock in socks:
                if sock is not None:
                    try:
                        self._sel.unregister(sock)
                    except (KeyError, ValueError):
                        pass
                    sock.close()
            ep.listener = None
            for fd in (ep.fd, ep.slave_fd):
                if fd is not None:
                    try:
                        self._sel.unregister(fd)
                    except (KeyError, ValueError):
                        pass
                    try:
                        os.close(fd)
                    except OSError:
                        pass
            ep.fd = ep.slave_fd = None
        try:
            self._sel.close()
        except (OSError, RuntimeError):
            pass


def _add_body(sim, index: int):
    """Add a robot: the world's start pose, else the nearest clear spot beside it."""
    if index == 0 and not sim.bodies:
        return sim.add_robot()
    start = np.asarray(sim.world.start, dtype=float)
    c, s = math.cos(start[2]), math.sin(start[2])
    for k in range(1, 40):
        for sign in (1, -1):
            for along in (0.0, -0.6, 0.6):
                side = sign * 0.6 * k
                pose = start + [along * c - side * s, along * s + side * c, 0.0]
                try:
                    return sim.add_robot(pose)
                except ValueError:
                    continue
    raise ValueError("no clear spot for another robot near the start pose")


# -- the command line -------------------------------------------------------------
def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``robotlib sim-server``."""
    parser.add_argument("--world", default="corridor", help="world name or file")
    parser.add_argument("--port", type=int, default=DEFAULT_PORT, help="first TCP port")
    parser.add_argument("--host", default="127.0.0.1", help="address to bind")
    parser.add_argument("--robots", type=int, default=1, help="robots on TCP ports")
    parser.add_argument(
        "--pty", type=int, default=0, metavar="N",
        help="also serve N robots on pseudo-terminals (serial path)",
    )  # fmt: skip
    parser.add_argument(
        "--speed", type=float, default=1.0, help="simulated s per real s (1: real time)"
    )
    parser.add_argument(
        "--lockstep", action="store_true",
        help="step only when every client asks (SIM_STEP; clients: lockstep=True)",
    )  # fmt: skip
    parser.add_argument("--seed", type=int, default=None, help="simulator seed")
    parser.add_argument("--name", default="robotlib", help="name in the SYNC2 reply")
    parser.add_argument(
        "--duration", type=float, default=None, help="stop after this many s"
    )


def run(args: argparse.Namespace) -> int:
    """Serve until interrupted (or ``--duration``); return the exit status."""
    logging.basicConfig(level=logging.INFO, format="sim-server: %(message)s")
    server = SimServer(
        args.world,
        robots=args.robots,
        ptys=args.pty,
        port=args.port,
        host=args.host,
        speed=args.speed,
        lockstep=args.lockstep,
        seed=args.seed,
        name=args.name,
    )
    for addr in server.addresses:
        log.info("serving %s", addr)
    try:
        server.serve(args.duration)
    except KeyboardInterrupt:  # Ctrl-C between two select calls: a clean stop
        log.info("interrupted: stopping")
    finally:
        server.stop()
    return 0 if server.error is None else 1
