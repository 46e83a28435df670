"""A wall met end-on echoes from its end face (`World.sensed_obstacles`)."""

import math

import numpy as np
import pytest

from robotlib.p3dx import ROBOT_RADIUS
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


def _distance(point, segments) -> float:
    """Least distance from a point to segments (x1, y1, x2, y2), in NumPy."""
    seg = np.asarray(segments, dtype=float)
    a, d = seg[:, :2], seg[:, 2:] - seg[:, :2]
    t = np.clip(((point - a) * d).sum(axis=1) / (d * d).sum(axis=1), 0.0, 1.0)
    return float(np.hypot(*(a + t[:, None] * d - point).T).min())


def test_collisions_ignore_the_faces():
    # a robot may stand where only the partition's end face would touch it
    # (faces are for sensing): nearer the face than its radius, clear of walls
    side = math.sqrt(ROBOT_RADIUS**2 - (END_FACE / 2) ** 2) + 0.0005
    pose = np.array([5.0 - side, 3.0 + END_FACE / 2, math.pi / 2])
    faces = ROOM.sensed_obstacles[len(ROOM.obstacles) :]
    assert (
        _distance(pose[:2], faces) < ROBOT_RADIUS < _distance(pose[:2], ROOM.obstacles)
    )
    sim = Simulator(ROOM, seed=0)
    body = sim.add_robot(pose)
    body.command("MOVE", 0.3)  # and drives on, north past the face
    for _ in range(40):
        sim.step()
    assert body.true_pose[1] - pose[1] == pytest.approx(0.3, abs=0.03)
    with pytest.raises(ValueError, match="overlap a wall"):  # walls still count
        sim.add_robot((5.0 - ROBOT_RADIUS / 2, 3.0, 0.0))
