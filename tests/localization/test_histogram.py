"""Histogram (grid) localization: kernels against plain loops, filters localize."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from robotlib.experiments import drive_route
from robotlib.localization import BEST, BeamParameters, BeamSensorModel
from robotlib.localization.histogram import (
    GridFilter,
    HistogramFilter1D,
    predict_1d,
    shift_kernel,
    update,
)
from robotlib.world import load_world


def naive_predict(belief, shift, sigma, res):
    """Each cell's mass spread by the Gaussian integrated over each target cell."""
    n = len(belief)
    out = np.zeros(n)
    for i in range(n):
        for j in range(n):
            lo = ((j - i) - 0.5) * res - shift
            hi = ((j - i) + 0.5) * res - shift
            s2 = sigma * 2**0.5
            w = 0.5 * (math.erf(hi / s2) - math.erf(lo / s2))
            out[j] += belief[i] * w
    return out / out.sum()


@given(
    st.lists(st.floats(0.0, 1.0), min_size=20, max_size=40),
    st.floats(-0.5, 0.5),
    st.floats(0.05, 0.5),
)
def test_predict_matches_the_plain_loop(b, shift, sigma):
    b = np.array(b) + 1e-3
    b /= b.sum()
    got = predict_1d(b, shift, sigma, 0.1)
    ref = naive_predict(b, shift, sigma, 0.1)
    assert got == pytest.approx(ref, abs=1e-6)
    assert got.sum() == pytest.approx(1.0)


def test_kernel_mean_and_mass():
    kmin, w = shift_kernel(0.37, 0.2, 0.05)
    k = kmin + np.arange(len(w))
    assert w.sum() == pytest.approx(1.0)
    assert (k * w).sum() * 0.05 == pytest.approx(0.37, abs=1e-3)
    assert shift_kernel(0.26, 0.0, 0.1) == (3, pytest.approx(np.ones(1)))


def test_update_is_bayes_rule():
    prior = np.array([0.1, 0.2, 0.3, 0.4])
    lk = np.array([4.0, 0.0, 1.0, 1.0])
    assert update(prior, lk) == pytest.approx(prior * lk / (prior * lk).sum())
    assert update(prior, np.zeros(4)) == pytest.approx(np.full(4, 0.25))
    with pytest.raises(ValueError):
        update(prior, -lk)


@pytest.fixture(scope="module")
def corridor():
    world = load_world("corridor")
    sensor = BeamSensorModel(world, fast=True, params=BeamParameters(**BEST["beam"]))
    return world, sensor, drive_route(world, seed=1, n_steps=12)


def test_1d_filter_localizes_in_the_corridor(corridor):
    world, sensor, route = corridor
    f = HistogramFilter1D(world, sensor, y=world.start[1])
    errors = []
    for k in range(len(route)):
        x = f.step(route.odometry[max(k - 1, 0)], route.odometry[k], route.sonar[k])
        errors.append(abs(x - route.truth[k, 0]))
    assert f.belief.sum() == pytest.approx(1.0)
    assert max(errors[4:]) < 0.3


def test_grid_filter_localizes_and_keeps_mass_on_free_space(corridor):
    world, sensor, route = corridor
    g = GridFilter(world, sensor, resolution=0.25, n_headings=24)
    for k in range(len(route)):
        est = g.step(route.odometry[max(k - 1, 0)], route.odometry[k], route.sonar[k])
    assert g.belief.sum() == pytest.approx(1.0)
    assert g.belief[:, ~g.free].sum() == 0.0
    assert math.hypot(*(est[:2] - route.truth[-1, :2])) < 0.4
    before = g.position_belief().copy()
    g.predict([0, 0, 0], [0, 0, 0])  # no motion: only the blur
    assert g.position_belief().argmax() == before.argmax()
