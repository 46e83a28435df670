"""Rewritten kernels against the ones they replace: the same numbers, bit for bit."""

import math

import numba as nb
import numpy as np
import pytest

from robotlib.localization._kernels.exact import cone_echo_rays
from robotlib.localization._kernels.fused import _flat_index
from robotlib.localization._kernels.tables import table_bin
from robotlib.sensing import SonarModel
from robotlib.sensing._kernels import cone_echo


@nb.njit
def _echoes_both(cones, walls, counts, n_rays, cone, max_range, cos_specular):
    out = np.empty((cones.shape[0], 2))
    ray = np.empty((4, max(n_rays, 1)))
    for k in range(cones.shape[0]):
        w = walls[k, : counts[k]]
        sx, sy, sth = cones[k, 0], cones[k, 1], cones[k, 2]
        out[k, 0] = cone_echo(sx, sy, sth, w, n_rays, cone, max_range, cos_specular)
        out[k, 1] = cone_echo_rays(
            sx, sy, sth, walls[k], counts[k], n_rays, cone, max_range, cos_specular,
            ray,
        )  # fmt: skip
    return out


@pytest.mark.parametrize("n_rays", [1, 2, 7, 9])
def test_cone_echo_rays_equals_cone_echo(n_rays):
    """Random walls, repeated walls, walls through the apex, parallel walls."""
    rng = np.random.default_rng(n_rays)
    k, m = 4000, 10
    cones = np.column_stack(
        [rng.uniform(-1, 1, k), rng.uniform(-1, 1, k), rng.uniform(-4, 4, k)]
    )
    walls = rng.uniform(-3, 3, (k, m, 4))
    walls[::5, 1] = walls[::5, 0]  # the same wall twice: the first one wins
    walls[::7, 2, :2] = cones[::7, :2]  # a wall starting at the apex
    walls[::11, 3] = [-2.0, 0.5, 2.0, 0.5]  # axis-parallel walls
    walls[::11, 4] = [0.5, -2.0, 0.5, 2.0]
    walls[::13, 5] = np.round(walls[::13, 5])  # whole-number end points
    counts = rng.integers(0, m + 1, k)
    sonar = SonarModel()
    out = _echoes_both(
        cones, walls, counts, n_rays, sonar.cone, sonar.max_range, sonar.cos_specular
    )
    assert np.isfinite(out[:, 0]).sum() > 100  # echoes were found
    np.testing.assert_array_equal(out[:, 0], out[:, 1])


@nb.njit
def _indexes_both(poses, sensors, ny, nx, n_bins, x0, y0, inv_res):
    out = np.empty((poses.shape[0], sensors.shape[0], 2), dtype=np.int64)
    bins = n_bins / (2.0 * math.pi)
    for j in range(poses.shape[0]):
        x, y, th = poses[j, 0], poses[j, 1], poses[j, 2]
        c = math.cos(th)
        s = math.sin(th)
        for i in range(sensors.shape[0]):
            row, col, b = table_bin(x, y, th, c, s, sensors, i, ny, nx, n_bins, x0, y0,
                                    inv_res)  # fmt: skip
            out[j, i, 0] = (row * nx + col) * n_bins + b
            out[j, i, 1] = _flat_index(
                x + c * sensors[i, 0] - s * sensors[i, 1],
                y + s * sensors[i, 0] + c * sensors[i, 1],
                (th + sensors[i, 2]) * bins, ny, nx, n_bins, x0, y0, inv_res,
            )  # fmt: skip
    return out


def test_flat_index_equals_table_bin():
    """Inside, outside and on the edges of the grid, headings over several turns."""
    rng = np.random.default_rng(0)
    n = 20000
    poses = np.column_stack(
        [rng.uniform(-3, 12, n), rng.uniform(-3, 9, n), rng.uniform(-7, 13, n)]
    )
    poses[::9, :2] = np.round(poses[::9, :2] * 20) / 20  # on cell boundaries
    poses[::17, 2] = np.round(poses[::17, 2] / (2 * np.pi / 72)) * (2 * np.pi / 72)
    sensors = SonarModel().sensors
    out = _indexes_both(poses, sensors, 120, 180, 72, 0.0, 0.0, 20.0)
    np.testing.assert_array_equal(out[..., 0], out[..., 1])


# -- the chunked and one-call MCL steps against the kernels they replace -----------


@pytest.fixture(scope="module")
def corridor():
    from robotlib.world import load_world

    return load_world("corridor")


def _scan(world):
    from robotlib.localization import expected_readings

    z = expected_readings(world, np.array([world.start]))[0]
    z[3] = 5.0  # a max reading (skipped by the beam model's lookups)
    return z


def _filters(world, n, kind):
    from robotlib.localization import (
        MCL,
        BeamParameters,
        BeamSensorModel,
        PaperSensorModel,
        ThresholdResampling,
    )

    def make(seed):
        sensor = (
            BeamSensorModel(world, fast=True, params=BeamParameters(exponent=0.2))
            if kind == "beam"
            else PaperSensorModel(world, fast=True)
        )
        return MCL(
            world, sensor, resampling=ThresholdResampling("systematic", 1.0), n=n,
            rng=seed, check=True,
        )  # fmt: skip

    return make


@pytest.mark.parametrize("kind", ["beam", "paper"])
@pytest.mark.parametrize("n", [300, 5000, 20000, "openmp"])
def test_fused_resampling_step_equals_its_parts(corridor, kind, n, monkeypatch):
    """Resampled in the step's own call (one call, or chunks on threads): same bits.

    300: one serial call; 5000: noise drawn first, then chunks; 20000:
    noise drawn chunk by chunk inside the step; "openmp": 20000 on numba's
    threaded kernels (`stepping.OPENMP_MIN` lowered for the test).
    """
    if n == "openmp":
        from robotlib.localization import stepping

        monkeypatch.setattr(stepping, "OPENMP_MIN", 10_000)
        n = 20000
    make = _filters(corridor, n, kind)
    z = _scan(corridor)
    odo = [np.array(corridor.start) + k * np.array([0.3, 0.0, 0.05]) for k in range(4)]
    a, b = make(3), make(3)
    for k in range(3):
        est = a.step(odo[k], odo[k + 1], z).copy()
        b.predict(odo[k], odo[k + 1])
        b.update(z)
        np.testing.assert_array_equal(est, b.estimate())
        assert a.ess == b.ess and a._log_mean == b._log_mean
        b.resample()
        np.testing.assert_array_equal(a.particles, b.particles)
        np.testing.assert_array_equal(a.weights, b.weights)
    assert a.info.resampled and a.info.n_after == n


def test_lut_part_equals_beam_scan_lut(corridor):
    from robotlib.localization import BeamParameters, BeamSensorModel, _kernels
    from robotlib.localization.stepping import beam_lut

    model = BeamSensorModel(corridor, fast=True, params=BeamParameters(exponent=0.2))
    m = model._model(_scan(corridor))
    ref = np.empty((len(m[0]), len(model._norms[0])))
    _kernels.beam_scan_lut(*m, ref)
    np.testing.assert_array_equal(beam_lut(m, ref.shape[1]), ref)


@pytest.mark.parametrize("kind", ["beam", "paper"])
def test_chunk_rows_equal_the_threaded_kernels(corridor, kind):
    """`run_step` over 1 and 2 threads against `lut_table_step_parallel` & co."""
    from robotlib.localization import (
        BeamParameters,
        BeamSensorModel,
        PaperSensorModel,
        _kernels,
    )

    n = 9000
    rng = np.random.default_rng(5)
    p = corridor.sample_free_poses(n, 6)
    w = rng.random(n)
    w /= w.sum()
    noise = rng.standard_normal((n, 3))
    motion = (0.1, 0.3, -0.05, 0.02, 0.03, 0.01)
    z = _scan(corridor)
    model = (
        BeamSensorModel(corridor, fast=True, params=BeamParameters(exponent=0.2))
        if kind == "beam"
        else PaperSensorModel(corridor, fast=True)
    )
    table, where = model._where()
    s = model.sonar.sensors
    ref_p, ref_w = np.empty((n, 3)), np.empty(n)
    cs, mm = np.empty((n, 2)), np.empty((n, len(z)), dtype=np.int32)
    if kind == "beam":
        m = model._model(z)
        lut = np.empty((len(z), len(model._norms[0])))
        _kernels.beam_scan_lut(*m, lut)
        ref = _kernels.lut_table_step_parallel(
            p, noise, motion, s, table, where, lut, m[2], 0.2, w, ref_p, ref_w, cs, mm
        )
    else:
        k = np.arange(int(round(model.sonar.max_range * 1000)) + 1)
        terms = np.abs((z[:, None] - k * 0.001) / z[:, None])
        ref = _kernels.paper_lut_step_parallel(
            p, noise, motion, s, table, where, terms, 1.0 / n, w, ref_p, ref_w, cs, mm
        )
    threads = nb.get_num_threads()
    try:
        for t in sorted({1, threads}):
            nb.set_num_threads(t)
            got = model._step(p, w, motion, noise, z)
            np.testing.assert_array_equal(got[0], ref_p)
            np.testing.assert_array_equal(got[1], ref_w)
            assert got[2:4] == ref[:2]
            np.testing.assert_array_equal(got[4], ref[2])
    finally:
        nb.set_num_threads(threads)
