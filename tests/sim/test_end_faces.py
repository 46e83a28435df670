"""A wall met end-on echoes from its end face (`World.sensed_obstacles`)."""

import math

import numpy as np
import pytest

from robotlib.sensing import SonarModel
from robotlib.sim import Simulator
from robotlib.world import END_FACE, World

# a closed 10 m x 6 m room with a partition along y = 3 from the east wall to
# x = 5 (its west end free), and one wall across the middle of its south half
ROOM = World(
    [
        [0, 0, 10, 0],
        [10, 0, 10, 6],
        [10, 6, 0, 6],
        [0, 6, 0, 0],
        [5, 3, 10, 3],
        [7, 0, 7, 1.5],
    ],
    start=(2, 2, 0),
)
FRONT = SonarModel(sensors=np.array([[0.0, 0.0, 0.0]]))  # one sonar looking ahead


def test_only_free_ends_get_faces():
    faces = ROOM.sensed_obstacles[len(ROOM.obstacles) :]
    np.testing.assert_allclose(
        faces,
        [
            [5, 3 - END_FACE / 2, 5, 3 + END_FACE / 2],
            [7 + END_FACE / 2, 1.5, 7 - END_FACE / 2, 1.5],
        ],
    )
    assert len(World([[0, 0, 1, 0], [1, 0, 1, 1]]).sensed_obstacles) == 4  # L: 2 ends


@pytest.mark.parametrize("model", [FRONT, FRONT.ideal()])
@pytest.mark.parametrize("end_faces", [True, False])
def test_sonar_pointed_at_a_wall_end_reads_it(model, end_faces):
    sim = Simulator(ROOM, seed=0, sonar=model, end_faces=end_faces)
    body = sim.add_robot((3.0, 3.0, 0.0))  # on the partition's line, 2 m short of it
    readings = []
    for _ in range(20):
        sim.step()
        readings.append(body.state.sonar[0])
    if end_faces:  # the end face 2 m ahead, seen in (nearly) every reading
        assert np.median(readings) == pytest.approx(2.0, abs=0.05)
    else:  # the bare segment is invisible end-on: no echo nearer than 2.5 m
        assert min(readings) > 2.5


def test_laser_sees_a_wall_end():
    for end_faces, near in ((True, True), (False, False)):
        sim = Simulator(ROOM, seed=0, end_faces=end_faces)
        body = sim.add_robot((3.0, 3.0, 0.0))
        scan = body.scan_laser()
        ahead = np.argmin(np.abs(sim.laser.angles))
        assert (abs(scan[ahead] - (2.0 - sim.laser.mount[0])) < 0.05) == near
        assert math.isfinite(scan[ahead])


def test_collisions_ignore_the_faces():
    # the robot may stand right at a free end's side: faces are for sensing
    sim = Simulator(ROOM, seed=0)
    sim.add_robot((5.0 - 0.26, 3.0, 0.0))
