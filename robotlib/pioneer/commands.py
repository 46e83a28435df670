"""Pioneer command numbers and their arguments, with the one SI <-> wire conversion.

Client code names commands and gives SI values (``encode_si("MOVE", 0.5)``);
the server turns a received packet back into a name and an SI value
(``decode_si(packet)``). Millimetres and degrees exist only in this module's
`SI_SCALE` table (and in `robotlib.pioneer.sip` for the SIP).
"""

from __future__ import annotations

import math
import struct
from enum import IntEnum
from typing import NamedTuple

from .packets import (
    Packet,
    PacketError,
    decode_arg,
    encode_int_arg,
    encode_str_arg,
    frame,
)

__all__ = [
    "Command",
    "SI_SCALE",
    "VEL2_DIVISOR",
    "command",
    "encode_si",
    "decode_si",
    "SiCommand",
    "vel2_arg",
    "vel2_split",
    "sim_set_pose",
]


class Command(IntEnum):
    """Command numbers (ARCOS / P2OS / MobileSim)."""

    PULSE = 0
    OPEN = 1
    CLOSE = 2
    POLLING = 3
    ENABLE = 4
    SETA = 5
    SETV = 6
    SETO = 7
    MOVE = 8
    ROTATE = 9
    SETRV = 10
    VEL = 11
    HEAD = 12
    DHEAD = 13
    SAY = 15
    CONFIG = 18
    ENCODER = 19
    RVEL = 21
    SETRA = 23
    SONAR = 28
    STOP = 29
    VEL2 = 32
    HOSTBAUD = 50
    ESTOP = 55
    SIM_SET_POSE = 224
    SIM_RESET = 225
    SIM_STEP = 250
    """robotlib's own (not ARCOS or MobileSim): a lock-step server's next cycle."""


SYNC0, SYNC1, SYNC2 = 0, 1, 2
"""Ids of the three sync packets (the same numbers as PULSE, OPEN, CLOSE)."""

_MM = 1000.0
_DEG = 180.0 / math.pi

SI_SCALE: dict[str, float] = {
    "MOVE": _MM,  # m -> mm
    "VEL": _MM,  # m/s -> mm/s
    "SETV": _MM,  # m/s -> mm/s
    "SETA": _MM,  # m/s^2 -> mm/s^2 (negative: deceleration)
    "HEAD": _DEG,  # rad -> deg (absolute, odometry frame; sent as 0-359)
    "DHEAD": _DEG,  # rad -> deg
    "RVEL": _DEG,  # rad/s -> deg/s
    "ROTATE": _DEG,  # rad/s -> deg/s
    "SETRV": _DEG,  # rad/s -> deg/s
    "SETRA": _DEG,  # rad/s^2 -> deg/s^2
}
"""Factor from the SI value of each scaled command to its integer wire argument."""

VEL2_DIVISOR = 20.0
"""VEL2 wheel-speed unit on a Pioneer 3-DX, mm/s."""

_FLAGS = {"ENABLE", "SONAR", "OPEN", "CLOSE", "CONFIG"}
_BARE = {"PULSE", "SETO", "STOP", "ESTOP", "SIM_RESET", "SIM_STEP"}


def command(number: int, arg: int | bytes | str | None = None) -> bytes:
    """Frame command ``number`` with an optional integer or string argument."""
    if arg is None:
        data = b""
    elif isinstance(arg, bytes | str):
        data = encode_str_arg(arg)
    else:
        data = encode_int_arg(int(arg))
    return frame(int(number), data)


def _to_int(name: str, value: float, scale: float) -> int:
    x = float(value) * scale
    if not math.isfinite(x):
        raise ValueError(f"{name}: argument {value!r} is not finite")
    n = int(math.floor(x + 0.5))
    if abs(n) > 0x7FFF:
        raise ValueError(f"{name}: argument {value!r} is out of the protocol's range")
    return n


def vel2_arg(left: float, right: float, divisor: float = VEL2_DIVISOR) -> int:
    """Pack wheel speeds (m/s) into VEL2's argument: left in the high byte.

    Each wheel is a signed byte in units of ``divisor`` mm/s, clipped to
    [-128, 127]. The result is the signed 16-bit value ARIA's ``com2Bytes``
    sends.
    """
    parts = []
    for side, v in (("left", left), ("right", right)):
        units = float(v) * _MM / divisor
        if not math.isfinite(units):
            raise ValueError(f"VEL2: {side} wheel speed {v!r} is not finite")
        parts.append(max(-128, min(127, int(math.floor(units + 0.5)))))
    word = ((parts[0] & 0xFF) << 8) | (parts[1] & 0xFF)
    return word - 0x10000 if word >= 0x8000 else word


def vel2_split(arg: int, divisor: float = VEL2_DIVISOR) -> tuple[float, float]:
    """Unpack VEL2's argument into ``(left, right)`` wheel speeds, m/s."""
    word = int(arg) & 0xFFFF
    left, right = struct.unpack("bb", bytes((word >> 8, word & 0xFF)))
    return left * divisor / _MM, right * divisor / _MM


def sim_set_pose(x: float, y: float, theta: float) -> bytes:
    """Frame MobileSim's SIM_SET_POSE: an ignored type byte, int32 x, y mm, th deg."""
    vals = [_to_int("SIM_SET_POSE", x, _MM), _to_int("SIM_SET_POSE", y, _MM)]
    vals.append(int(math.floor(math.degrees(float(theta)) + 0.5)))
    return frame(Command.SIM_SET_POSE, b"\x00" + struct.pack("<3i", *vals))


def encode_si(name: str, value=None, vel2_divisor: float = VEL2_DIVISOR) -> bytes:
    """Frame the command ``name`` with its SI ``value``.

    Parameters
    ----------
    name : str
        A `Command` name. Scaled ones (see `SI_SCALE`) take SI values: MOVE m,
        HEAD / DHEAD rad, VEL / SETV m/s, SETA m/s^2, RVEL / ROTATE / SETRV
        rad/s, SETRA rad/s^2. ENABLE, SONAR, OPEN, CLOSE, CONFIG take a flag
        (default 1). VEL2 takes ``(left, right)`` m/s. SIM_SET_POSE takes
        ``(x, y, theta)`` m, m, rad. PULSE, SETO, STOP, ESTOP, SIM_RESET,
        SIM_STEP take nothing.
    value : float, bool, tuple or None
    vel2_divisor : float
        VEL2 wheel-speed unit, mm/s.

    Returns
    -------
    bytes
        The complete packet.
    """
    name = name.upper()
    if name not in Command.__members__:
        raise ValueError(f"unknown Pioneer command {name!r}")
    number = Command[name]
    if name in SI_SCALE:
        if value is None:
            raise ValueError(f"{name} needs a value")
        if name == "HEAD":  # absolute heading, sent as 0-359 deg as ARCOS documents
            return command(number, _to_int(name, value, SI_SCALE[name]) % 360)
        return command(number, _to_int(name, value, SI_SCALE[name]))
    if name in _FLAGS:
        return command(number, 1 if value is None else int(bool(value)))
    if name in _BARE:
        return command(number)
    if name == "VEL2":
        left, right = value
        return command(number, vel2_arg(left, right, vel2_divisor))
    if name == "SIM_SET_POSE":
        return sim_set_pose(*value)
    if isinstance(value, bytes | str):
        return command(number, value)
    return command(number, None if value is None else int(value))


class SiCommand(NamedTuple):
    """A received command: its number, name (None if unknown), SI value."""

    number: int
    name: str | None
    value: object


def decode_si(packet: Packet, vel2_divisor: float = VEL2_DIVISOR) -> SiCommand:
    """Decode a command packet into its name and SI value (the inverse of `encode_si`).

    Integer arguments of scaled commands come back in SI units; flags as
    bool; VEL2 as ``(left, right)`` m/s; SIM_SET_POSE as ``(x, y, theta)``;
    unknown commands with their raw argument.

    Raises
    ------
    PacketError
        If the argument is malformed or missing where one is required.
    """
    number = packet.id
    name = Command(number).name if number in Command._value2member_map_ else None
    if name == "SIM_SET_POSE":
        if len(packet.data) < 13:
            raise PacketError("SIM_SET_POSE truncated")
        x, y, th = struct.unpack_from("<3i", packet.data, 1)
        return SiCommand(number, name, (x / _MM, y / _MM, math.radians(th)))
    arg = decode_arg(packet.data)
    if name in SI_SCALE:
        if not isinstance(arg, int):
            raise PacketError(f"{name} needs an integer argument")
        return SiCommand(number, name, arg / SI_SCALE[name])
    if name == "VEL2":
        if not isinstance(arg, int):
            raise PacketError("VEL2 needs an integer argument")
        return SiCommand(number, name, vel2_split(arg, vel2_divisor))
    if name in _FLAGS:
        return SiCommand(number, name, bool(arg) if isinstance(arg, int) else True)
    return SiCommand(number, name, arg)
