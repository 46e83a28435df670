"""Grid FastSLAM's estimates: lineage likelihood, posterior mean path and map."""

from dataclasses import replace

import numpy as np
import pytest

from robotlib.mapping import GridFastSLAM, record_drive, run_fastslam
from robotlib.mapping.fastslam_settings import SONAR_SETTINGS
from robotlib.world.geometry import wrap_angle

LEG = [(8.0, 1.5), (12.0, 1.5)]


@pytest.fixture(scope="module")
def log():
    return record_drive("loop", LEG, seed=3, every=4)


def _filter(log, n, **kw):
    settings = replace(SONAR_SETTINGS, temperature=0.3, resample_below=0.9, **kw)
    return GridFastSLAM.for_world(
        log.world, 0.1, start=log.odometry[0], n_particles=n, sensor="sonar",
        settings=settings, sonar=log.sonar_model, rng=5,
    )  # fmt: skip


def _naive_paths(f):
    out = []
    for k0 in range(f.n):
        k, rows = k0, []
        for t in range(len(f._poses) - 1, -1, -1):
            rows.append(f._poses[t][k])
            k = int(f._parents[t][k])
        out.append(rows[::-1])
    return np.array(out)


def test_path_loglik_sums_each_lineage_and_picks_the_best(log):
    f = _filter(log, 12)
    lls = []
    weigh = f.weigh_sonar
    f.weigh_sonar = lambda p, z: lls.append(weigh(p, z)) or lls[-1]
    for t in range(len(log)):
        f.step(log.odometry[t], log.sonar[t])
    assert f.resampled > 0
    # the reference: follow each final particle's ancestry, adding its ll
    want = np.zeros(f.n)
    for n in range(f.n):
        k = n
        # row u of the history is record u - 1 after its resampling; its
        # parent was weighed at that record (lls[u - 2]; record 0 is not)
        for u in range(len(f._poses) - 1, 1, -1):
            k = int(f._parents[u][k])
            want[n] += lls[u - 2][k]
    np.testing.assert_allclose(f.path_loglik, want, rtol=1e-12)
    assert f.best() == int(np.argmax(want))
    f.settings = replace(f.settings, best_by="weight")
    assert f.best() == int(np.argmax(f.logw))
    with pytest.raises(ValueError, match="best_by"):
        _filter(log, 2, best_by="max")
    with pytest.raises(ValueError, match="estimate"):
        _filter(log, 2, estimate="median")


def test_mean_path_is_the_weighted_mean_of_the_lineages(log):
    f = _filter(log, 10)
    for t in range(len(log)):
        f.step(log.odometry[t], log.sonar[t])
    paths = _naive_paths(f)
    np.testing.assert_array_equal(f.paths(), paths)
    w = f.weights
    mean = f.mean_path()
    np.testing.assert_allclose(mean[:, :2], (w[:, None, None] * paths[:, :, :2]).sum(0))
    # headings: the mean direction, within the spread of the lineages
    c = (w[:, None] * np.cos(paths[:, :, 2])).sum(0)
    s = (w[:, None] * np.sin(paths[:, :, 2])).sum(0)
    np.testing.assert_allclose(wrap_angle(mean[:, 2] - np.arctan2(s, c)), 0, atol=1e-12)
    assert len(np.unique(paths[:, -1, 0])) > 1  # the lineages differ


def test_mean_map_of_one_particle_is_its_map(log):
    f = _filter(log, 1)
    for t in range(len(log)):
        f.step(log.odometry[t], log.sonar[t])
    np.testing.assert_allclose(f.mean_path(), f.best_path(), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(f.mean_map(log.sonar).logodds, f.maps[0])
    with pytest.raises(ValueError, match="scans"):
        f.mean_map(log.sonar[:-1])


def test_sonar_run_reports_the_mean_and_is_seeded(log):
    a = run_fastslam(log, 8, "sonar", rng=2)
    b = run_fastslam(log, 8, "sonar", rng=2)
    np.testing.assert_array_equal(a.path, b.path)
    np.testing.assert_array_equal(a.map.logodds, b.map.logodds)
    np.testing.assert_array_equal(a.path, a.filter.mean_path()[1:])
    c = run_fastslam(
        log, 8, "sonar", rng=2, settings=replace(SONAR_SETTINGS, estimate="best")
    )
    np.testing.assert_array_equal(c.path, c.filter.best_path()[1:])
    np.testing.assert_array_equal(c.map.logodds, c.filter.best_map().logodds)
