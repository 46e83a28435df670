"""Systematic odometry error (Borenstein's Ed, Eb) and UMBmark recovering it."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from robotlib.experiments.umbmark import return_error, umbmark, umbmark_estimate
from robotlib.p3dx import AXLE_TRACK
from robotlib.sim import OdometryNoise, SimRobot, Simulator
from robotlib.world import World

OPEN = World(
    [[-3, -7, 7, -7], [7, -7, 7, 7], [7, 7, -3, 7], [-3, 7, -3, -7]], start=(0, 0, 0)
)


def _drive(odometry, seed=4, cycles=60):
    sim = Simulator(OPEN, seed=seed, odometry=odometry)
    body = sim.add_robot()
    body.command("MOVE", 2.0)
    out = []
    for k in range(cycles):
        if k == 30:
            body.command("DHEAD", 1.0)
        sim.step()
        out.append((body.true_pose.copy(), body.state.pose, body.state.sonar))
    return out


def test_off_by_default_changes_nothing():
    default = _drive(None)
    explicit = _drive(OdometryNoise(ed=1.0, eb=1.0))
    for a, b in zip(default, explicit, strict=True):
        for x, y in zip(a, b, strict=True):
            assert np.array_equal(x, y)
    assert not OdometryNoise().systematic
    assert OdometryNoise().true_increment(0.123, -0.456) == (0.123, -0.456)


def test_unequal_wheels_curve_and_long_track_under_turns():
    bigger_right = _drive(OdometryNoise(0, 0, 0, ed=1.01), cycles=30)
    true, odo, _ = bigger_right[-1]
    assert abs(odo[2]) < 1e-12  # the odometry believes it went straight
    assert true[2] > 0.01  # the right wheel is bigger: the robot curves left
    wide = _drive(OdometryNoise(0, 0, 0, eb=1.05))
    true, odo, _ = wide[-1]
    assert true[2] == pytest.approx(odo[2] / 1.05, abs=1e-9)


@given(
    st.floats(-0.3, 0.3), st.floats(-0.5, 0.5), st.floats(0.9, 1.1), st.floats(0.9, 1.1)
)
def test_true_increment_is_the_wheel_geometry(ds, dth, ed, eb):
    model = OdometryNoise(ed=ed, eb=eb)
    true_ds, true_dth = model.true_increment(ds, dth)
    left = ds - AXLE_TRACK * dth / 2
    right = ds + AXLE_TRACK * dth / 2
    dl, dr = 2 / (ed + 1), 2 * ed / (ed + 1)  # diameters over the nominal one
    assert true_ds == pytest.approx((dl * left + dr * right) / 2, abs=1e-12)
    assert true_dth == pytest.approx(
        (dr * right - dl * left) / (eb * AXLE_TRACK), abs=1e-12
    )


def test_umbmark_recovers_ed_and_eb():
    for ed, eb in [(1.002, 1.01), (0.998, 0.985)]:
        sim = Simulator(OPEN, seed=2, odometry=OdometryNoise(0, 0, 0, ed=ed, eb=eb))
        cw, ccw = umbmark(SimRobot(sim), side=4.0, runs=2)
        ed_hat, eb_hat = umbmark_estimate(cw, ccw, 4.0)
        assert abs(ed_hat - ed) < 0.1 * abs(ed - 1), (ed_hat, ed)
        assert abs(eb_hat - eb) < 0.1 * abs(eb - 1), (eb_hat, eb)


def test_umbmark_estimate_of_no_error_and_return_error_frame():
    assert umbmark_estimate(np.zeros((3, 2)), np.zeros((3, 2)), 4.0) == (1.0, 1.0)
    e = return_error([1, 1, math.pi / 2], [1, 2, 0], [0, 0, 0], [0, 0, 0])
    assert np.allclose(e, [1.0, 0.0])  # 1 m along the first leg (+y in the world)
