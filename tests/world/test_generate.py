"""Seeded test worlds (`robotlib.world.generate`): valid, closed, pairs reachable."""

from collections import deque

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robotlib.p3dx import ROBOT_RADIUS
from robotlib.world import World
from robotlib.world.generate import KINDS, PASSAGE, generate_world, reachable_pairs

RES = 0.1
SEEDS = st.integers(0, 2**32 - 1)


def _component(free: np.ndarray, i0: int, j0: int) -> np.ndarray:
    """Cells 4-connected to (i0, j0) through ``free`` (a plain breadth-first search)."""
    out = np.zeros_like(free)
    out[i0, j0] = True
    todo = deque([(i0, j0)])
    ny, nx = free.shape
    while todo:
        i, j = todo.popleft()
        for a, b in ((i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1)):
            if 0 <= a < ny and 0 <= b < nx and free[a, b] and not out[a, b]:
                out[a, b] = True
                todo.append((a, b))
    return out


def _reach(world: World, radius: float) -> tuple[np.ndarray, object]:
    """The cells a disc of ``radius`` reaches from the start (own search)."""
    field = world.distance_field(RES)
    i, j = field.cell_of(np.array(world.start[:2]))
    return _component(field.data > radius, int(i), int(j)), field


@pytest.mark.parametrize("kind", KINDS)
def test_generated_world_valid_closed_and_pairs_reachable(kind):
    _check_world(kind, 0)


@pytest.mark.slow
@pytest.mark.parametrize("kind", KINDS)
@settings(max_examples=10, deadline=None)
@given(seed=SEEDS)
def test_every_generated_world_valid_closed_and_pairs_reachable(kind, seed):
    _check_world(kind, seed)


def _check_world(kind: str, seed: int) -> None:
    """Valid, closed, a start that is free, and pairs reachable by own search."""
    w = generate_world(kind, seed)
    assert w.name == kind and len(w.segments) >= 4
    assert np.all(np.isfinite(w.segments))
    x0, y0, x1, y1 = w.bounds
    xs, ys = w.segments[:, 0::2], w.segments[:, 1::2]
    assert xs.min() >= x0 and xs.max() <= x1 and ys.min() >= y0 and ys.max() <= y1
    assert w.is_free(np.array(w.start[:2]), ROBOT_RADIUS + PASSAGE)
    # closed: even a point-sized robot cannot get within 0.3 m of the bounds
    inside, field = _reach(w, 0.07)
    centres = field.centres()
    near_edge = (
        (centres[..., 0] < x0 + 0.3)
        | (centres[..., 0] > x1 - 0.3)
        | (centres[..., 1] < y0 + 0.3)
        | (centres[..., 1] > y1 - 0.3)
    )
    assert not (inside & near_edge).any()
    # a robot reaches a good share of the floor (the ring: its corridor), not a closet
    robot, _ = _reach(w, ROBOT_RADIUS + PASSAGE)
    assert robot.sum() * RES**2 > 0.2 * (x1 - x0 - 1) * (y1 - y0 - 1)
    pairs = reachable_pairs(w, 5, rng=seed)
    assert pairs.shape == (5, 5)
    assert np.all(np.hypot(*(pairs[:, 3:] - pairs[:, :2]).T) >= 4.0)
    for p in pairs:
        for xy in (p[:2], p[3:]):
            assert w.distance_to_walls(xy) >= 0.5
            i, j = field.cell_of(xy)
            assert robot[i, j], (kind, seed, xy)


@pytest.mark.parametrize("kind", KINDS)
def test_same_seed_same_world_and_pairs(kind):
    a, b, c = generate_world(kind, 7), generate_world(kind, 7), generate_world(kind, 8)
    assert a == b and a != c
    np.testing.assert_array_equal(reachable_pairs(a, 3, 1), reachable_pairs(b, 3, 1))


def _box_gaps(w: World) -> np.ndarray:
    """Smallest distance between each two of the hall's boxes (outer walls left out)."""
    boxes = w.segments[4:].reshape(-1, 4, 4)
    gaps = []
    for k, a in enumerate(boxes):
        for b in boxes[k + 1 :]:
            pts = np.concatenate([b[:, :2], b[:, 2:]])
            gaps.append(World(a).distance_to_walls(pts).min())
            pts = np.concatenate([a[:, :2], a[:, 2:]])
            gaps[-1] = min(gaps[-1], World(b).distance_to_walls(pts).min())
    return np.array(gaps)


@settings(max_examples=5, deadline=None)
@given(seed=SEEDS)
def test_hall_gaps_between_boxes(seed):
    gaps = _box_gaps(generate_world("hall", seed))
    assert gaps.min() >= 0.8 - 1e-3
    assert (gaps <= 1.0 + 1e-3).any()  # the tight gaps are there


def test_office_has_twelve_doors_of_0_9_m():
    w = generate_world("office", 3)
    horizontal = w.segments[np.isclose(w.segments[:, 1], w.segments[:, 3])]
    inner = horizontal[(horizontal[:, 1] > 0.1) & (horizontal[:, 1] < w.bounds[3] - 1)]
    doors = []
    for y in np.unique(inner[:, 1]):
        row = inner[inner[:, 1] == y]
        xs = np.sort(np.concatenate([row[:, 0], row[:, 2]]))[1:-1].reshape(-1, 2)
        doors += [b - a for a, b in xs if b - a > 1e-3]
    assert len(doors) == 12 and np.allclose(doors, 0.9, atol=2e-3)


def test_bad_input():
    with pytest.raises(ValueError, match="unknown world kind"):
        generate_world("castle")
    with pytest.raises(ValueError, match="apart"):
        reachable_pairs(generate_world("hall", 0), 1, min_separation=100.0)


def test_a_bench_world_per_seed_generated_or_shipped():
    from robotlib.world import load_world, seeded_world

    a, b, c = (seeded_world("gen-hall", s) for s in (1, 1, 2))
    assert a == b and a != c  # the same seed draws the same map, another seed another
    assert seeded_world("gen-office", 1) != seeded_world("gen-ring", 1)
    assert seeded_world("corridor", 5) == load_world("corridor")  # a shipped map stays
    with pytest.raises(ValueError, match="unknown world kind"):
        seeded_world("gen-castle", 0)
