"""Small worlds built in code for the tests."""

from robotlib.world import World

DOOR_CORRIDOR = [
    (0, 0, 6, 0),
    (0, 2, 2.5, 2),
    (3.5, 2, 6, 2),
    (2.5, 2, 2.5, 3),
    (3.5, 2, 3.5, 3),
    (2.5, 3, 3.5, 3),
    (0, 0, 0, 2),
    (6, 0, 6, 2),
    (4.5, 0.0, 4.5, 0.5),
]
"""A 6 m x 2 m corridor with one door (into a 1 m bay) and a box, m."""


def door_corridor(extra=()) -> World:
    """`DOOR_CORRIDOR` plus ``extra`` segments, start at the west end."""
    return World(
        [*DOOR_CORRIDOR, *extra], bounds=(-0.2, -0.2, 6.2, 3.2), start=(1.0, 1.0, 0.0)
    )
