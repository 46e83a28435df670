"""The bucket index of large maps gives the very numbers of the every-wall kernels."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from robotlib.world import World
from robotlib.world import _kernels as wk
from robotlib.world.index import INDEX_MIN_SEGMENTS, SegmentIndex


def many_point_world(seed=0, n=400):
    rng = np.random.default_rng(seed)
    walls = [[0, 0, 6, 0], [6, 0, 6, 4], [6, 4, 0, 4], [0, 4, 0, 0], [2, 1, 2, 3]]
    along = np.linspace(0.5, 5.5, n // 2)  # a "scanned" wall of points, with gaps
    pts = np.concatenate(
        [
            np.column_stack([along, 2.5 + rng.normal(0, 0.004, len(along))]),
            rng.uniform([0.2, 0.2], [5.8, 3.8], (n - len(along), 2)),
        ]
    )
    return World(walls, points=pts, start=(1, 1, 0))


coords = st.floats(-5, 5, allow_nan=False)


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.tuples(coords, coords, coords, coords), min_size=1, max_size=60),
    st.lists(st.tuples(st.floats(-7, 7), st.floats(-7, 7)), min_size=1, max_size=30),
    st.sampled_from([None, 0.1, 0.7]),
)
def test_index_distances_equal_the_every_segment_kernel(segs, pts, size):
    segs = np.array(segs, dtype=float)
    pts = np.array(pts, dtype=float)
    index = SegmentIndex.build(segs, (-1, -1, 1, 1), size=size)
    ref = np.empty(len(pts))
    wk.min_distance_to_segments(pts, segs, ref)
    np.testing.assert_array_equal(index.distances(pts), ref)


def test_large_map_field_and_free_space_are_unchanged_bit_for_bit():
    world = many_point_world()
    assert len(world.obstacles) >= INDEX_MIN_SEGMENTS  # takes the indexed paths
    field = world.distance_field(0.1)
    ref = np.empty(field.data.size)
    wk.min_distance_to_segments(
        np.ascontiguousarray(field.centres().reshape(-1, 2)), world.obstacles, ref
    )
    np.testing.assert_array_equal(field.data.reshape(-1), ref)
    free = world.free_space(0.1)
    assert free.data.any() and not free.data.all()


def test_free_space_without_the_field_is_the_fields_own_mask():
    """`World.free_space` on a large map measures only the unsettled blocks."""
    world = many_point_world(seed=1, n=600)
    assert len(world.obstacles) >= INDEX_MIN_SEGMENTS
    fresh = many_point_world(seed=1, n=600)
    field = world.distance_field(0.05)  # cached: its free space uses the field
    for radius in (0.0, 0.05, 0.2, 0.35):
        np.testing.assert_array_equal(
            fresh.free_space(0.05, radius).data, world.free_space(0.05, radius).data
        )
    assert ("distance", 0.05) not in fresh._cache  # the whole field was not made
    # cuts at the field's own values: the strict side of each cell is kept
    index = fresh.segment_index()
    values = field.data[np.isfinite(field.data)]
    cuts = np.quantile(values, [0.02, 0.3, 0.6, 0.97], method="nearest")
    settled = 0
    for cut in cuts:
        out = np.empty(field.data.shape)
        wk.indexed_distance_field(
            *field.origin, 0.05, 4, index.segments, *index.args, float(cut), out
        )
        np.testing.assert_array_equal(out > cut, field.data > cut)
        measured = np.isfinite(out)
        np.testing.assert_array_equal(out[measured], field.data[measured])
        settled += int((~measured).sum())
    assert settled > field.data.size  # most blocks were settled by their bound
