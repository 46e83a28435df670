"""Look-alike places: a map's symmetries and the trajectories they fool."""

import math

import numpy as np

from robotlib.planning.aliasing import agreement, look_alike, map_symmetries
from robotlib.sensing import expected_ranges
from robotlib.world import World, compose

ROOM = [[0, 0, 10, 0], [10, 0, 10, 6], [10, 6, 0, 6], [0, 6, 0, 0]]


def _box(x, y, w=1.0, h=1.0):
    return [[x, y, x + w, y], [x + w, y, x + w, y + h], [x + w, y + h, x, y + h],
            [x, y + h, x, y]]  # fmt: skip


def test_a_centred_box_is_symmetric_by_half_a_turn_an_offset_one_is_not():
    centred = World(segments=ROOM + _box(4.5, 2.5), start=(1, 1, 0))
    (g,) = map_symmetries(centred)
    assert g[2] == math.pi
    # the turn maps a corner of the room onto the opposite one
    assert np.allclose(compose(g, np.array([0.0, 0.0, 0.0]))[:2], (10.0, 6.0))
    offset = World(segments=ROOM + _box(2.0, 2.5), start=(5, 1, 0))
    assert map_symmetries(offset) == []


def test_a_drive_in_a_symmetric_room_fits_the_turned_room_as_well():
    world = World(segments=ROOM + _box(4.5, 2.5), start=(1, 1, 0))
    poses = np.column_stack([np.linspace(1, 3, 20), np.full(20, 1.0), np.zeros(20)])
    scans = expected_ranges(world, poses)
    assert agreement(world, poses, scans) == 1.0
    g = look_alike(world, poses, scans, map_symmetries(world))
    assert g is not None and g[2] == math.pi
    # the same drive where a second box breaks the symmetry near the path
    broken = World(segments=ROOM + _box(4.5, 2.5) + _box(8.0, 4.3, 0.8, 0.8))
    scans = expected_ranges(broken, poses)
    assert look_alike(broken, poses, scans, map_symmetries(world)) is None
    assert look_alike(world, poses[:0], scans[:0], map_symmetries(world)) is None
