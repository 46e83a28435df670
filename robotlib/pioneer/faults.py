"""A fault-injecting link between a Pioneer client and server: delay and loss.

`FaultyLink` is a TCP proxy on loopback: a client connects to its port
instead of the server's, and every packet (whole, as `PacketDecoder` splits
the stream) is passed on after a delay of ``delay`` plus a uniform jitter up
to ``jitter`` seconds, in order; server information packets (SIPs, ids
0x30-0x3F) are dropped with probability ``loss``. Handshake and command
packets are delayed but never dropped, as a real link's retries would see to.
Together with a simulator whose odometry slips more (`robotlib.sim.OdometryNoise`)
it stands in for a bad radio link to a real robot.

Every socket operation has a timeout; `stop` ends the proxy's thread. Imports
the packet framing only; never the server or client.
"""

from __future__ import annotations

import heapq
import itertools
import selectors
import socket
import threading
import time

from .._random import as_rng
from .packets import PacketDecoder, frame

__all__ = ["FaultyLink"]

_SIP_IDS = range(0x30, 0x40)


class FaultyLink:
    """Proxy one client at a time to ``target``, delaying and dropping packets.

    Parameters
    ----------
    target_port : int
        The server's TCP port.
    target_host : str
        The server's address.
    delay, jitter : float
        Each packet waits ``delay + U(0, jitter)`` s (order is kept).
    loss : float
        Probability that a SIP from the server is dropped.
    seed : numpy.random.Generator, int or None
        The faults' randomness.
    host : str
        Address to listen on (loopback by default).
    port : int
        Port to listen on; 0 picks a free one (see `port`).

    Attributes
    ----------
    dropped, forwarded : int
        Packets dropped and passed on so far.
    """

    def __init__(
        self,
        target_port: int,
        target_host: str = "127.0.0.1",
        *,
        delay: float = 0.0,
        jitter: float = 0.0,
        loss: float = 0.0,
        seed=None,
        host: str = "127.0.0.1",
        port: int = 0,
    ):
        if delay < 0 or jitter < 0 or not 0 <= loss <= 1:
            raise ValueError("need delay >= 0, jitter >= 0 and 0 <= loss <= 1")
        self.target = (target_host, int(target_port))
        self.delay, self.jitter, self.loss = float(delay), float(jitter), float(loss)
        self._rng = as_rng(seed)
        self._listener = socket.create_server((host, port))
        self._listener.settimeout(1.0)
        self.port = self._listener.getsockname()[1]
        self.dropped = 0
        self.forwarded = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.error: BaseException | None = None

    @property
    def address(self) -> str:
        """The robot address a client connects to (``tcp://HOST:PORT``)."""
        return f"tcp://{self._listener.getsockname()[0]}:{self.port}"

    def start(self) -> FaultyLink:
        """Serve in a background thread; return self."""
        self._thread = threading.Thread(target=self._serve, daemon=True, name="faults")
        self._thread.start()
        return self

    def stop(self, timeout: float = 2.0) -> None:
        """Stop serving and close every socket."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout)
        self._listener.close()

    def __enter__(self) -> FaultyLink:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    # -- the proxy ----------------------------------------------------------
    def _serve(self) -> None:
        try:
            while not self._stop.is_set():
                try:
                    client, _ = self._listener.accept()
                except TimeoutError:
                    continue
                except OSError:
                    return
                with client:
                    try:
                        server = socket.create_connection(self.target, timeout=5.0)
                    except OSError:
                        continue
                    with server:
                        self._pump(client, server)
        except BaseException as exc:  # noqa: BLE001 - reported, not raised
            self.error = exc

    def _pump(self, client: socket.socket, server: socket.socket) -> None:
        """Forward both ways until either side closes or `stop`."""
        client.setblocking(False)
        server.setblocking(False)
        peer = {client: server, server: client}
        decoders = {client: PacketDecoder(), server: PacketDecoder()}
        queue: list[tuple[float, int, socket.socket, bytes]] = []
        order = itertools.count()
        last_due = {client: 0.0, server: 0.0}
        with selectors.DefaultSelector() as sel:
            sel.register(client, selectors.EVENT_READ)
            sel.register(server, selectors.EVENT_READ)
            while not self._stop.is_set():
                wait = 0.05 if not queue else max(0.0, queue[0][0] - time.monotonic())
                for key, _ in sel.select(timeout=min(wait, 0.05)):
                    src = key.fileobj
                    try:
                        data = src.recv(4096)
                    except (BlockingIOError, InterruptedError):
                        continue
                    except OSError:
                        return
                    if not data:
                        return
                    dst = peer[src]
                    for pkt in decoders[src].feed(data):
                        if src is server and pkt.id in _SIP_IDS:
                            if self._rng.random() < self.loss:
                                self.dropped += 1
                                continue
                        lag = self.delay + self.jitter * float(self._rng.random())
                        due = max(time.monotonic() + lag, last_due[dst])
                        last_due[dst] = due
                        raw = frame(pkt.id, pkt.data)
                        heapq.heappush(queue, (due, next(order), dst, raw))
                now = time.monotonic()
                while queue and queue[0][0] <= now:
                    _, _, dst, raw = heapq.heappop(queue)
                    try:
                        dst.settimeout(1.0)
                        dst.sendall(raw)
                        dst.setblocking(False)
                    except OSError:
                        return
                    self.forwarded += 1


# -- the command line -------------------------------------------------------------
def add_arguments(parser) -> None:
    """Arguments of ``robotlib faulty-link``."""
    parser.add_argument("--target", type=int, default=8101, help="the server's port")
    parser.add_argument("--port", type=int, default=8102, help="port to listen on")
    parser.add_argument("--delay", type=float, default=0.05, help="delay per packet, s")
    parser.add_argument("--jitter", type=float, default=0.05, help="extra delay, s")
    parser.add_argument("--loss", type=float, default=0.1, help="share of SIPs lost")
    parser.add_argument("--seed", type=int, default=None, help="the faults' seed")
    parser.add_argument(
        "--duration", type=float, default=None, help="stop after this many s"
    )


def run(args) -> int:
    """Proxy until interrupted (or ``--duration``); return the exit status."""
    import logging

    logging.basicConfig(level=logging.INFO, format="faulty-link: %(message)s")
    link = FaultyLink(
        args.target, delay=args.delay, jitter=args.jitter, loss=args.loss,
        seed=args.seed, port=args.port,
    ).start()  # fmt: skip
    logging.getLogger(__name__).info("serving %s -> port %d", link.address, args.target)
    try:
        end = None if args.duration is None else time.monotonic() + args.duration
        while end is None or time.monotonic() < end:
            time.sleep(0.2)
    except KeyboardInterrupt:
        pass
    finally:
        link.stop()
    return 0 if link.error is None else 1
