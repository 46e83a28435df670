import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

import robotlib
from robotlib import (
    disconnect,
    isheadingdone,
    ismovedone,
    load_world,
    move,
    readsonar,
    robot,
    setdeltaheading,
)
from robotlib.p3dx import ROBOT_RADIUS
from robotlib.sensing import SonarModel, expected_ranges
from robotlib.sim import OdometryNoise, SimRobot, Simulator
from robotlib.world import World
from robotlib.world.geometry import wrap_angle

ROOM = World(
    [[0, 0, 10, 0], [10, 0, 10, 6], [10, 6, 0, 6], [0, 6, 0, 0]], start=(3, 3, 0)
)


def paper_example(r):
    """The paper's Table-1 loop; returns the number of polls."""
    polls = 0
    for _ in range(10):
        move(r, 0.5)
        while not ismovedone(r):
            polls += 1
        setdeltaheading(r, math.pi)
        while not isheadingdone(r):
            polls += 1
    return polls


def test_paper_example_runs_in_the_corridor_and_returns_home():
    r = robot("sim:corridor", seed=0)
    start = r.true_pose()
    polls = paper_example(r)
    sonar = readsonar(r)
    end_true, end_odo = r.true_pose(), r.pose()
    disconnect(r)
    assert 100 < polls < 2000
    # Forth and back five times: the truth ends near the start ...
    assert math.hypot(*(end_true[:2] - start[:2])) < 0.5
    # ... and the odometry, which started at the true start pose, has drifted.
    assert 0 < math.hypot(*(end_odo[:2] - end_true[:2])) < 0.5
    assert end_odo[2] != end_true[2]
    assert sonar.shape == (8,) and np.all((sonar >= 0.1) & (sonar <= 5.0))


def test_heading_drift_matches_the_odometry_error_model():
    # Ten half turns and 5 m of travel: the heading error's variance is the sum
    # of the model's per-cycle variances, rot_per_rad^2 |dtheta| + rot_per_m^2 |ds|.
    model = OdometryNoise()
    errors = []
    for seed in range(60):
        r = SimRobot(Simulator(ROOM, seed=seed, odometry=model))
        paper_example(r)
        errors.append(wrap_angle(r.pose()[2] - r.true_pose()[2]))
    total_turn = 10 * math.pi
    expected_var = model.rot_per_rad**2 * total_turn + model.rot_per_m**2 * 5.0
    ratio = np.var(errors) / expected_var
    assert 0.6 < ratio < 1.6, ratio


def test_perfect_odometry_tracks_the_truth_exactly():
    r = SimRobot(Simulator(ROOM, seed=1, odometry=OdometryNoise.none()))
    paper_example(r)
    np.testing.assert_allclose(r.pose(), r.true_pose(), atol=1e-12)


def test_same_seed_same_run_bit_for_bit():
    def run(seed):
        r = robot("sim:corridor", seed=seed)
        log = []
        for _ in range(3):
            move(r, 1.0)
            while not ismovedone(r):
                log.append(np.concatenate([r.true_pose(), r.state.pose, r.state.sonar]))
            setdeltaheading(r, 1.0)
            while not isheadingdone(r):
                log.append(np.concatenate([r.true_pose(), r.state.pose, r.state.sonar]))
        return np.array(log)

    a, b, c = run(5), run(5), run(6)
    np.testing.assert_array_equal(a, b)
    assert a.shape != c.shape or not np.array_equal(a, c)


def test_move_and_heading_finish_within_arias_tolerances():
    r = SimRobot(Simulator(ROOM, seed=2))
    start = r.pose()
    r.move(1.2)
    r.wait_move_done()
    assert abs(math.hypot(*(r.pose()[:2] - start[:2])) - 1.2) < 0.040
    r.setheading(math.radians(135))
    r.wait_heading_done()
    assert abs(wrap_angle(r.pose()[2] - math.radians(135))) < math.radians(3)
    r.move(-0.5)
    before = r.pose()
    r.wait_move_done()
    back = r.pose()[:2] - before[:2]
    # Backwards: against the heading.
    assert back @ [math.cos(before[2]), math.sin(before[2])] < 0


def test_velocity_commands_respect_limits_and_accelerations():
    sim = Simulator(ROOM, seed=3, odometry=OdometryNoise.none())
    body = sim.add_robot((2, 3, 0))
    body.command("SETV", 0.4)
    body.command("VEL", 2.0)
    speeds = []
    for _ in range(20):
        sim.step()
        speeds.append(body.state.velocity[0])
    assert max(speeds) == pytest.approx(0.4)
    assert np.all(np.diff(speeds) <= 0.3 * 0.1 + 1e-12)  # default 0.3 m/s^2
    body.command("RVEL", -0.5)
    for _ in range(30):
        sim.step()
    assert body.state.velocity[1] == pytest.approx(-0.5)
    body.command("STOP")
    for _ in range(40):
        sim.step()
    assert body.state.velocity == (0.0, 0.0) and not body.moving


def test_vel2_drives_the_wheels():
    sim = Simulator(ROOM, seed=3, odometry=OdometryNoise.none())
    body = sim.add_robot((5, 3, 0))
    body.command("VEL2", (0.1, 0.3))
    for _ in range(30):
        sim.step()
    v, w = body.state.velocity
    assert v == pytest.approx(0.2)
    assert w == pytest.approx(0.2 / robotlib.p3dx.AXLE_TRACK)


def test_walls_stop_the_robot_and_set_the_stall_flag():
    sim = Simulator(ROOM, seed=4)
    body = sim.add_robot((8, 3, 0))
    body.command("VEL", 0.7)
    for _ in range(60):
        sim.step()
        assert ROOM.distance_to_walls(body.true_pose[:2]) > ROBOT_RADIUS
    assert body.stalled
    assert body.state.stalled
    assert 10 - body.true_pose[0] < ROBOT_RADIUS + 0.02  # pushed up to the wall
    body.command("VEL", -0.3)
    for _ in range(10):
        sim.step()
    assert not body.stalled


@settings(max_examples=15, deadline=None)
@given(
    st.lists(
        st.tuples(
            st.sampled_from(["VEL", "RVEL", "MOVE", "DHEAD"]), st.floats(-2.0, 2.0)
        ),
        min_size=1,
        max_size=6,
    ),
    st.integers(0, 2**16),
)
# hypothesis found this one: 0.2502 m from a wall, in a 5 cm cell whose centre
# is nearer (so not "free"), which the test once took for a wall crossed
@example([("VEL", 1.0), ("DHEAD", 1.78125), ("RVEL", -0.875), ("VEL", 0.0)], 4787)
def test_no_command_sequence_passes_through_a_wall(commands, seed):
    world = load_world("maze")
    sim = Simulator(world, seed=seed)
    body = sim.add_robot()
    body.command("SETV", 2.2)
    body.command("SETA", 5.0)
    last = body.true_pose[:2].copy()
    for name, value in commands:
        body.command(name, value)
        for _ in range(15):
            sim.step()
            here = body.true_pose[:2].copy()
            assert world.distance_to_walls(here) > ROBOT_RADIUS
            # both ends more than a radius from every wall: a step that crossed
            # one would be longer than two radii
            assert math.hypot(*(here - last)) <= 2 * ROBOT_RADIUS
            last = here


def test_two_robots_see_and_block_each_other():
    sim = Simulator(ROOM, seed=5, sonar=SonarModel().ideal())
    a = sim.add_robot((3, 3, 0))
    b = sim.add_robot((6, 3, math.pi))
    sim.step()
    # a's forward sonars see b's body, well before the far wall.
    assert a.state.sonar[3] < 2.7
    a.command("VEL", 0.5)
    for _ in range(80):
        sim.step()
        assert math.hypot(*(a.true_pose[:2] - b.true_pose[:2])) > 2 * ROBOT_RADIUS
    assert a.stalled and not b.stalled
    with pytest.raises(ValueError, match="overlap"):
        sim.add_robot(b.true_pose)


def test_readsonar_matches_a_ray_cast_check():
    ideal = SonarModel().ideal()
    r = SimRobot(Simulator(load_world("corridor"), seed=6, sonar=ideal))
    r.move(2.0)
    r.wait_move_done()
    z = r.readsonar()
    np.testing.assert_allclose(
        z, expected_ranges(r.simulator.world, r.true_pose(), ideal)[0]
    )
    noisy = SimRobot(Simulator(load_world("corridor"), seed=6))
    for _ in range(20):
        z = noisy.readsonar()
        exact = expected_ranges(noisy.simulator.world, noisy.true_pose())[0]
        echo = exact < 5.0
        # An echo reads within 5 sigma of the truth, unless it dropped out.
        ok = np.isclose(z, exact, rtol=5 * 0.01) | (z == 5.0)
        assert np.all(ok[echo])
        assert np.all((z >= 0.1) & (z <= 5.0))


def test_sonar_and_motors_can_be_switched_off():
    sim = Simulator(ROOM, seed=7)
    body = sim.add_robot()
    body.enable_sonar(False)
    body.enable_motors(False)
    body.command("VEL", 0.5)
    for _ in range(10):
        sim.step()
    np.testing.assert_array_equal(body.state.sonar, 5.0)
    np.testing.assert_array_equal(body.true_pose, ROOM.start)
    body.enable_motors(True)
    body.enable_sonar(True)
    for _ in range(10):
        sim.step()
    assert body.true_pose[0] > ROOM.start[0] and body.state.sonar.min() < 5.0


def test_odometry_reset_set_pose_and_simulator_reset():
    sim = Simulator(ROOM, seed=8)
    body = sim.add_robot()
    body.command("VEL", 0.3)
    for _ in range(10):
        sim.step()
    body.reset_odometry()
    np.testing.assert_array_equal(body.state.pose, 0.0)
    body.set_true_pose((5, 5, 4.0))
    assert body.true_pose[2] == pytest.approx(4.0 - 2 * math.pi)
    sim.reset()
    assert sim.time == 0.0
    np.testing.assert_array_equal(body.true_pose, ROOM.start)
    np.testing.assert_array_equal(body.state.pose, ROOM.start)


def test_unknown_commands_addresses_and_worlds_are_clear_errors():
    sim = Simulator(ROOM)
    body = sim.add_robot()
    with pytest.raises(ValueError, match="unknown command"):
        body.command("JUMP", 1.0)
    with pytest.raises(ValueError, match="unknown robot address"):
        robot("carrier-pigeon:1")
    with pytest.raises(FileNotFoundError, match="no world named"):
        robot("sim:atlantis")


def test_disconnect_is_idempotent_and_final():
    with robot("sim:arena", seed=0) as r:
        r.setvel(0.2)
        r.pose()
    r.disconnect()
    with pytest.raises(RuntimeError, match="disconnected"):
        r.readsonar()
