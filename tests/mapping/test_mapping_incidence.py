"""Sonar walls chosen per reading by the angle of incidence in a particle's map."""

import math
from dataclasses import replace

import numpy as np

from robotlib.mapping import SONAR_SETTINGS, GridFastSLAM, record_drive, run_fastslam
from robotlib.mapping import _kernels_incidence as kin
from tests import naive_mapping as naive

ORIGIN = (0.0, 0.0)
RES = 0.1
INCIDENCE = replace(SONAR_SETTINGS, sonar_incidence=0.35)


def _numpy_incidence(L, pose, sensors, ranges, max_range, g_min):
    """Plain NumPy version of `sonar_incidence_many` for one map and pose."""
    r = kin.GRADIENT_RADIUS
    out = np.full(len(sensors), np.nan)
    d = np.arange(-r, r + 1)
    c, s = math.cos(pose[2]), math.sin(pose[2])
    for k, ((ax, ay, ah), z) in enumerate(zip(sensors, ranges, strict=True)):
        if z >= max_range:
            continue
        u = np.array([math.cos(pose[2] + ah), math.sin(pose[2] + ah)])
        p = np.array([pose[0] + c * ax - s * ay, pose[1] + s * ax + c * ay]) + z * u
        j, i = np.floor((p - ORIGIN) / RES).astype(int)
        if i < r or j < r or i >= L.shape[0] - r or j >= L.shape[1] - r:
            continue
        w = np.clip(L[i - r : i + r + 1, j - r : j + r + 1].astype(float), -3, 3)
        g = np.array([(w * d[None, :]).sum(), (w * d[:, None]).sum()])
        if np.hypot(*g) >= g_min:
            out[k] = abs(u @ g) / np.hypot(*g)
    return out


def _wall_map():
    """A 4 m x 4 m grid: free below y = 3 m, a wall row at y = 3 m, unknown above."""
    L = np.zeros((40, 40), dtype=np.float32)
    L[:30] = -2.0
    L[30] = 4.0
    return L


def test_incidence_matches_numpy_and_the_walls_direction():
    L = _wall_map()
    maps = np.stack([L, L.T.copy()])  # the second: the wall at x = 3 m
    sensors = np.array([[0.0, 0.0, a] for a in np.radians([90, 50, 30, 0, -90])])
    poses = np.array([[2.0, 1.0, 0.0], [1.0, 2.0, -math.pi / 2]])
    z = np.array([2.05, 2.05 / math.sin(math.radians(50)), 4.1, 1.5, 5.0])
    out = np.empty((2, 5))
    kin.sonar_incidence_many(maps, *ORIGIN, RES, poses, sensors, z, 5.0, 3.0, out)
    for n in range(2):
        want = _numpy_incidence(maps[n], poses[n], sensors, z, 5.0, 3.0)
        np.testing.assert_allclose(out[n], want, atol=1e-12)
    # facing the wall: cos 1; 40 degrees off its normal: cos 40 degrees; into
    # free space (no gradient there) or a max-range reading: NaN
    assert out[0, 0] == 1.0
    assert math.isclose(out[0, 1], math.cos(math.radians(40)), abs_tol=0.15)
    assert np.isnan(out[0, 3]) and np.isnan(out[0, 4])
    # the same wall turned a quarter, seen from the turned pose: the same cosines
    np.testing.assert_allclose(out[1, :2], out[0, :2], atol=1e-12)


def test_marks_update_matches_the_reference_per_reading():
    rng = np.random.default_rng(7)
    sensors = GridFastSLAM((1, 1), ORIGIN, RES, (0, 0, 0), sensor="sonar").sonar
    s, m = sensors, GridFastSLAM((1, 1), ORIGIN, RES, (0, 0, 0)).settings.sonar_model
    poses = np.column_stack([rng.uniform(1.5, 3.5, 3), rng.uniform(1.5, 3.5, 3),
                             rng.uniform(-3, 3, 3)])  # fmt: skip
    z = rng.uniform(0.4, 3.0, 8)
    z[2] = s.max_range
    marks = rng.random((3, 8)) < 0.5
    maps = np.zeros((3, 50, 50), dtype=np.float32)
    kin.sonar_update_marks_many(
        maps, *ORIGIN, RES, poses, s.sensors, z, marks, s.cone / 2, s.max_range,
        m.thickness, m.l_occ, m.l_free, m.sigma, m.max_weight, m.l_min, m.l_max,
    )  # fmt: skip
    for n in range(3):
        want = np.zeros((50, 50))
        for k in range(8):
            want = naive.sonar_scan(
                want, ORIGIN, RES, poses[n], s.sensors[k : k + 1], z[k : k + 1],
                s.cone / 2, s.max_range, m.thickness,
                m.l_occ if marks[n, k] else 0.0, m.l_free, m.sigma, m.max_weight,
                m.l_min, m.l_max,
            )  # fmt: skip
        np.testing.assert_allclose(maps[n], want, atol=1e-5)


def test_fastslam_with_incidence_walls_is_seeded_and_differs():
    log = record_drive("loop", [(12.0, 1.5), (19.5, 1.5), (19.5, 4.0)], seed=4,
                       every=4)  # fmt: skip
    a = run_fastslam(log, 6, "sonar", rng=2, settings=INCIDENCE)
    b = run_fastslam(log, 6, "sonar", rng=2, settings=INCIDENCE)
    np.testing.assert_array_equal(a.path, b.path)
    np.testing.assert_array_equal(a.map.logodds, b.map.logodds)
    c = run_fastslam(log, 6, "sonar", rng=2)
    assert not np.array_equal(a.map.logodds, c.map.logodds)
