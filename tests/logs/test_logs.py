"""Recorded runs: MCAP record and replay, bit for bit; damage; CARMEN logs."""

import bz2
import gzip
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robotlib import robot
from robotlib.localization import MCL
from robotlib.logs import (
    EndOfLog,
    LogError,
    LogRobot,
    ReplayError,
    parse_carmen_line,
    read_log,
    record,
)
from robotlib.world import load_world


def _drive_and_poll(r, legs=3):
    """Drive a few moves and turns; return every polled state and true pose."""
    states, truths = [], []
    for k in range(legs):
        r.move(0.5)
        for _ in range(15):
            states.append(r._poll())
            truths.append(r.true_pose())
        r.setdeltaheading(0.4 if k % 2 else -0.4)
        for _ in range(8):
            states.append(r._poll())
            truths.append(r.true_pose())
    return states, truths


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    path = tmp_path_factory.mktemp("logs") / "run.mcap"
    rec = record(robot("sim:corridor", seed=5), path, seed=5)
    states, truths = _drive_and_poll(rec)
    rec.setvel(0.1)
    rec.stop()
    rec.disconnect()
    return path, states, truths


def test_replay_gives_back_the_same_readings_bit_for_bit(recorded):
    path, states, truths = recorded
    run = read_log(path)
    assert run.error is None
    assert run.metadata["world"] == "corridor" and run.metadata["seed"] == "5"
    got = run.states[1:]  # the first move() polled once before the loop
    assert len(got) == len(states)
    for a, b in zip(states, got, strict=True):
        assert np.array_equal(a.pose, b.pose) and np.array_equal(a.sonar, b.sonar)
        assert (a.time, a.velocity, a.stalled, a.motors_enabled) == (
            b.time,
            b.velocity,
            b.stalled,
            b.motors_enabled,
        )
    assert np.array_equal(np.array(truths), run.true_poses[1:])
    texts = [t for _, t in run.commands]
    assert texts[0] == "MOVE 0.5" and texts[-2:] == ["VEL 0.1", "STOP"]


def test_log_robot_polls_in_order_and_refuses_motion(recorded):
    path, states, _ = recorded
    r = robot(f"log:{path}")
    assert isinstance(r, LogRobot)
    r.pose()
    assert np.array_equal(r.readsonar(), states[0].sonar)
    for name, args in [("move", (1.0,)), ("setheading", (0.0,)), ("setvel", (0.2,))]:
        with pytest.raises(ReplayError, match="recorded run"):
            getattr(r, name)(*args)
    for _ in range(r.remaining):
        r.pose()
    with pytest.raises(EndOfLog, match="end of the recorded run"):
        r.pose()


def test_the_file_opens_with_standard_ros2_decoding(recorded):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    path, states, _ = recorded
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        topics = {c.topic: s.name for _, c in reader.get_summary().channels.items()
                  for s in [reader.get_summary().schemas[c.schema_id]]}  # fmt: skip
        assert topics["/odom"] == "nav_msgs/Odometry"
        assert topics["/sonar"] == "sensor_msgs/PointCloud2"
        odom = [m for _, ch, _, m in reader.iter_decoded_messages(topics=["/odom"])]
    assert len(odom) == len(states) + 1
    o = odom[1]
    theta = 2 * math.atan2(o.pose.pose.orientation.z, o.pose.pose.orientation.w)
    assert o.pose.pose.position.x == states[0].pose[0]
    assert theta == pytest.approx(states[0].pose[2], abs=1e-12)


def test_mcl_on_the_replay_equals_mcl_on_the_live_run(recorded):
    path, states, _ = recorded
    world = load_world("corridor")

    def localize(odometry, sonar):
        mcl = MCL.best(world, rng=3, n=2000)
        out = []
        for k in range(len(odometry)):
            mcl.step(odometry[max(k - 1, 0)], odometry[k], sonar[k])
            out.append(mcl.estimate())
        return np.array(out)

    live = localize([s.pose for s in states], [s.sonar for s in states])
    r = robot(f"log:{path}")
    r.pose()  # the poll before the first move
    replay = [r._poll() for _ in range(len(states))]
    again = localize([s.pose for s in replay], [s.sonar for s in replay])
    assert np.array_equal(live, again)


def test_a_truncated_file_names_itself_and_keeps_what_came_before(recorded, tmp_path):
    path, states, _ = recorded
    big = tmp_path / "big.mcap"
    rec = record(robot("sim:corridor", seed=1), big)
    for _ in range(600):
        rec.pose()
    rec.close()
    data = big.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    run = read_log(cut)
    assert 0 < len(run) < 600
    assert isinstance(run.error, LogError)
    assert str(cut) in str(run.error) and "record" in str(run.error)
    full = read_log(big)
    pairs = zip(run.states, full.states[: len(run)], strict=True)
    assert all(np.array_equal(a.sonar, b.sonar) for a, b in pairs)
    r = LogRobot(run)
    for _ in range(len(run)):
        r.pose()
    with pytest.raises(LogError, match="truncated at record"):
        r.pose()
    (tmp_path / "head.mcap").write_bytes(data[:40])
    with pytest.raises(LogError, match="head.mcap"):
        read_log(tmp_path / "head.mcap")


CARMEN = """\
# a small CARMEN log
ODOM 1.0 2.0 0.5 0.3 0.1 0.0 100.0 host 100.0
FLASER 3 1.5 2.5 3.5 9.0 9.0 0.0 1.0 2.0 0.5 100.1 host 100.1
TRUEPOS 1.1 2.1 0.6 1.0 2.0 0.5 100.15 host 100.15
PARAM robot_width 0.5
ODOM 1.2 2.0 0.5 0.3 0.0 0.0 100.2 host 100.2
SONAR 0.26 2 0.7 4.0 0.1 0.1 0.5 0.1 -0.1 -0.5 100.3 host 100.3
RAWLASER1 0 -1.5708 3.1416 0.0175 80.0 0.01 0 2 4.0 5.0 0 100.4 host 100.4
FLASER 3 1.0 nope
ODOM 9 9 9 9 9 9 101 host 101
"""


def test_carmen_log_replays_up_to_a_bad_line(tmp_path):
    path = tmp_path / "run.log"
    path.write_text(CARMEN)
    run = read_log(path)
    assert len(run) == 3
    a, b, c = run.states
    assert np.array_equal(a.pose, [1.0, 2.0, 0.5]) and a.velocity == (0.3, 0.1)
    assert np.array_equal(a.extra["laser"], [1.5, 2.5, 3.5]) and a.time == 100.1
    assert run.truth[0] is None and np.array_equal(run.truth[1], [1.1, 2.1, 0.6])
    assert np.array_equal(b.sonar, [0.7, 4.0]) and np.array_equal(b.pose, [1.2, 2, 0.5])
    assert np.array_equal(c.extra["laser"], [4.0, 5.0])
    assert c.extra["laser_angles"] == pytest.approx((-1.5708, 1.5708))
    assert "line 9" in str(run.error) and str(path) in str(run.error)
    r = robot(f"log:{path}")
    assert np.array_equal(r.pose(), [1.0, 2.0, 0.5])


@pytest.mark.parametrize(
    "suffix, pack", [(".bz2", bz2.compress), (".gz", gzip.compress)]
)
def test_a_compressed_carmen_log_reads_as_the_plain_one(tmp_path, suffix, pack):
    plain = tmp_path / "run.clf"
    plain.write_text(CARMEN)
    packed = tmp_path / f"run.clf{suffix}"
    packed.write_bytes(pack(CARMEN.encode()))
    a, b = read_log(plain), read_log(packed)
    assert len(b) == len(a) == 3 and "line 9" in str(b.error)
    for s, t in zip(a.states, b.states, strict=True):
        assert np.array_equal(s.pose, t.pose) and s.time == t.time
        assert np.array_equal(s.extra.get("laser", []), t.extra.get("laser", []))
    # a damaged archive (bzip2 decodes by 900 kB blocks: 3 MB of scans):
    # what came before the damage stays, the error says so
    r = np.random.default_rng(0).uniform(0, 8, (30_000, 3))
    good = "".join(f"FLASER 3 {a:.3f} {b:.3f} {c:.3f} 1 2 0 1 2 0 {k} h {k}\n"
                   for k, (a, b, c) in enumerate(r))  # fmt: skip
    data = pack(good.encode())
    cut = tmp_path / f"cut.clf{suffix}"
    cut.write_bytes(data[:-1000])
    run = read_log(cut)
    assert 1000 < len(run) < 30_000 and str(cut) in str(run.error)
    assert np.array_equal(run.states[-1].extra["laser"], r[len(run) - 1].round(3))


@settings(max_examples=50)
@given(
    st.lists(st.floats(0.0, 80.0), min_size=1, max_size=20),
    st.tuples(*[st.floats(-50, 50)] * 3),
    st.floats(0, 1e6),
)
def test_carmen_flaser_line_round_trip(ranges, pose, t):
    nums = " ".join(repr(v) for v in [*ranges, *pose, *pose, t])
    kind, v = parse_carmen_line(f"FLASER {len(ranges)} {nums} host {t!r}")
    assert kind == "FLASER" and v["laser"] == ranges
    assert v["pose"] == list(pose) and v["time"] == t
    with pytest.raises(ValueError):
        parse_carmen_line(f"FLASER {len(ranges) + 30} {nums}")


def test_the_logs_bench_runs(tmp_path):
    from robotlib.experiments.bench_logs import bench_logs

    r = bench_logs(polls=60, folder=tmp_path)
    assert r["polls"] == 60 and r["mcap_bytes"] > r["npz_bytes"] > 0
    assert r["replay_polls_per_s"] > r["read_polls_per_s"] > 0


def test_the_fast_encoders_write_what_mcap_ros2_writes():
    from mcap_ros2._dynamic import serialize_dynamic
    from mcap_ros2.decoder import DecoderFactory  # noqa: F401 - the reader's side

    from robotlib.logs import _cdr
    from robotlib.logs import _messages as m
    from robotlib.p3dx import SONAR_POSES

    def enc(name, msg):
        return bytes(serialize_dynamic(name, m.msgdef(name))[name](msg))

    row = np.random.default_rng(0).normal(size=19)
    label = m.state_msg(row)["layout"]["dim"][0]["label"]
    state = enc("std_msgs/Float64MultiArray", m.state_msg(row))
    assert state == _cdr.encode_state(row, label)
    assert np.array_equal(_cdr.decode_state(state), row)
    pose, vel = (1.0, -2.0, 2.5), (0.3, -0.2)
    assert enc("nav_msgs/Odometry", m.odometry_msg(12.3, pose, vel)) == (
        _cdr.encode_odometry(12.3, pose, vel)
    )
    cloud = m.sonar_cloud_msg(1.5, np.linspace(0.2, 5, 8), SONAR_POSES)
    assert enc("sensor_msgs/PointCloud2", cloud) == _cdr.encode_cloud(
        1.5, cloud["fields"], cloud["data"], 8, 32
    )
    stamped = {"header": m.header(2.5, "map"), "pose": m.pose_msg(pose)}
    assert enc("geometry_msgs/PoseStamped", stamped) == (
        _cdr.encode_pose_stamped(2.5, "map", pose)
    )
    assert enc("std_msgs/String", {"data": "MOVE 0.5"}) == _cdr.encode_string(
        "MOVE 0.5"
    )
    assert enc("geometry_msgs/Twist", m.twist_msg(0.2, 0.1)) == _cdr.encode_twist(
        0.2, 0.1
    )
    scan = m.laser_msg(3.0, [1.0, 2.5, 3.25], -1.5, 1.5, 80.0)
    assert enc("sensor_msgs/LaserScan", scan) == _cdr.encode_laser(
        3.0, [1.0, 2.5, 3.25], -1.5, 1.5, 80.0
    )
