"""SIP, config packet and SYNC2 reply: decoding, encoding, units, 15-bit wrap."""

import math
import struct

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robotlib.pioneer.packets import PacketError, frame, unframe
from robotlib.pioneer.sip import (
    CONFIG_FIELDS,
    ConvFactors,
    Odometry,
    RawSip,
    decode_config,
    decode_sip,
    decode_sync2_reply,
    default_config,
    encode_config,
    encode_sip,
    encode_sync2_reply,
    factors_for,
    sip_from_si,
    sip_to_si,
)

P3DX = factors_for("p3dx")


def sip_bytes(x=0, y=0, th=0, lv=0, rv=0, sonar=(), tail=b""):
    fields = (x, y, th, lv, rv, 121, 0, 0, 0x0003, 0, len(sonar))
    head = struct.pack("<HHhhhBHhHBB", *fields)
    return head + b"".join(struct.pack("<BH", i, r) for i, r in sonar) + tail


def test_conversion_factors_from_subclass():
    assert factors_for("p3dx").dist == 0.485
    assert factors_for("p3dx-sh").dist == 1.0
    assert factors_for("P3DX-SH-LMS").dist == 1.0
    assert factors_for("something-else") == ConvFactors()
    assert P3DX.angle == 0.001534 and P3DX.vel == 1.0 and P3DX.range == 1.0


def test_decode_fixed_part_and_sonar_pairs():
    data = sip_bytes(x=0x8000 | 1000, y=2000, th=1024, lv=100, rv=300,
                     sonar=((0, 1500), (7, 5000), (3, 250)))  # fmt: skip
    sip = decode_sip(data)
    assert sip.x == 1000  # 15 bits kept
    assert sip.y == 2000 and sip.th == 1024
    assert sip.sonar == ((0, 1500), (7, 5000), (3, 250))
    assert sip.io_port is None and sip.rotvel_x10 is None
    si = sip_to_si(sip, P3DX)
    assert si.theta == pytest.approx(1024 * 0.001534)
    assert si.v == pytest.approx(0.2) and si.left == pytest.approx(0.1)
    # no rotvel in the tail: from the wheel speeds with DiffConvFactor
    assert si.w == pytest.approx((300 - 100) / 2 * 0.0056)
    assert si.sonar == {0: 1.5, 7: 5.0, 3: 0.25}
    assert si.motors_enabled and si.sonar_enabled and si.battery == pytest.approx(12.1)


def test_optional_tail_read_only_while_bytes_remain():
    base = sip_bytes(lv=0, rv=0)
    group = struct.pack("<HBBB", 0, 0, 0, 0)
    full = base + group + struct.pack("<HBhH", 127, 1, -355, 0)
    sip = decode_sip(full)
    assert sip.battery_x10 == 127 and sip.rotvel_x10 == -355 and sip.fault_flags == 0
    assert sip_to_si(sip, P3DX).w == pytest.approx(math.radians(-35.5))
    assert sip_to_si(sip, P3DX).battery == pytest.approx(12.7)
    # a tail cut in the middle of a field: the fields before it, no error
    part = decode_sip(base + group + b"\x7f")
    assert part.digout == 0 and part.battery_x10 is None


def test_truncated_fixed_part_is_an_error():
    data = sip_bytes(sonar=((0, 1000), (1, 2000)))
    for n in (0, 5, 20, len(data) - 1):
        with pytest.raises(PacketError):
            decode_sip(data[:n])


def test_stall_and_bumper_bits():
    data = bytearray(sip_bytes())
    struct.pack_into("<H", data, 11, 0x0100 | 0x0004)  # right stalled, bumper bit 2
    si = sip_to_si(decode_sip(bytes(data)), P3DX)
    assert si.stalled and si.bumpers == 0b10


def test_moving_sets_the_packet_id():
    assert unframe(encode_sip(RawSip(moving=True))).id == 0x33
    assert unframe(encode_sip(RawSip())).id == 0x32


raw_sips = st.builds(
    RawSip,
    x=st.integers(0, 0x7FFF),
    y=st.integers(0, 0x7FFF),
    th=st.integers(-2048, 2047),
    left_vel=st.integers(-32768, 32767),
    right_vel=st.integers(-32768, 32767),
    battery=st.integers(0, 255),
    stall_bumpers=st.integers(0, 0xFFFF),
    control=st.integers(-32768, 32767),
    flags=st.integers(0, 0xFFFF),
    compass=st.integers(0, 255),
    sonar=st.lists(
        st.tuples(st.integers(0, 15), st.integers(0, 0xFFFF)), max_size=16
    ).map(tuple),
)


@settings(max_examples=150, deadline=None)
@given(sip=raw_sips, tail=st.integers(0, 13))
def test_raw_sip_round_trip(sip, tail):
    from robotlib.pioneer import sip as sipmod

    values = {name: 1 for name, _ in sipmod._TAIL[:tail]}
    sip = RawSip(**{**sip.__dict__, **values})
    pkt = unframe(encode_sip(sip))
    assert decode_sip(pkt.data) == sip


@settings(max_examples=150, deadline=None)
@given(
    x=st.floats(-7.5, 7.5),
    y=st.floats(-7.5, 7.5),
    th=st.floats(-3.14, 3.14),
    v=st.floats(-2.0, 2.0),
    w=st.floats(-3.0, 3.0),
    ranges=st.lists(st.floats(0.1, 5.0), min_size=8, max_size=8),
    sub=st.sampled_from(["p3dx", "p3dx-sh"]),
)
def test_si_sip_round_trip(x, y, th, v, w, ranges, sub):
    f = factors_for(sub)
    raw = sip_from_si((x, y, th), v, w, enumerate(ranges), factors=f)
    si = sip_to_si(decode_sip(unframe(encode_sip(raw)).data), f)
    pose = Odometry(f).update(si.x_raw, si.y_raw, si.theta)
    assert pose[0] == pytest.approx(x, abs=f.dist / 1000)
    assert pose[1] == pytest.approx(y, abs=f.dist / 1000)
    assert abs(math.remainder(pose[2] - th, 2 * math.pi)) < 0.001
    assert si.v == pytest.approx(v, abs=0.0011)
    assert si.w == pytest.approx(w, abs=math.radians(0.06))
    assert [si.sonar[i] for i in range(8)] == pytest.approx(ranges, abs=0.0006)


def test_odometry_unwraps_the_15_bit_position():
    odo = Odometry(P3DX)
    xs = np.arange(0, 60.0, 0.3)  # 60 m: the 15-bit x (15.9 m on a p3dx) wraps 3 times
    for x in xs:
        raw = sip_from_si((x, -3.0, 0.0), 0.0, 0.0, factors=P3DX)
        pose = odo.update(raw.x, raw.y, 0.0)
    assert pose[0] == pytest.approx(xs[-1], abs=0.001)
    assert pose[1] == pytest.approx(-3.0, abs=0.001)
    # backwards over the wrap as well
    for x in xs[::-1]:
        raw = sip_from_si((x, -3.0, 0.0), 0.0, 0.0, factors=P3DX)
        pose = odo.update(raw.x, raw.y, 0.0)
    assert pose[0] == pytest.approx(0.0, abs=0.001)


def test_config_packet_round_trip_and_field_order():
    cfg = default_config(name="MobileSim", trans_vel_max=1234)
    pkt = unframe(encode_config(cfg))
    assert pkt.id == 0x20
    assert pkt.data.startswith(b"Pioneer\0p3dx\0SIM\0\0")
    # right after the serial number's NUL and the spare byte: RotVelTop, TransVelTop
    assert struct.unpack_from("<HH", pkt.data, 18) == (500, 2200)
    back = decode_config(pkt.data)
    assert back == cfg
    assert [k for k, _ in CONFIG_FIELDS][:3] == ["type", "subtype", "serial"]


def test_short_config_packet_keeps_what_is_there():
    data = unframe(encode_config(default_config())).data
    part = decode_config(data[:30])
    assert part["serial"] == "SIM" and "sip_cycle" not in part


def test_sync2_reply():
    raw = encode_sync2_reply("MobileSim", "Pioneer", "p3dx")
    assert raw == frame(2, b"MobileSim\0Pioneer\0p3dx\0")
    assert decode_sync2_reply(unframe(raw).data) == ("MobileSim", "Pioneer", "p3dx")
    assert decode_sync2_reply(b"OnlyName") == ("OnlyName", "", "")
