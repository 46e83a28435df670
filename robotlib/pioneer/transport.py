"""Byte links to a Pioneer: TCP, serial (pyserial), a file descriptor, in memory.

All share the small `Transport` interface (``write``, ``read`` with a
timeout, ``close``). Every time limit of the protocol is in `Timeouts`, the
one place to change them.
"""

from __future__ import annotations

import os
import select
import socket
import threading
from abc import ABC, abstractmethod
from collections import deque
from dataclasses import dataclass
from urllib.parse import urlsplit

__all__ = [
    "Timeouts",
    "LinkClosed",
    "Transport",
    "TcpTransport",
    "SerialTransport",
    "FdTransport",
    "MemoryTransport",
    "memory_pair",
    "open_transport",
    "DEFAULT_PORT",
    "DEFAULT_TIMEOUTS",
]

DEFAULT_PORT = 8101
"""MobileSim's (and ``robotlib sim-server``'s) first TCP port."""


@dataclass(frozen=True)
class Timeouts:
    """Every time limit of the Pioneer link, s.

    Attributes
    ----------
    connect : float
        Opening the TCP connection or the serial port.
    sync_reply : float
        Waiting for each reply of the SYNC handshake.
    sync_total : float
        The whole handshake, retries included.
    link : float
        The longest silence (no valid packet) before the link counts as
        dead and polls raise.
    poll : float
        One blocking read in the reader thread (how often it wakes up).
    pulse : float
        Send PULSE when nothing else was sent for this long.
    config : float
        Waiting for the config packet after CONFIG 1.
    close : float
        Flushing ENABLE 0 and CLOSE and joining the reader on disconnect.
    """

    connect: float = 5.0
    sync_reply: float = 0.5
    sync_total: float = 5.0
    link: float = 3.0
    poll: float = 0.05
    pulse: float = 0.5
    config: float = 1.0
    close: float = 1.0


DEFAULT_TIMEOUTS = Timeouts()
"""The default time limits."""


class LinkClosed(ConnectionError):
    """The other end closed the link (or it was closed here)."""


class Transport(ABC):
    """A bidirectional byte link with read timeouts."""

    name = "link"

    @abstractmethod
    def write(self, data: bytes) -> None:
        """Send all of ``data`` (raise `ConnectionError` if the link is gone)."""

    @abstractmethod
    def read(self, timeout: float) -> bytes:
        """Return the bytes available within ``timeout`` s (b"" if none).

        Raises `LinkClosed` when the other end has closed the link.
        """

    @abstractmethod
    def close(self) -> None:
        """Release the link (idempotent)."""

    def reset_input(self) -> None:  # noqa: B027 - optional hook
        """Throw away bytes received but not yet read, where that is possible."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class TcpTransport(Transport):
    """A TCP connection (MobileSim, ``robotlib sim-server``, a serial bridge)."""

    def __init__(self, host: str, port: int, timeouts: Timeouts = DEFAULT_TIMEOUTS):
        self.name = f"tcp://{host}:{port}"
        try:
            self._sock = socket.create_connection(
                (host, port), timeout=timeouts.connect
            )
        except OSError as exc:
            raise ConnectionError(f"cannot connect to {self.name}: {exc}") from exc
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._wlock = threading.Lock()
        self._write_timeout = timeouts.connect

    def write(self, data: bytes) -> None:  # noqa: D102
        with self._wlock:
            try:
                self._sock.settimeout(self._write_timeout)
                self._sock.sendall(data)
            except OSError as exc:
                raise LinkClosed(f"{self.name}: write failed: {exc}") from exc

    def read(self, timeout: float) -> bytes:  # noqa: D102
        try:
            ready, _, _ = select.select([self._sock], [], [], max(0.0, timeout))
            if not ready:
                return b""
            data = self._sock.recv(4096)
        except (OSError, ValueError) as exc:
            raise LinkClosed(f"{self.name}: read failed: {exc}") from exc
        if not data:
            raise LinkClosed(f"{self.name}: closed by the robot")
        return data

    def close(self) -> None:  # noqa: D102
        try:
            self._sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        self._sock.close()


class SerialTransport(Transport):
    """A serial port through pyserial's ``serial_for_url``.

    ``url`` is a device (``/dev/ttyUSB0``, ``/dev/pts/3``) or any pyserial URL
    (``loop://``, ``socket://host:port``, ``rfc2217://...``).
    """

    def __init__(
        self, url: str, baudrate: int = 9600, timeouts: Timeouts = DEFAULT_TIMEOUTS
    ):
        import serial  # pyserial: imported only when a serial link is used

        self.name = f"serial:{url}"
        try:
            self._port = serial.serial_for_url(
                url, baudrate=baudrate, timeout=timeouts.poll,
                write_timeout=timeouts.connect,
            )  # fmt: skip
        except (serial.SerialException, OSError, ValueError) as exc:
            raise ConnectionError(f"cannot open {self.name}: {exc}") from exc
        self._serial_error = serial.SerialException
        self._wlock = threading.Lock()

    def write(self, data: bytes) -> None:  # noqa: D102
        with self._wlock:
            try:
                self._port.write(data)
            except (self._serial_error, OSError, TypeError) as exc:
                raise LinkClosed(f"{self.name}: write failed: {exc}") from exc

    def read(self, timeout: float) -> bytes:  # noqa: D102
        try:
            self._port.timeout = max(0.0, timeout)
            first = self._port.read(1)
            if not first:
                return b""
            more = self._port.in_waiting
            return first + (self._port.read(more) if more else b"")
        except (self._serial_error, OSError, TypeError, AttributeError) as exc:
            raise LinkClosed(f"{self.name}: read failed: {exc}") from exc

    def reset_input(self) -> None:  # noqa: D102
        try:
            self._port.reset_input_buffer()
        except (self._serial_error, OSError):
            pass

    def close(self) -> None:  # noqa: D102
        try:
            self._port.close()
        except (self._serial_error, OSError):
            pass


class FdTransport(Transport):
    """A raw file descriptor (the master side of a pseudo-terminal), non-blocking.

    Writes that would block are dropped, as bytes on a serial line with
    nobody listening are lost.
    """

    def __init__(self, fd: int, name: str = "fd"):
        self.fd = fd
        self.name = name
        os.set_blocking(fd, False)
        self._closed = False

    def write(self, data: bytes) -> None:  # noqa: D102
        if self._closed:
            raise LinkClosed(f"{self.name} is closed")
        try:
            os.write(self.fd, data)
        except BlockingIOError:
            pass
        except OSError as exc:
            raise LinkClosed(f"{self.name}: write failed: {exc}") from exc

    def read(self, timeout: float) -> bytes:  # noqa: D102
        if self._closed:
            raise LinkClosed(f"{self.name} is closed")
        try:
            ready, _, _ = select.select([self.fd], [], [], max(0.0, timeout))
            return os.read(self.fd, 4096) if ready else b""
        except BlockingIOError:
            return b""
        except OSError as exc:
            raise LinkClosed(f"{self.name}: read failed: {exc}") from exc

    def fileno(self) -> int:
        """Return the descriptor, for ``select``."""
        return self.fd

    def close(self) -> None:  # noqa: D102
        if not self._closed:
            self._closed = True
            try:
                os.close(self.fd)
            except OSError:
                pass


class MemoryTransport(Transport):
    """One end of an in-memory link (see `memory_pair`), for tests."""

    def __init__(self, name: str = "memory"):
        self.name = name
        self._inbox: deque[bytes] = deque()
        self._cond = threading.Condition()
        self._closed = False
        self.peer: MemoryTransport | None = None

    def _deliver(self, data: bytes) -> None:
        with self._cond:
            self._inbox.append(bytes(data))
            self._cond.notify_all()

    def _peer_closed(self) -> None:
        with self._cond:
            self._closed = True
            self._cond.notify_all()

    def write(self, data: bytes) -> None:  # noqa: D102
        if self._closed or self.peer is None:
            raise LinkClosed(f"{self.name} is closed")
        self.peer._deliver(data)

    def read(self, timeout: float) -> bytes:  # noqa: D102
        with self._cond:
            if not self._inbox and not self._closed:
                self._cond.wait(max(0.0, timeout))
            if self._inbox:
                data = b"".join(self._inbox)
                self._inbox.clear()
                return data
            if self._closed:
                raise LinkClosed(f"{self.name} is closed")
            return b""

    def reset_input(self) -> None:  # noqa: D102
        with self._cond:
            self._inbox.clear()

    def close(self) -> None:  # noqa: D102
        self._peer_closed()
        if self.peer is not None:
            self.peer._peer_closed()


def memory_pair() -> tuple[MemoryTransport, MemoryTransport]:
    """Two connected in-memory transports: what one writes, the other reads."""
    a, b = MemoryTransport("memory-a"), MemoryTransport("memory-b")
    a.peer, b.peer = b, a
    return a, b


def open_transport(
    address: str, timeouts: Timeouts = DEFAULT_TIMEOUTS, baudrate: int = 9600
) -> Transport:
    """Open a transport from a robot address.

    Parameters
    ----------
    address : str
        ``tcp://HOST:PORT`` (port 8101 if left out; port 0 is an error), ``serial:///dev/ttyS0``
        (a device path), or ``serial:URL`` with any pyserial URL
        (``serial:loop://``, ``serial:socket://127.0.0.1:9000``).
    timeouts : Timeouts
    baudrate : int
        Serial speed (a Pioneer listens at 9600 baud when it starts).
    """
    scheme, _, rest = address.partition(":")
    if scheme == "tcp":
        parts = urlsplit(address)
        if not parts.hostname:
            raise ValueError(f"robot address {address!r} has no host")
        try:
            port = parts.port
        except ValueError:
            raise ValueError(f"robot address {address!r}: bad port") from None
        if port == 0:
            raise ValueError(
                f"robot address {address!r}: port 0 is not a robot's port "
                f"(leave it out for {DEFAULT_PORT})"
            )
        return TcpTransport(
            parts.hostname, DEFAULT_PORT if port is None else port, timeouts
        )
    if scheme == "serial":
        url = rest[2:] if rest.startswith("//") else rest
        if not url:
            raise ValueError(f"robot address {address!r} has no device")
        return SerialTransport(url, baudrate, timeouts)
    raise ValueError(f"not a Pioneer address: {address!r} (tcp://... or serial:...)")
