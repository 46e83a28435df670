"""Frontier detection and choice against plain-loop references."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from robotlib.exploration import (
    FREE,
    OCCUPIED,
    UNKNOWN,
    choose,
    classify,
    departure,
    discount,
    frontier_cells,
    frontier_costs,
    frontier_regions,
    information_gain,
    known_space,
    open_frontier,
)
from robotlib.planning import cost_field
from tests import naive_exploration as naive

states = arrays(
    np.int8,
    st.tuples(st.integers(1, 12), st.integers(1, 12)),
    elements=st.sampled_from([FREE, UNKNOWN, OCCUPIED]),
)


@settings(max_examples=60, deadline=None)
@given(states)
def test_frontier_cells_match_the_loops(state):
    assert np.array_equal(frontier_cells(state), naive.frontier_cells(state))


@settings(max_examples=60, deadline=None)
@given(states, st.integers(1, 4))
def test_regions_match_the_flood_fill(state, min_size):
    mask = naive.frontier_cells(state)
    got = frontier_regions(mask, (0.0, 0.0), 0.5, min_size)
    want = [c for c in naive.regions(mask) if len(c) >= min_size]
    assert sorted(len(c) for c in want) == sorted(f.size for f in got)
    assert {frozenset(c) for c in want} == {frozenset(map(tuple, f.cells)) for f in got}
    for f in got:
        xy = np.column_stack([(f.cells[:, 1] + 0.5) * 0.5, (f.cells[:, 0] + 0.5) * 0.5])
        assert np.allclose(f.centroid, xy.mean(axis=0))
        assert any(
            np.allclose(f.target, p) for p in xy
        )  # the target is a frontier cell
        assert f.length == pytest.approx(0.5 * f.size)
    assert [f.size for f in got] == sorted((f.size for f in got), reverse=True)


def test_classify_thresholds_and_edges():
    L = np.array([[-1.0, 0.0, 1.0], [-0.1, 0.1, -0.3]])
    assert classify(L).tolist() == [[FREE, UNKNOWN, OCCUPIED], [UNKNOWN, UNKNOWN, FREE]]
    # a free cell at the grid's edge with no unknown neighbour is no frontier
    assert not frontier_cells(np.zeros((3, 3), np.int8)).any()
    with pytest.raises(ValueError):
        classify(L, free_level=-1)
    with pytest.raises(ValueError):
        frontier_cells(np.zeros(3))


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.floats(0, 10), min_size=1, max_size=8),
    st.floats(-5, 5),
    st.floats(-5, 5),
    st.floats(0.5, 6),
)
def test_discount_matches_the_loop(gains, cx, cy, radius):
    rng = np.random.default_rng(len(gains))
    targets = rng.uniform(-5, 5, (len(gains), 2))
    got = discount(gains, targets, (cx, cy), radius)
    assert np.allclose(got, naive.discount(gains, targets, (cx, cy), radius))
    assert np.all(got <= np.asarray(gains) + 1e-12)


def test_coordination_spreads_a_team_and_nearest_does_not():
    # two robots side by side, two frontier targets: one near both, one far
    targets = np.array([[1.0, 0.0], [10.0, 0.0]])
    gains = np.array([5.0, 5.0])
    costs = np.array([[1.0, 9.0], [1.2, 8.8]])
    assert choose(costs, gains, targets, "nearest").tolist() == [0, 0]
    assert choose(costs, gains, targets, "utility", beta=0.1).tolist() == [0, 0]
    got = choose(costs, gains, targets, "coordinated", beta=0.1, radius=4.0)
    assert sorted(got.tolist()) == [0, 1]
    # a target a teammate already drives to is discounted away
    alone = choose(
        costs[:1], gains, targets, "coordinated", beta=0.1, taken=[targets[0]]
    )
    assert alone.tolist() == [1]
    # unreachable everywhere: -1
    assert choose(np.full((1, 2), np.inf), gains, targets).tolist() == [-1]
    with pytest.raises(ValueError):
        choose(costs, gains, targets, "random")


def test_path_costs_treat_unknown_as_obstacle():
    # a corridor of known free cells, unknown on the right; a wall splits it
    state = np.full((20, 40), UNKNOWN, np.int8)
    state[5:15, 0:20] = FREE
    state[5:15, 10] = OCCUPIED
    state[8:12, 10] = FREE  # a gap in the wall
    cs = known_space(state, (0.0, 0.0), 0.1, 0.1)
    regions = frontier_regions(frontier_cells(state), (0.0, 0.0), 0.1, 3)
    costs, targets = frontier_costs(cs, (0.35, 1.0), regions)
    assert np.isfinite(costs).any()
    for c, t in zip(costs, targets, strict=True):
        if np.isfinite(c):
            assert (
                c >= np.hypot(*(t - (0.35, 1.0))) - 1e-9
            )  # never shorter than straight
    assert cs.blocked[state == UNKNOWN].all()
    gain = information_gain(state, (0.0, 0.0), 0.1, [[1.95, 1.0], [0.35, 1.0]], 0.5)
    assert gain[0] > 5 * gain[1]


def _corridor():
    """A known corridor 4 m long, unknown beyond both ends; its known space."""
    state = np.full((10, 60), UNKNOWN, np.int8)
    state[2:8, 10:50] = FREE
    state[1, 10:50] = state[8, 10:50] = OCCUPIED
    return state, known_space(state, (0.0, 0.0), 0.1, 0.1)


def test_path_costs_count_the_turn_before_setting_off():
    state, cs = _corridor()
    regions = frontier_regions(frontier_cells(state), (0.0, 0.0), 0.1, 3)
    assert len(regions) == 2
    here = (3.0, 0.5)  # the middle, facing east (+x)
    plain, targets = frontier_costs(cs, here, regions)
    east = int(np.argmax(targets[:, 0]))
    west = 1 - east
    turned, same = frontier_costs(cs, here, regions, heading=0.0, turn=0.5)
    np.testing.assert_array_equal(same, targets)
    # setting off east costs (almost) nothing more, west half a turn more
    assert turned[east] - plain[east] == pytest.approx(0.0, abs=0.06)
    assert turned[west] - plain[west] == pytest.approx(0.5 * np.pi, abs=0.06)
    with pytest.raises(ValueError):  # a given field has no parents to walk
        frontier_costs(cs, here, regions, cost_field(cs, here), heading=0.0, turn=0.5)


def test_departure_matches_walking_the_parents():
    state, cs = _corridor()
    state[2:6, 30] = OCCUPIED  # a wall across but for its top: paths bend
    cs = known_space(state, (0.0, 0.0), 0.1, 0.1)
    here = (2.0, 0.45)
    field, parent = cost_field(cs, here, parents=True)
    ends = np.argwhere(np.isfinite(field))[::37]
    got = departure(cs, parent, here, ends, 0.5)
    for (i, j), a in zip(ends, got, strict=True):  # one cell after another
        at = (int(i), int(j))
        while True:
            nxt = divmod(int(parent[at]), parent.shape[1])
            if parent[at] < 0 or np.hypot(*(cs.to_metres(nxt) - here)) < 0.5:
                break
            at = nxt
        x, y = cs.to_metres(at)
        assert a == pytest.approx(np.arctan2(y - here[1], x - here[0]))


def test_open_frontier_drops_what_faces_a_closed_pocket_only():
    state = np.full((12, 20), FREE, dtype=np.int8)
    state[2:7, 2:7] = OCCUPIED  # a box, its inside unknown, one wall cell free
    state[3:6, 3:6] = UNKNOWN
    state[4, 6] = FREE
    state[:, 14:] = UNKNOWN  # the unexplored rest of the building
    frontier = frontier_cells(state)
    kept = open_frontier(state, frontier, min_cells=10)
    assert frontier[4, 6] and not kept[4, 6]  # the box's pocket: 9 cells
    assert kept[:, 13].all() and (kept == (frontier & (np.arange(20) == 13))).all()
    assert open_frontier(state, frontier, min_cells=9)[4, 6]
