"""The server information packet (SIP), the config packet and the sync reply.

Raw packets hold protocol integers exactly as on the wire (`RawSip`);
`ConvFactors` and the functions `sip_to_si` / `sip_from_si` are the one place
where they become SI units (m, rad, s) and back. `Odometry` unwraps the
15-bit x and y positions into a continuous pose, as ARIA does.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass, field

import numpy as np

from ..world.geometry import wrap_angle
from .packets import PacketError, Reader, frame

__all__ = [
    "SIP_ID",
    "SIP_MOVING_ID",
    "CONFIG_ID",
    "ConvFactors",
    "factors_for",
    "RawSip",
    "decode_sip",
    "encode_sip",
    "SiSip",
    "sip_to_si",
    "sip_from_si",
    "Odometry",
    "CONFIG_FIELDS",
    "default_config",
    "encode_config",
    "decode_config",
    "encode_sync2_reply",
    "decode_sync2_reply",
    "NO_ECHO",
]

SIP_ID = 0x32
"""Id of a SIP while the robot is stopped."""
SIP_MOVING_ID = 0x33
"""Id of a SIP while the robot is moving."""
CONFIG_ID = 0x20
"""Id of the config packet (the reply to CONFIG 1)."""
NO_ECHO = 5000
"""Sonar range (mm) that means "no echo"."""


@dataclass(frozen=True)
class ConvFactors:
    """Conversion factors from SIP integers to mm, rad, mm/s (ARIA's robot parameters).

    Attributes
    ----------
    dist : float
        DistConvFactor: mm per position unit.
    angle : float
        AngleConvFactor: rad per heading unit.
    vel : float
        VelConvFactor: mm/s per wheel-velocity unit.
    range : float
        RangeConvFactor: mm per sonar-range unit.
    diff : float
        DiffConvFactor: rad/s of rotation per mm/s of half the wheel-speed
        difference.
    vel2_divisor : float
        VEL2 wheel-speed unit, mm/s.
    """

    dist: float = 1.0
    angle: float = 0.001534
    vel: float = 1.0
    range: float = 1.0
    diff: float = 0.0056
    vel2_divisor: float = 20.0


_FACTORS = {
    "p3dx": ConvFactors(dist=0.485),
    "p3dx-sh": ConvFactors(dist=1.0),
    "p3at": ConvFactors(dist=0.465, diff=0.0034),
    "p3at-sh": ConvFactors(dist=1.0, diff=0.0034),
}


def factors_for(subclass: str) -> ConvFactors:
    """Return the conversion factors for a robot subclass (from the SYNC2 reply).

    ``p3dx`` uses DistConvFactor 0.485; ``p3dx-sh`` (and any ``*-sh*`` or
    unknown subclass, as ARIA's generic robot) 1.0.
    """
    key = subclass.strip().lower()
    if key in _FACTORS:
        return _FACTORS[key]
    for base in ("p3dx-sh", "p3at-sh"):
        if key.startswith(base):
            return _FACTORS[base]
    return ConvFactors()


# -- the SIP, raw ---------------------------------------------------------
_TAIL = (
    ("io_port", "u16"),  # gripper state (low byte), selected analog port
    ("analog", "u8"),
    ("digin", "u8"),
    ("digout", "u8"),
    ("battery_x10", "u16"),
    ("charge_state", "u8"),
    ("rotvel_x10", "i16"),  # deg/s * 10
    ("fault_flags", "u16"),
    ("latvel", "i16"),
    ("temperature", "i8"),
    ("state_of_charge", "i8"),
    ("uc_time", "u32"),
    ("flags3", "u32"),
)
_FMT = {"u8": "B", "i8": "b", "u16": "H", "i16": "h", "u32": "I"}


@dataclass(frozen=True)
class RawSip:
    """A SIP's fields as protocol integers, in wire order.

    ``x`` and ``y`` keep only their 15 low bits on the wire. ``sonar`` is a
    tuple of ``(index, range)`` pairs. The optional tail fields are None when
    the packet ends before them.
    """

    x: int = 0
    y: int = 0
    th: int = 0
    left_vel: int = 0
    right_vel: int = 0
    battery: int = 130
    stall_bumpers: int = 0
    control: int = 0
    flags: int = 0
    compass: int = 0
    sonar: tuple[tuple[int, int], ...] = ()
    io_port: int | None = None
    analog: int | None = None
    digin: int | None = None
    digout: int | None = None
    battery_x10: int | None = None
    charge_state: int | None = None
    rotvel_x10: int | None = None
    fault_flags: int | None = None
    latvel: int | None = None
    temperature: int | None = None
    state_of_charge: int | None = None
    uc_time: int | None = None
    flags3: int | None = None
    moving: bool = field(default=False, compare=False)


def decode_sip(data: bytes, moving: bool = False) -> RawSip:
    """Decode a SIP's data bytes (after the id) into a `RawSip`.

    The optional tail is read field by field only while bytes remain.

    Raises
    ------
    PacketError
        If the fixed part or a sonar pair is truncated.
    """
    r = Reader(data, "SIP")
    x = r.read("u16", "x") & 0x7FFF
    y = r.read("u16", "y") & 0x7FFF
    th = r.read("i16", "theta")
    lv = r.read("i16", "left velocity")
    rv = r.read("i16", "right velocity")
    battery = r.read("u8", "battery")
    stall = r.read("u16", "stall/bumpers")
    control = r.read("i16", "control")
    flags = r.read("u16", "flags")
    compass = r.read("u8", "compass")
    n = r.read("u8", "sonar count")
    sonar = tuple(
        (r.read("u8", f"sonar index {i}"), r.read("u16", f"sonar range {i}"))
        for i in range(n)
    )
    tail = {}
    for name, kind in _TAIL:
        if r.remaining < struct.calcsize(_FMT[kind]):
            break
        tail[name] = r.read(kind, name)
    return RawSip(
        x, y, th, lv, rv, battery, stall, control, flags, compass, sonar,
        **tail, moving=moving,
    )  # fmt: skip


def encode_sip(sip: RawSip) -> bytes:
    """Frame a `RawSip` as a complete packet (id 0x33 if moving, else 0x32).

    Tail fields are written in order up to the first one that is None.
    """
    if len(sip.sonar) > 0xFF:
        raise PacketError("too many sonar readings for one SIP")
    head = struct.pack(
        "<HHhhhBHhHBB",
        sip.x & 0x7FFF,
        sip.y & 0x7FFF,
        sip.th,
        sip.left_vel,
        sip.right_vel,
        sip.battery,
        sip.stall_bumpers,
        sip.control,
        sip.flags,
        sip.compass,
        len(sip.sonar),
    )
    parts = [head] + [struct.pack("<BH", i, rng) for i, rng in sip.sonar]
    for name, kind in _TAIL:
        value = getattr(sip, name)
        if value is None:
            break
        parts.append(struct.pack("<" + _FMT[kind], value))
    return frame(SIP_MOVING_ID if sip.moving else SIP_ID, b"".join(parts))


# -- SI conversion -----------------------------------------------------------
@dataclass(frozen=True)
class SiSip:
    """A SIP in SI units (the pose still as sent: 15-bit x, y not unwrapped).

    Attributes
    ----------
    x_raw, y_raw : int
        The 15-bit positions, for `Odometry`.
    theta : float
        Heading, rad, wrapped to (-pi, pi].
    v, w : float
        Translational (m/s) and rotational (rad/s) velocity.
    left, right : float
        Wheel speeds, m/s.
    sonar : dict
        Sonar index to range, m, for the readings in this packet.
    stalled, motors_enabled, sonar_enabled : bool
    battery : float
        Battery voltage, V.
    """

    x_raw: int
    y_raw: int
    theta: float
    v: float
    w: float
    left: float
    right: float
    sonar: dict
    stalled: bool
    motors_enabled: bool
    sonar_enabled: bool
    battery: float
    bumpers: int
    flags: int


def sip_to_si(sip: RawSip, f: ConvFactors) -> SiSip:
    """Convert a `RawSip` to SI units with the robot's conversion factors."""
    left = sip.left_vel * f.vel / 1000.0
    right = sip.right_vel * f.vel / 1000.0
    if sip.rotvel_x10 is not None:
        w = math.radians(sip.rotvel_x10 / 10.0)
    else:
        w = (sip.right_vel - sip.left_vel) * f.vel / 2.0 * f.diff
    battery = sip.battery_x10 / 10.0 if sip.battery_x10 else sip.battery / 10.0
    stall = sip.stall_bumpers
    return SiSip(
        x_raw=sip.x,
        y_raw=sip.y,
        theta=float(wrap_angle(sip.th * f.angle)),
        v=(left + right) / 2.0,
        w=w,
        left=left,
        right=right,
        sonar={i: rng * f.range / 1000.0 for i, rng in sip.sonar},
        stalled=bool(stall & 0x0001 or stall & 0x0100),
        motors_enabled=bool(sip.flags & 0x0001),
        sonar_enabled=bool(sip.flags & 0x001E),
        battery=battery,
        bumpers=((stall >> 1) & 0x7F) | (((stall >> 9) & 0x7F) << 7),
        flags=sip.flags,
    )


def _round(x: float) -> int:
    return int(math.floor(x + 0.5))


def sip_from_si(
    pose,
    v: float,
    w: float,
    sonar=(),
    *,
    stalled: bool = False,
    motors_enabled: bool = True,
    sonar_enabled: bool = True,
    moving: bool | None = None,
    battery: float = 13.0,
    factors: ConvFactors = ConvFactors(),
) -> RawSip:
    """Build a `RawSip` from an odometry pose and velocities in SI units.

    Parameters
    ----------
    pose : array_like, shape (3,)
        Odometry ``(x, y, theta)``, m and rad; x and y are sent modulo the
        15-bit range.
    v, w : float
        Translational (m/s) and rotational (rad/s) velocity.
    sonar : iterable of (int, float)
        ``(index, range m)`` pairs to report; ranges are clipped to 5 m.
    stalled, motors_enabled, sonar_enabled : bool
    moving : bool or None
        Send id 0x33; by default when ``v`` or ``w`` is not zero.
    battery : float
        Volts.
    factors : ConvFactors
    """
    f = factors
    x, y, th = (float(c) for c in pose)
    half = w / f.diff  # mm/s: half the wheel-speed difference
    lv = _clip16(_round((v * 1000.0 - half) / f.vel))
    rv = _clip16(_round((v * 1000.0 + half) / f.vel))
    readings = tuple(
        (int(i), min(NO_ECHO, max(0, _round(r * 1000.0 / f.range)))) for i, r in sonar
    )
    if moving is None:
        moving = abs(v) > 1e-6 or abs(w) > 1e-6
    stall = 0x0101 if stalled else 0
    flags = (0x0001 if motors_enabled else 0) | (0x0002 if sonar_enabled else 0)
    return RawSip(
        x=_round(x * 1000.0 / f.dist) & 0x7FFF,
        y=_round(y * 1000.0 / f.dist) & 0x7FFF,
        th=_clip16(_round(float(wrap_angle(th)) / f.angle)),
        left_vel=lv,
        right_vel=rv,
        battery=max(0, min(255, _round(battery * 10.0))),
        stall_bumpers=stall,
        control=0,
        flags=flags,
        compass=0,
        sonar=readings,
        io_port=0,
        analog=0,
        digin=0,
        digout=0,
        battery_x10=max(0, min(0xFFFF, _round(battery * 10.0))),
        charge_state=0,
        rotvel_x10=_clip16(_round(math.degrees(w) * 10.0)),
        fault_flags=0,
        moving=moving,
    )


def _clip16(n: int) -> int:
    return max(-0x8000, min(0x7FFF, n))


class Odometry:
    """Unwrap the SIP's 15-bit x, y into a continuous odometry pose, in m.

    The first SIP's position is read as a signed 15-bit number (so a robot
    within +-16384 units of the origin, +-7.9 m on a p3dx, is placed
    exactly); later positions add the shortest modular step from the
    previous one, which is ARIA's unwrapping.
    """

    def __init__(self, factors: ConvFactors):
        self.factors = factors
        self._last: tuple[int, int] | None = None
        self._units = [0, 0]

    def reset(self) -> None:
        """Take the next SIP's position as absolute again."""
        self._last = None

    def update(self, x_raw: int, y_raw: int, theta: float) -> np.ndarray:
        """Feed one SIP's raw x, y and its heading (rad); return the pose (3,)."""
        x_raw &= 0x7FFF
        y_raw &= 0x7FFF
        if self._last is None:
            self._units = [_signed15(x_raw), _signed15(y_raw)]
        else:
            self._units[0] += _signed15((x_raw - self._last[0]) & 0x7FFF)
            self._units[1] += _signed15((y_raw - self._last[1]) & 0x7FFF)
        self._last = (x_raw, y_raw)
        d = self.factors.dist / 1000.0
        return np.array([self._units[0] * d, self._units[1] * d, theta])


def _signed15(u: int) -> int:
    return u - 0x8000 if u >= 0x4000 else u


# -- config packet -------------------------------------------------------------
CONFIG_FIELDS: tuple[tuple[str, str], ...] = (
    ("type", "str"),
    ("subtype", "str"),
    ("serial", "str"),
    ("four_mots", "u8"),
    ("rot_vel_top", "u16"),
    ("trans_vel_top", "u16"),
    ("rot_accel_top", "u16"),
    ("trans_accel_top", "u16"),
    ("pwm_max", "u16"),
    ("name", "str"),
    ("sip_cycle", "u8"),
    ("host_baud", "u8"),
    ("aux1_baud", "u8"),
    ("has_gripper", "u16"),
    ("front_sonar", "u16"),
    ("rear_sonar", "u8"),
    ("low_battery", "u16"),
    ("rev_count", "u16"),
    ("watchdog", "u16"),
    ("normal_mpacs", "u8"),
    ("stall_val", "u16"),
    ("stall_count", "u16"),
    ("joy_vel", "u16"),
    ("joy_rot_vel", "u16"),
    ("rot_vel_max", "u16"),
    ("trans_vel_max", "u16"),
    ("rot_accel", "u16"),
    ("rot_decel", "u16"),
    ("rot_kp", "u16"),
    ("rot_kv", "u16"),
    ("rot_ki", "u16"),
    ("trans_accel", "u16"),
    ("trans_decel", "u16"),
    ("trans_kp", "u16"),
    ("trans_kv", "u16"),
    ("trans_ki", "u16"),
    ("front_bumps", "u8"),
    ("rear_bumps", "u8"),
    ("has_charger", "u8"),
    ("sonar_cycle", "u8"),
    ("reset_baud", "u8"),
    ("gyro_type", "u8"),
    ("drift_factor", "i16"),
    ("aux2_baud", "u8"),
    ("aux3_baud", "u8"),
    ("ticks_mm", "u16"),
    ("shutdown_voltage", "u16"),
    ("firmware_version", "str"),
    ("gyro_cw", "u16"),
    ("gyro_ccw", "u16"),
    ("kinematics_delay", "u8"),
    ("lat_vel_top", "u16"),
    ("lat_accel_top", "u16"),
    ("lat_vel_max", "u16"),
    ("lat_accel", "u16"),
    ("lat_decel", "u16"),
    ("powerbot_charge_threshold", "u16"),
    ("pdb_port", "u8"),
    ("gyro_rate_limit", "u16"),
    ("high_temperature_shutdown", "i8"),
    ("power_bits", "u16"),
    ("battery_type", "u8"),
    ("state_of_charge_low", "u16"),
    ("state_of_charge_shutdown", "u16"),
    ("firmware_bootloader_version", "str"),
    ("config_flags", "u32"),
    ("gyro_fw_version", "i16"),
)
"""The config packet's fields in the order ARIA's config reader takes them.

Speeds are mm/s and deg/s, accelerations mm/s^2 and deg/s^2 (wire units).
"""


def default_config(**overrides) -> dict:
    """Return a config packet for a simulated p3dx, as MobileSim sends (wire units)."""
    cfg = {name: ("" if kind == "str" else 0) for name, kind in CONFIG_FIELDS}
    cfg.update(
        type="Pioneer",
        subtype="p3dx",
        serial="SIM",
        rot_vel_top=500,
        trans_vel_top=2200,
        rot_accel_top=300,
        trans_accel_top=2000,
        pwm_max=1000,
        name="robotlib",
        sip_cycle=100,
        front_sonar=1,
        low_battery=110,
        rev_count=16570,
        watchdog=5000,
        joy_vel=300,
        joy_rot_vel=50,
        rot_vel_max=100,
        trans_vel_max=750,
        rot_accel=100,
        rot_decel=100,
        rot_kp=40,
        rot_kv=20,
        trans_accel=300,
        trans_decel=300,
        trans_kp=30,
        trans_kv=20,
        front_bumps=5,
        sonar_cycle=40,
        ticks_mm=128,
        shutdown_voltage=105,
        firmware_version="robotlib",
        high_temperature_shutdown=-128,
    )
    unknown = set(overrides) - set(cfg)
    if unknown:
        raise KeyError(f"unknown config fields: {sorted(unknown)}")
    cfg.update(overrides)
    return cfg


def encode_config(cfg: dict) -> bytes:
    """Frame a config packet (id 0x20) from a dict of `CONFIG_FIELDS` values.

    Missing fields are sent as 0 or empty strings.
    """
    parts = []
    for name, kind in CONFIG_FIELDS:
        value = cfg.get(name, "" if kind == "str" else 0)
        if kind == "str":
            parts.append(str(value).encode("latin-1") + b"\0")
        else:
            parts.append(struct.pack("<" + _FMT[kind], int(value)))
    return frame(CONFIG_ID, b"".join(parts))


def decode_config(data: bytes) -> dict:
    """Decode a config packet's data; fields after the data's end are left out."""
    r = Reader(data, "config packet")
    out: dict = {}
    for name, kind in CONFIG_FIELDS:
        if r.remaining <= 0:
            break
        if kind == "str":
            out[name] = r.string(name)
        elif r.remaining < struct.calcsize(_FMT[kind]):
            break
        else:
            out[name] = r.read(kind, name)
    return out


# -- the SYNC2 reply -------------------------------------------------------------
def encode_sync2_reply(name: str, robot_class: str, subclass: str) -> bytes:
    """Frame the reply to SYNC2: three NUL-terminated strings after id 2."""
    data = b"".join(s.encode("latin-1") + b"\0" for s in (name, robot_class, subclass))
    return frame(2, data)


def decode_sync2_reply(data: bytes) -> tuple[str, str, str]:
    """Return ``(name, class, subclass)`` from the SYNC2 reply's data (missing: "")."""
    items = bytes(data).split(b"\0")
    items = [s.decode("latin-1", "replace") for s in items[:3]]
    items += [""] * (3 - len(items))
    return items[0], items[1], items[2]
