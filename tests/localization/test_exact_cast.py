"""The exact path's pruned cone caster against the plain one: the same bits.

`cone_echo_pruned` casts only the rays that can lower a cone's echo, after
an approximate first pass; `robotlib.sensing._kernels.cone_echo` (itself
checked against a NumPy reference in tests/sensing/test_sonar.py) casts every ray
against every wall. Here both run on the same walls, and the whole exact
scan (`expected_scan_blocks`, through the wall index) runs against the plain
every-wall `expected_scan` and the NumPy reference in tests/naive.py.
"""

import math

import numba as nb
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robotlib.localization import expected_readings
from robotlib.localization._kernels.exact import (
    SECTORS,
    _lanes,
    _offsets,
    cone_echo_pruned,
    wall_blocks,
    wall_table,
)
from robotlib.sensing import SonarModel
from robotlib.sensing import _kernels as sensing
from robotlib.world import World, load_world
from tests import naive


@nb.njit(error_model="numpy")
def _echoes_both(cones, walls, counts, n_rays, cone, max_range, cos_specular):
    out = np.empty((cones.shape[0], 2))
    offs = _offsets(n_rays, cone)
    ray = np.empty((3, _lanes(n_rays)))
    cand = np.empty(((walls.shape[1] + 63) // 64, _lanes(n_rays)), dtype=np.uint64)
    pas = np.empty(walls.shape[1], dtype=np.uint64)
    items = np.empty(0, dtype=np.int32)
    for k in range(cones.shape[0]):
        w = walls[k, : counts[k]]
        sx, sy, sth = cones[k, 0], cones[k, 1], cones[k, 2]
        out[k, 0] = sensing.cone_echo(
            sx, sy, sth, w, n_rays, cone, max_range, cos_specular
        )
        table = wall_table(w)
        out[k, 1] = cone_echo_pruned(
            sx, sy, sth, math.cos(sth), math.sin(sth), table, items, True, 0,
            counts[k], n_rays, cone, max_range, cos_specular, offs, ray, cand, pas,
        )  # fmt: skip
    return out


def _random_cones(seed, k=4000, m=10):
    rng = np.random.default_rng(seed)
    cones = np.column_stack(
        [rng.uniform(-1, 1, k), rng.uniform(-1, 1, k), rng.uniform(-4, 4, k)]
    )
    walls = rng.uniform(-3, 3, (k, m, 4))
    walls[::5, 1] = walls[::5, 0]  # the same wall twice: the first one wins
    walls[::7, 2, :2] = cones[::7, :2]  # a wall starting at the apex
    walls[::11, 3] = [-2.0, 0.5, 2.0, 0.5]  # axis-parallel walls
    walls[::11, 4] = [0.5, -2.0, 0.5, 2.0]
    walls[::13, 5] = np.round(walls[::13, 5])  # whole-number end points
    walls[::17, 6, 2:] = walls[::17, 6, :2]  # a wall of no length
    # a wall through the apex along the cone's first ray, and one across it
    off = -0.5 * SonarModel().cone
    a = cones[::19, 2] + off
    walls[::19, 7, :2] = cones[::19, :2] - np.column_stack([np.cos(a), np.sin(a)])
    walls[::19, 7, 2:] = cones[::19, :2] + 2 * np.column_stack([np.cos(a), np.sin(a)])
    mid = cones[::19, :2] + 1.5 * np.column_stack([np.cos(a), np.sin(a)])
    walls[::19, 8, :2] = mid + 0.5 * np.column_stack([-np.sin(a), np.cos(a)])
    walls[::19, 8, 2:] = mid - 0.5 * np.column_stack([-np.sin(a), np.cos(a)])
    counts = rng.integers(0, m + 1, k)
    counts[::19] = m
    return cones, walls, counts


@pytest.mark.parametrize("n_rays", [1, 2, 7, 9])
@pytest.mark.parametrize("specular", [math.radians(70.0), None, math.radians(20.0)])
def test_pruned_cone_equals_cone_echo(n_rays, specular):
    """Random, repeated, apex, parallel, zero-length and ray-aligned walls."""
    cones, walls, counts = _random_cones(n_rays)
    sonar = SonarModel(specular_angle=specular)
    out = _echoes_both(
        cones, walls, counts, n_rays, sonar.cone, sonar.max_range, sonar.cos_specular
    )
    assert np.isfinite(out[:, 0]).sum() > 100  # echoes were found
    np.testing.assert_array_equal(out[:, 0], out[:, 1])


def _plain(world, poses, sonar):
    out = np.empty((len(poses), len(sonar.sensors)))
    seg = np.ascontiguousarray(world.obstacles, dtype=np.float64).reshape(-1, 4)
    sensing.expected_scan(
        np.ascontiguousarray(poses, dtype=np.float64), sonar.sensors, seg,
        sonar.n_rays, sonar.cone, sonar.max_range, sonar.min_range,
        sonar.cos_specular, out,
    )  # fmt: skip
    return out


@pytest.mark.parametrize("name", ["office", "building"])
def test_exact_scan_equals_every_wall_scan(name):
    """Free poses, and poses anywhere (in walls, outside the map), 1 and 2 threads."""
    world = load_world(name)
    rng = np.random.default_rng(1)
    x0, y0, x1, y1 = world.bounds
    anywhere = np.column_stack(
        [rng.uniform(x0 - 2, x1 + 2, 600), rng.uniform(y0 - 2, y1 + 2, 600),
         rng.uniform(-7, 7, 600)]
    )  # fmt: skip
    sonar = SonarModel()
    for poses in (world.sample_free_poses(600, rng), anywhere):
        ref = _plain(world, poses, sonar)
        np.testing.assert_array_equal(expected_readings(world, poses[:40], sonar),
                                      ref[:40])  # fmt: skip
        np.testing.assert_array_equal(expected_readings(world, poses, sonar), ref)


def test_wall_index_holds_rows_of_the_wall_table():
    world = load_world("office")
    seg = np.asarray(world.obstacles, dtype=np.float64)
    walls, start, items, grid = wall_blocks(seg, world.bounds, 5.0, cone=0.5)
    assert walls.shape == (len(seg), 8) and items.dtype == np.int32
    np.testing.assert_array_equal(walls[:, :4], seg)
    np.testing.assert_array_equal(walls[:, 4], seg[:, 2] - seg[:, 0])
    assert start[0] == 0 and start[-1] == len(items) and np.all(np.diff(start) >= 0)
    for b in range(len(start) - 1):  # each list keeps the walls' order
        assert np.all(np.diff(items[start[b] : start[b + 1]]) > 0)
    assert grid[5] == SECTORS


coord = st.floats(-4, 4, allow_nan=False)
wall = st.tuples(coord, coord, coord, coord)


@settings(max_examples=30, deadline=None)
@given(
    st.lists(wall, min_size=1, max_size=12),
    st.lists(st.tuples(coord, coord, st.floats(-7, 7)), min_size=1, max_size=6),
    st.sampled_from([1, 3, 7]),
)
def test_exact_scan_equals_references_on_random_walls(walls, poses, n_rays):
    """Any walls (crossing, touching, of no length), any poses: the same bits."""
    world = World(np.array(walls), bounds=(-5, -5, 5, 5))
    sonar = SonarModel(n_rays=n_rays)
    poses = np.array(poses)
    got = expected_readings(world, poses, sonar)
    np.testing.assert_array_equal(got, _plain(world, poses, sonar))
    c = np.cos(poses[:, 2:3])
    s = np.sin(poses[:, 2:3])
    sx = poses[:, 0:1] + c * sonar.sensors[:, 0] - s * sonar.sensors[:, 1]
    sy = poses[:, 1:2] + s * sonar.sensors[:, 0] + c * sonar.sensors[:, 1]
    sth = poses[:, 2:3] + sonar.sensors[:, 2]
    for k in range(len(poses)):  # the NumPy reference, away from ties at ends
        for i in range(len(sonar.sensors)):
            echo, _ = naive.sonar_cone(
                sx[k, i], sy[k, i], sth[k, i], world.obstacles, n_rays, sonar.cone,
                sonar.max_range, sonar.specular_angle,
            )  # fmt: skip
            ref = min(max(min(echo, sonar.max_range), sonar.min_range), sonar.max_range)
            assert got[k, i] == pytest.approx(ref, abs=1e-6) or _near_end(
                sx[k, i], sy[k, i], sth[k, i], world.obstacles, n_rays, sonar.cone
            )


def _near_end(sx, sy, sth, segments, n_rays, cone):
    """Whether a ray of the cone passes within 1e-6 m of a wall's end point."""
    ends = np.concatenate([segments[:, :2], segments[:, 2:]]) - [sx, sy]
    offsets = [0.0] if n_rays == 1 else np.linspace(-cone / 2, cone / 2, n_rays)
    for off in offsets:
        d = np.array([math.cos(sth + off), math.sin(sth + off)])
        if np.any(np.abs(ends[:, 0] * d[1] - ends[:, 1] * d[0]) < 1e-6):
            return True
    return False


@pytest.mark.parametrize("n", [40, 300])
def test_fused_exact_weighing_equals_cast_then_weigh(n):
    """`exact_models`' kernels: the casts and the weights of the two kernels in turn."""
    from robotlib.localization import _kernels
    from robotlib.localization._kernels import exact_models
    from robotlib.localization.cones import exact_arguments

    world = load_world("office")
    sonar = SonarModel()
    rng = np.random.default_rng(3)
    x0, y0, x1, y1 = world.bounds
    poses = np.concatenate([
        world.sample_free_poses(n, rng),
        np.column_stack([rng.uniform(x0 - 1, x1 + 1, n), rng.uniform(y0 - 1, y1 + 1, n),
                         rng.uniform(-4, 4, n)]),
    ])  # fmt: skip
    args = exact_arguments(world, sonar)
    zhat = np.empty((len(poses), 8))
    _kernels.expected_scan_blocks(poses, *args, zhat)
    z = np.array([0.3, 1.0, 2.2, 4.999, 5.0, 0.1, 3.3, 1.7])
    beam = (0.75, 0.1, 0.05, 0.1, 0.15, 0.5)
    ref_beam = np.empty(len(poses))
    _kernels.beam_loglik(z, zhat, 5.0, *beam, ref_beam)
    ref_paper = np.empty(len(poses))
    _kernels.paper_loglik(z, zhat, float(len(poses)), ref_paper)
    for fused in (exact_models.exact_beam, exact_models.exact_beam_parallel):
        got, got_z = np.empty(len(poses)), np.empty_like(zhat)
        fused(poses, *args, got_z, z, *beam, got)
        np.testing.assert_array_equal(got_z, zhat)
        np.testing.assert_array_equal(got, ref_beam)
    for fused in (exact_models.exact_paper, exact_models.exact_paper_parallel):
        got, got_z = np.empty(len(poses)), np.empty_like(zhat)
        fused(poses, *args, got_z, z, float(len(poses)), got)
        np.testing.assert_array_equal(got_z, zhat)
        np.testing.assert_array_equal(got, ref_paper)


@pytest.mark.parametrize(
    "kind, n, policy",
    [("beam", 40, "every"), ("beam", 300, "every"), ("beam1", 300, "threshold"),
     ("paper", 40, "threshold"), ("paper", 300, "every")],
)  # fmt: skip
def test_exact_step_in_one_call_equals_its_parts(kind, n, policy):
    """`MCL.step` on the exact path (`exact_models.exact_step`): the four stages' bits.

    40 particles: the serial call; 300: the threaded one. "every": resampled
    in the call; "threshold": by the policy afterwards (when the ESS is low).
    """
    from robotlib.localization import (
        MCL,
        BeamParameters,
        BeamSensorModel,
        PaperSensorModel,
        ThresholdResampling,
    )

    world = load_world("office")

    def make():
        sensor = (
            PaperSensorModel(world)
            if kind == "paper"
            else BeamSensorModel(
                world, params=BeamParameters(exponent=0.2 if kind == "beam" else 1.0)
            )
        )
        resampling = (
            ThresholdResampling("systematic", 1.0)
            if policy == "every"
            else ThresholdResampling("systematic", 0.5)
        )
        return MCL(world, sensor, resampling=resampling, n=n, rng=5, check=True)

    z = expected_readings(world, np.array([world.start]))[0]
    z[2] = 5.0  # a max reading
    odo = [np.array(world.start) + k * np.array([0.3, 0.1, 0.2]) for k in range(5)]
    a, b = make(), make()
    for k in range(4):
        est = a.step(odo[k], odo[k + 1], z).copy()
        b.predict(odo[k], odo[k + 1])
        b.update(z)
        np.testing.assert_array_equal(est, b.estimate())
        assert a.ess == b.ess and a._log_mean == b._log_mean
        b.resample()
        np.testing.assert_array_equal(a.particles, b.particles)
        np.testing.assert_array_equal(a.weights, b.weights)
    assert a.info.n_after == n
