import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from robotlib import load_world
from robotlib.planning import (
    CSpace,
    _kernels,
    astar,
    configuration_space,
    cost_field,
    dijkstra,
    edge_free,
    inflate,
    octile,
    path_free,
    path_length,
    rrt,
    rrt_star,
    shortcut,
    wavefront,
    wavefront_field,
    weighted_astar,
)
from tests import naive_plan

SETTINGS = settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)


@st.composite
def grids(draw, max_side=12):
    ny = draw(st.integers(2, max_side))
    nx = draw(st.integers(2, max_side))
    seed = draw(st.integers(0, 2**32 - 1))
    density = draw(st.sampled_from([0.0, 0.15, 0.3, 0.45]))
    rng = np.random.default_rng(seed)
    blocked = rng.random((ny, nx)) < density
    with_cost = draw(st.booleans())
    cost = rng.random((ny, nx)) * 3 if with_cost else np.zeros((ny, nx))
    free = np.argwhere(~blocked)
    if len(free) < 1:
        blocked[0, 0] = False
        free = np.argwhere(~blocked)
    s = tuple(free[rng.integers(len(free))])
    g = tuple(free[rng.integers(len(free))])
    res = draw(st.sampled_from([1.0, 0.05]))
    cs = CSpace.from_array(blocked, resolution=res, cost=cost)
    return cs, s, g


def centre(cs, cell):
    return cs.to_metres(np.array(cell))


def check_path(cs, plan, s, g, connectivity):
    cells = plan.cells
    assert tuple(cells[0]) == s and tuple(cells[-1]) == g
    assert not cs.blocked[cells[:, 0], cells[:, 1]].any()
    steps = np.diff(cells, axis=0)
    assert np.all(np.abs(steps).max(axis=1) == 1)
    if connectivity == 4:
        assert np.all(np.abs(steps).sum(axis=1) == 1)
    for (i, j), (di, dj) in zip(cells[:-1], steps, strict=True):
        if di and dj:  # no corner cutting
            assert not cs.blocked[i, j + dj] and not cs.blocked[i + di, j]
    np.testing.assert_allclose(plan.path, cs.to_metres(cells))


@SETTINGS
@given(grids(), st.sampled_from([4, 8]))
def test_astar_and_dijkstra_are_optimal(case, connectivity):
    cs, s, g = case
    ref = naive_plan.dijkstra_costs(cs.blocked, cs.cost, s, connectivity, cs.resolution)
    a = astar(cs, centre(cs, s), centre(cs, g), connectivity)
    d = dijkstra(cs, centre(cs, s), centre(cs, g), connectivity)
    if g not in ref:
        assert not a.found and not d.found
        assert a.cost == math.inf and len(a.path) == 0
        return
    assert a.found and d.found
    assert a.cost == pytest.approx(ref[g], abs=1e-9)
    assert d.cost == pytest.approx(ref[g], abs=1e-9)
    assert a.expanded <= d.expanded
    for plan in (a, d):
        check_path(cs, plan, s, g, connectivity)
        # the reported cost is the cost of the reported path
        c = sum(
            cs.resolution * math.hypot(*(v - u)) * (1 + cs.cost[tuple(v)])
            for u, v in zip(plan.cells[:-1], plan.cells[1:], strict=True)
        )
        assert c == pytest.approx(plan.cost, abs=1e-9)
    w = weighted_astar(cs, centre(cs, s), centre(cs, g), 2.5, connectivity)
    assert w.found and ref[g] - 1e-9 <= w.cost <= 2.5 * ref[g] + 1e-9
    check_path(cs, w, s, g, connectivity)


@SETTINGS
@given(grids(), st.sampled_from([4, 8]), st.sampled_from([0.0, 1.0, 2.5]))
def test_astar_expands_as_the_heapq_reference(case, connectivity, weight):
    # the kernel's heap (indexed, 4-ary, decrease-key) against heapq with lazy
    # deletion on the same keys: the same nodes in the same order, the same
    # path, the same cost to the bit
    cs, s, g = case
    order, path, cost = naive_plan.astar_order(
        cs.blocked, cs.cost, s, g, connectivity, cs.resolution, weight
    )
    a = weighted_astar(
        cs, centre(cs, s), centre(cs, g), weight, connectivity, record=True
    )
    assert [tuple(c) for c in a.order] == order
    assert a.expanded == len(order)
    if path is None:
        assert not a.found
        return
    assert [tuple(c) for c in a.cells] == path
    assert a.cost == cost


@pytest.mark.parametrize("seed", [0, 1])
def test_astar_expands_as_the_heapq_reference_on_a_larger_grid(seed):
    # deep heaps (hundreds of open nodes) and many decrease-keys, with a cost map
    rng = np.random.default_rng(seed)
    blocked = rng.random((70, 90)) < 0.25
    blocked[0, 0] = blocked[-1, -1] = False
    cost = rng.random(blocked.shape) * (seed + 1)
    cs = CSpace.from_array(blocked, resolution=0.05, cost=cost)
    for connectivity in (4, 8):
        order, path, c = naive_plan.astar_order(
            blocked, cost, (0, 0), (69, 89), connectivity, 0.05
        )
        a = astar(
            cs, centre(cs, (0, 0)), centre(cs, (69, 89)), connectivity, record=True
        )
        assert [tuple(x) for x in a.order] == order
        if path is None:
            assert not a.found
        else:
            assert [tuple(x) for x in a.cells] == path and a.cost == c


@SETTINGS
@given(grids(), st.sampled_from([4, 8]))
def test_wavefront_has_fewest_moves(case, connectivity):
    cs, s, g = case
    ref = naive_plan.bfs_moves(cs.blocked, g, connectivity)
    p = wavefront(cs, centre(cs, s), centre(cs, g), connectivity)
    field = wavefront_field(cs, centre(cs, g), connectivity)
    for cell in np.ndindex(cs.shape):
        assert field[cell] == ref.get(cell, -1)
    if s not in ref:
        assert not p.found and len(p.path) == 0
        return
    assert p.found and len(p.cells) == ref[s] + 1
    check_path(cs, p, s, g, connectivity)
    assert p.cost == pytest.approx(path_length(p.path))


@SETTINGS
@given(grids(max_side=8))
def test_octile_is_admissible(case):
    cs, _, g = case
    for cell in map(tuple, np.argwhere(~cs.blocked)):
        ref = naive_plan.dijkstra_costs(cs.blocked, cs.cost, cell, 8, cs.resolution)
        if g in ref:
            assert octile(np.array(cell), np.array(g), cs.resolution) <= ref[g] + 1e-12
    field = cost_field(cs, centre(cs, g), 8, use_cost=False)
    free_ref = naive_plan.dijkstra_costs(cs.blocked, 0 * cs.cost, g, 8, cs.resolution)
    for cell in np.ndindex(cs.shape):
        assert field[cell] == pytest.approx(free_ref.get(cell, math.inf), abs=1e-9)


@SETTINGS
@given(grids(max_side=8))
def test_cost_field_parents_lead_down_to_the_goal(case):
    cs, _, g = case
    field, parent = cost_field(cs, centre(cs, g), 8, parents=True)
    nx = cs.shape[1]
    assert parent[g] == -1
    for cell in np.ndindex(cs.shape):
        if not np.isfinite(field[cell]):
            assert parent[cell] == -1
            continue
        at, steps = cell, 0
        while at != g:  # each step is to a neighbour nearer the goal
            nxt = divmod(int(parent[at]), nx)
            assert max(abs(nxt[0] - at[0]), abs(nxt[1] - at[1])) == 1
            assert field[nxt] < field[at]
            at, steps = nxt, steps + 1
            assert steps <= field.size


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(0.0, 4.0))
def test_inflate_matches_reference(seed, r):
    occ = np.random.default_rng(seed).random((15, 11)) < 0.05
    np.testing.assert_array_equal(inflate(occ, r), naive_plan.inflate(occ, r))
    np.testing.assert_array_equal(
        inflate(occ, 0.1 * r, 0.1), naive_plan.inflate(occ, r)
    )


@pytest.mark.slow
@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-2, 2, allow_nan=False), min_size=8, max_size=8))
def test_segment_distance_matches_reference(v):
    a, b, c, d = np.array(v).reshape(4, 2)
    got = _kernels.segment_distance(*a, *b, *c, *d)
    ref = naive_plan.segment_distance(a, b, c, d)
    assert got <= ref + 1e-9
    assert got >= ref - np.hypot(*(b - a)) / 399 - 1e-9


def test_start_or_goal_in_a_wall_is_a_clear_error():
    cs = CSpace.from_array(np.array([[0, 1], [0, 0]], bool))
    for planner in (astar, dijkstra, wavefront):
        with pytest.raises(ValueError, match="goal .* inside an obstacle"):
            planner(cs, (0.5, 0.5), (1.5, 0.5))
        with pytest.raises(ValueError, match="start .* inside an obstacle"):
            planner(cs, (1.5, 0.5), (0.5, 0.5))
        with pytest.raises(ValueError, match="off the grid"):
            planner(cs, (0.5, 0.5), (5.0, 0.5))
    with pytest.raises(ValueError, match="connectivity"):
        astar(cs, (0.5, 0.5), (0.5, 1.5), connectivity=6)


@pytest.fixture(scope="module")
def office():
    world = load_world("office")
    return world, configuration_space(world, 0.05)


def test_cspace_of_the_office(office):
    world, cs = office
    centres = cs.to_metres(np.argwhere(np.ones(cs.shape, bool))).reshape(*cs.shape, 2)
    free = world.is_free(centres, cs.radius)
    assert not np.any(free & cs.blocked)  # every free-in-the-world cell is open...
    assert not np.any(~free & ~cs.blocked)  # ...and every open cell is free
    assert cs.cost.max() > 0 and cs.cost[~cs.blocked].min() == 0
    p = astar(cs, (1.5, 7.5), (17.5, 12.0))
    assert p.found and world.is_free(p.path, cs.radius - 0.02 - 1e-9).all()
    plain = astar(cs, (1.5, 7.5), (17.5, 12.0), use_cost=False)
    assert plain.cost == pytest.approx(path_length(plain.path))
    # the cost map keeps the path further from the walls on average
    assert (
        world.distance_to_walls(p.path).mean()
        > world.distance_to_walls(plain.path).mean()
    )


def test_with_points_blocks_around_hits(office):
    _, cs = office
    hit = np.array([[5.0, 7.5]])
    cs2 = cs.with_points(hit)
    assert not cs2.is_free(hit + [[cs.radius - 0.05, 0.0]])[0]
    assert cs2.is_free(hit + [[0.0, cs.radius + 0.2]])[0]
    assert np.all(cs2.blocked >= cs.blocked)


def test_rrt_is_reproducible_and_free(office):
    world, _ = office
    a = rrt(world, (1.5, 7.5), (17.5, 12.0), rng=3)
    b = rrt(world, (1.5, 7.5), (17.5, 12.0), rng=3)
    assert a.found and np.array_equal(a.nodes, b.nodes)
    assert np.array_equal(a.parents, b.parents)
    assert path_free(world, a.path)
    short = shortcut(world, a.path, rng=3)
    assert np.array_equal(short, shortcut(world, a.path, rng=3))
    assert path_free(world, short) and path_length(short) <= a.cost + 1e-9
    assert np.array_equal(short[[0, -1]], a.path[[0, -1]])
    # every tree edge is free
    for k in range(1, len(a.nodes)):
        assert edge_free(world, a.nodes[a.parents[k]], a.nodes[k])


def test_rrt_star_improves_and_reports_no_path_when_walled_in():
    world = load_world("maze")
    s, g = (1.25, 1.25), (11.75, 8.75)
    star = rrt_star(world, s, g, max_iter=1500, rng=0)
    assert star.found and path_free(world, star.path)
    assert star.cost == pytest.approx(path_length(star.path))
    with pytest.raises(ValueError, match="not free"):
        rrt(world, (0.5, 0.5), g)
    # a goal enclosed by a small box of walls is never reached
    x0, x1, y0, y1 = 11.2, 12.3, 8.2, 9.3
    box = np.array(
        [[x0, y0, x1, y0], [x1, y0, x1, y1], [x1, y1, x0, y1], [x0, y1, x0, y0]]
    )
    from robotlib import World

    closed = World(np.vstack([world.segments, box]), bounds=world.bounds)
    t = rrt(closed, s, g, max_iter=300, rng=0)
    assert not t.found and t.cost == math.inf and len(t.path) == 0
