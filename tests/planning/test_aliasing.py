"""Look-alike places: a map's symmetries and the trajectories they fool."""

import math

import numpy as np

from robotlib.planning.aliasing import (
    agreement,
    drive_score,
    look_alike,
    map_symmetries,
)
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


def test_a_drive_through_a_door_tells_two_look_alike_rooms_apart():
    # two equal rooms side by side, a door between them at y 2.5-3.5
    walls = [[0, 0, 12, 0], [12, 0, 12, 6], [12, 6, 0, 6], [0, 6, 0, 0]]
    walls += [[6, 0, 6, 2.5], [6, 3.5, 6, 6]]
    world = World(segments=walls, start=(1, 3, 0))
    xs = np.linspace(3.0, 9.0, 121)  # from the left room into the right one
    truth = np.column_stack([xs, np.full_like(xs, 3.0), np.zeros_like(xs)])
    scans = expected_ranges(world, truth)
    odometry = truth + np.array([0.5, -0.2, 0.0])  # any frame: only its moves count
    here = drive_score(world, truth[-1], odometry, scans)
    assert here == 1.0
    # the look-alike place one room to the left: the drive runs through the wall
    there = truth[-1] - np.array([6.0, 0.0, 0.0])
    assert drive_score(world, there, odometry, scans) < here - 0.3
    # near the true place the score stays high: it weighs places, not centimetres
    assert drive_score(world, truth[-1] + [0.1, 0.05, 0.0], odometry, scans) > 0.8
