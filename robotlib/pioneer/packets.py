"""Pioneer packet framing: the header, the checksum and command arguments.

A packet on the wire is ``0xFA 0xFB | len | id | data... | ck_hi ck_lo``
where ``len`` counts ``id``, ``data`` and the two checksum bytes. These are
pure functions on bytes, used by both the client and the server.
"""

from __future__ import annotations

import struct
from typing import NamedTuple

__all__ = [
    "HEADER",
    "MAX_LENGTH",
    "ARG_INT",
    "ARG_NINT",
    "ARG_STR",
    "Packet",
    "PacketError",
    "PacketDecoder",
    "checksum",
    "frame",
    "unframe",
    "encode_int_arg",
    "encode_str_arg",
    "decode_arg",
    "Reader",
]

HEADER = b"\xfa\xfb"
"""The two sync bytes that start every packet."""
MAX_LENGTH = 249
"""Largest ``len`` byte accepted: id + data + checksum (ARIA uses up to ~200)."""
MIN_LENGTH = 3
"""Smallest ``len``: an id and the two checksum bytes."""

ARG_INT = 0x3B
"""Argument type: a positive integer (uint16 little-endian follows)."""
ARG_NINT = 0x1B
"""Argument type: a negative integer (its magnitude, uint16 LE, follows)."""
ARG_STR = 0x2B
"""Argument type: a string (a length byte, then the bytes)."""


class PacketError(ValueError):
    """A byte string is not a valid Pioneer packet (or packet field)."""


class Packet(NamedTuple):
    """One decoded packet: its id byte and its data bytes (no header, no checksum)."""

    id: int
    data: bytes


def checksum(body: bytes) -> int:
    """Return the Pioneer checksum of ``body`` (the id and data bytes).

    Big-endian 16-bit words are summed modulo 2**16; an odd final byte is
    XOR-ed into the sum.
    """
    n = len(body)
    even = n - (n & 1)
    c = sum(struct.unpack(f">{even // 2}H", body[:even])) & 0xFFFF if even else 0
    if n & 1:
        c ^= body[-1]
    return c


def frame(packet_id: int, data: bytes = b"") -> bytes:
    """Frame ``packet_id`` and ``data`` as a complete packet with its checksum."""
    if not 0 <= packet_id <= 0xFF:
        raise PacketError(f"packet id {packet_id} is not a byte")
    body = bytes((packet_id,)) + bytes(data)
    length = len(body) + 2
    if length > MAX_LENGTH:
        raise PacketError(f"packet body of {len(body)} bytes is too long")
    return HEADER + bytes((length,)) + body + struct.pack(">H", checksum(body))


def unframe(raw: bytes) -> Packet:
    """Decode exactly one complete packet; raise `PacketError` if it is not one."""
    raw = bytes(raw)
    if len(raw) < 2 + 1 + MIN_LENGTH or raw[:2] != HEADER:
        raise PacketError(f"not a packet: {raw[:8].hex(' ')}")
    length = raw[2]
    if length < MIN_LENGTH or length > MAX_LENGTH or len(raw) != 3 + length:
        raise PacketError(f"bad packet length {length} for {len(raw)} bytes")
    body, ck = raw[3:-2], raw[-2:]
    if checksum(body) != int.from_bytes(ck, "big"):
        raise PacketError(f"bad checksum in packet id 0x{body[0]:02x}")
    return Packet(body[0], body[1:])


class PacketDecoder:
    """Split a byte stream into packets, skipping garbage and bad packets.

    Feed it whatever the link delivers; it returns the complete, valid
    packets and keeps any partial one for the next call. A bad length or a
    bad checksum drops only the first header byte and resynchronises on the
    next ``0xFA 0xFB``, so a corrupted packet never hides the ones after it.

    Attributes
    ----------
    skipped : int
        Bytes thrown away so far (garbage, bad packets).
    bad_checksums : int
        Packets rejected for their checksum.
    """

    def __init__(self):
        self._buf = bytearray()
        self.skipped = 0
        self.bad_checksums = 0

    def reset(self) -> None:
        """Forget any partial packet."""
        self.skipped += len(self._buf)
        self._buf.clear()

    def feed(self, data: bytes) -> list[Packet]:
        """Add ``data`` to the stream; return the packets now complete."""
        buf = self._buf
        buf += data
        out: list[Packet] = []
        while True:
            start = buf.find(HEADER)
            if start < 0:
                # keep a trailing 0xFA: it may begin the next header
                keep = 1 if buf[-1:] == HEADER[:1] else 0
                self.skipped += len(buf) - keep
                del buf[: len(buf) - keep]
                return out
            if start:
                self.skipped += start
                del buf[:start]
            if len(buf) < 3:
                return out
            length = buf[2]
            if length < MIN_LENGTH or length > MAX_LENGTH:
                self.skipped += 1
                del buf[:1]
                continue
            if len(buf) < 3 + length:
                return out
            body = bytes(buf[3 : 1 + length])
            ck = (buf[1 + length] << 8) | buf[2 + length]
            if checksum(body) != ck:
                self.bad_checksums += 1
                self.skipped += 1
                del buf[:1]
                continue
            del buf[: 3 + length]
            out.append(Packet(body[0], body[1:]))

    @property
    def pending(self) -> int:
        """Bytes held back as the start of an incomplete packet."""
        return len(self._buf)


def encode_int_arg(value: int) -> bytes:
    """Encode an integer command argument: type byte and uint16 magnitude (LE).

    Raises
    ------
    PacketError
        If ``|value|`` does not fit in 16 bits.
    """
    value = int(value)
    if abs(value) > 0xFFFF:
        raise PacketError(f"integer argument {value} does not fit in 16 bits")
    kind = ARG_INT if value >= 0 else ARG_NINT
    return bytes((kind,)) + struct.pack("<H", abs(value))


def encode_str_arg(text: bytes | str) -> bytes:
    """Encode a string command argument: ``0x2B``, a length byte, the bytes."""
    raw = text.encode("latin-1") if isinstance(text, str) else bytes(text)
    if len(raw) > 200:
        raise PacketError(f"string argument of {len(raw)} bytes is too long")
    return bytes((ARG_STR, len(raw))) + raw


def decode_arg(data: bytes) -> int | bytes | None:
    """Decode a command's argument from its data bytes.

    Returns
    -------
    int, bytes or None
        The signed integer, the string bytes, or None when there is no
        argument (empty data).

    Raises
    ------
    PacketError
        If the type byte is unknown or the argument is truncated.
    """
    if not data:
        return None
    kind = data[0]
    if kind in (ARG_INT, ARG_NINT):
        if len(data) < 3:
            raise PacketError("truncated integer argument")
        mag = data[1] | (data[2] << 8)
        return mag if kind == ARG_INT else -mag
    if kind == ARG_STR:
        if len(data) < 2 or len(data) < 2 + data[1]:
            raise PacketError("truncated string argument")
        return bytes(data[2 : 2 + data[1]])
    raise PacketError(f"unknown argument type 0x{kind:02x}")


class Reader:
    """Read little-endian fields from packet data in order, as ARIA's ``bufTo*`` do.

    Every read raises `PacketError` if the data are exhausted; `remaining`
    tells how many bytes are left (for optional trailing fields).
    """

    _FORMATS = {
        "u8": "<B",
        "i8": "<b",
        "u16": "<H",
        "i16": "<h",
        "u32": "<I",
        "i32": "<i",
    }

    def __init__(self, data: bytes, what: str = "packet"):
        self.data = bytes(data)
        self.pos = 0
        self.what = what

    @property
    def remaining(self) -> int:
        """Bytes not yet read."""
        return len(self.data) - self.pos

    def read(self, kind: str, name: str = "field") -> int:
        """Read one integer field of type ``kind`` (``u8``, ``i16``, ``u32``...)."""
        fmt = self._FORMATS[kind]
        size = struct.calcsize(fmt)
        if self.remaining < size:
            raise PacketError(f"{self.what} truncated at {name} (byte {self.pos})")
        (value,) = struct.unpack_from(fmt, self.data, self.pos)
        self.pos += size
        return value

    def string(self, name: str = "string") -> str:
        """Read a NUL-terminated string (a missing NUL ends it at the data's end)."""
        if self.remaining <= 0:
            raise PacketError(f"{self.what} truncated at {name} (byte {self.pos})")
        end = self.data.find(b"\0", self.pos)
        if end < 0:
            end = len(self.data)
        text = self.data[self.pos : end].decode("latin-1")
        self.pos = min(end + 1, len(self.data))
        return text
