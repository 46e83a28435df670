"""Physical parameters of the Pioneer 3-DX, in SI units.

Values from the ARIA ``p3dx`` parameter file (see ``PIONEER_PROTOCOL.md``),
converted once here from millimetres and degrees.
"""

import math

import numpy as np

ROBOT_RADIUS = 0.250
"""Radius of the circle that bounds the robot for collisions, m."""
ROBOT_WIDTH = 0.425
"""Overall width, m."""
ROBOT_LENGTH_FRONT = 0.210
"""Distance from the centre of rotation to the front bumper, m."""
ROBOT_LENGTH_REAR = 0.301
"""Distance from the centre of rotation to the rear, m."""

MAX_VELOCITY = 2.2
"""Top translational speed, m/s."""
MAX_ROT_VELOCITY = math.radians(500.0)
"""Top rotational speed, rad/s."""

CYCLE = 0.1
"""Server information cycle: one SIP and one control step, s."""

SONAR_POSES = np.array(
    [
        [0.069, 0.136, math.radians(90.0)],
        [0.114, 0.119, math.radians(50.0)],
        [0.148, 0.078, math.radians(30.0)],
        [0.166, 0.027, math.radians(10.0)],
        [0.166, -0.027, math.radians(-10.0)],
        [0.148, -0.078, math.radians(-30.0)],
        [0.114, -0.119, math.radians(-50.0)],
        [0.069, -0.136, math.radians(-90.0)],
    ]
)
"""Front sonar ring, (8, 3): ``x, y`` in m and heading in rad, robot frame."""
SONAR_POSES.setflags(write=False)

SONAR_MAX_RANGE = 5.0
"""Largest range a sonar reports; also the value for "no echo", m."""
SONAR_MIN_RANGE = 0.1
"""Smallest range a sonar reports, m."""
SONAR_CONE = math.radians(30.0)
"""Full opening angle of a sonar's cone, rad."""

MOVE_DONE_TOLERANCE = 0.040
"""``isMoveDone``: within this distance of the commanded travel, m."""
HEADING_DONE_TOLERANCE = math.radians(3.0)
"""``isHeadingDone``: within this angle of the target heading, rad."""

AXLE_TRACK = 1.0 / (1000.0 * 0.0056 / 2.0)
"""Effective wheel separation from ARIA's DiffConvFactor (0.0056), m.

ARIA turns a wheel-speed difference into a rotational velocity as
``w = (right - left) / 2 * DiffConvFactor`` (mm/s to rad/s), which is a
differential drive with this track.
"""

DEFAULT_MAX_VELOCITY = 0.75
"""Translational speed limit at start-up (``TransVelMax``), m/s."""
DEFAULT_MAX_ROT_VELOCITY = math.radians(100.0)
"""Rotational speed limit at start-up (``RotVelMax``), rad/s."""
DEFAULT_ACCELERATION = 0.3
"""Translational acceleration and deceleration at start-up, m/s^2."""
DEFAULT_ROT_ACCELERATION = math.radians(100.0)
"""Rotational acceleration and deceleration at start-up, rad/s^2."""
