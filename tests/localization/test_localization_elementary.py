"""The kernels' own ``exp`` and ``sincos`` against the C library's, ulp by ulp."""

import math

import numba as nb
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from robotlib.localization._kernels.elementary import exp, log, sincos


@nb.njit
def _exps(x, ours, libm):
    for i in range(x.shape[0]):
        ours[i] = exp(x[i])
        libm[i] = math.exp(x[i])


@nb.njit
def _sincos(x, ours, libm):
    for i in range(x.shape[0]):
        ours[i, 0], ours[i, 1] = sincos(x[i])
        libm[i, 0] = math.sin(x[i])
        libm[i, 1] = math.cos(x[i])


def _ulps(ours, libm):
    """Each difference in units of the C library's result's last place."""
    return np.abs(ours - libm) / np.spacing(np.abs(libm))


def _pair(kernel, x):
    """``kernel``'s two results (ours, the C library's) on floats ``x``."""
    x = np.asarray(x, dtype=np.float64)
    ours, libm = np.empty_like(x), np.empty_like(x)
    kernel(x, ours, libm)
    return ours, libm


def _exp_pair(x):
    return _pair(_exps, x)


def test_exp_is_within_one_ulp():
    rng = np.random.default_rng(0)
    x = np.concatenate([
        rng.uniform(-708.0, 709.7, 300_000), -rng.exponential(2.0, 300_000),
        rng.uniform(-1e-3, 1e-3, 100_000), -0.5 * rng.normal(0.0, 3.0, 100_000) ** 2,
    ])  # fmt: skip
    ours, libm = _exp_pair(x)
    assert _ulps(ours, libm).max() <= 1.0
    assert (ours == libm).mean() > 0.85  # mostly the very same number


def test_exp_edges():
    x = [np.inf, -np.inf, np.nan, 0.0, -0.0, 709.78, 709.79, -745.13, -745.14,
         -1e300, 1e300, 5e-324, -5e-324]  # fmt: skip
    ours, libm = _exp_pair(x)
    np.testing.assert_array_equal(ours, libm)


def test_exp_subnormals_are_near():
    x = np.linspace(-745.1, -708.4, 10_001)
    ours, libm = _exp_pair(x)
    assert np.abs(ours - libm).max() <= 5e-324  # at most one subnormal step


@given(st.floats(allow_nan=True, allow_infinity=True))
def test_exp_any_float(x):
    ours, libm = _exp_pair([x])
    if math.isnan(libm[0]) or math.isinf(libm[0]):
        assert ours[0] == libm[0] or math.isnan(ours[0]) and math.isnan(libm[0])
    else:
        assert abs(ours[0] - libm[0]) <= max(np.spacing(abs(libm[0])), 5e-324)


def _sincos_pair(x):
    x = np.asarray(x, dtype=np.float64)
    ours, libm = np.empty((len(x), 2)), np.empty((len(x), 2))
    _sincos(x, ours, libm)
    return ours, libm


def test_sincos_on_headings_is_within_one_ulp():
    rng = np.random.default_rng(1)
    x = np.concatenate([rng.uniform(-7.0, 7.0, 500_000), rng.normal(0.0, 1e-3, 10_000)])
    ours, libm = _sincos_pair(x)
    far = np.abs(libm) > 1e-3  # away from the zeros
    assert _ulps(ours, libm)[far].max() <= 1.0
    assert np.abs(ours - libm).max() <= np.spacing(1.0)


def test_sincos_near_multiples_of_half_pi():
    k = np.arange(-40, 41)
    x = np.concatenate([k * (math.pi / 2), np.nextafter(k * (math.pi / 2), np.inf)])
    ours, libm = _sincos_pair(x)
    assert (np.abs(ours - libm).max(axis=1) <= 1e-31 * (1.0 + np.abs(x))).all()
    assert _ulps(ours, libm)[np.abs(libm) > 0.5].max() <= 1.0


@pytest.mark.parametrize("x", [0.0, -0.0, np.inf, -np.inf, np.nan, 1e-300, -1e-300])
def test_sincos_edges(x):
    ours, libm = _sincos_pair([x])
    np.testing.assert_array_equal(ours, libm)


@given(st.floats(min_value=-1e6, max_value=1e6))
def test_sincos_any_angle(x):
    ours, libm = _sincos_pair([x])
    assert np.abs(ours - libm).max() <= 1e-15 * max(1.0, abs(x) / 1e3)


@nb.njit
def _logs(x, ours, libm):
    for i in range(x.shape[0]):
        ours[i] = log(x[i])
        libm[i] = math.log(x[i]) if x[i] > 0.0 else (-np.inf if x[i] == 0 else np.nan)


def _log_pair(x):
    return _pair(_logs, x)


def test_log_is_within_one_ulp():
    rng = np.random.default_rng(2)
    x = np.concatenate([
        rng.uniform(0.0, 10.0, 300_000), np.exp(rng.uniform(-700.0, 700.0, 300_000)),
        rng.uniform(0.5, 2.0, 200_000), 1.0 + rng.normal(0.0, 1e-6, 100_000),
        rng.uniform(0.0, 1e-310, 10_000),
    ])  # fmt: skip
    ours, libm = _log_pair(x)
    assert _ulps(ours[libm != 0], libm[libm != 0]).max() <= 1.0
    assert (ours == libm).mean() > 0.85


def test_log_edges():
    x = [0.0, -0.0, -1.0, np.inf, -np.inf, np.nan, 1.0, 5e-324, 1.7976931348623157e308]
    ours, libm = _log_pair(x)
    np.testing.assert_array_equal(ours, libm)


@given(st.floats(allow_nan=True, allow_infinity=True))
def test_log_any_float(x):
    ours, libm = _log_pair([x])
    if not math.isfinite(libm[0]):
        assert ours[0] == libm[0] or math.isnan(ours[0]) and math.isnan(libm[0])
    else:
        assert abs(ours[0] - libm[0]) <= np.spacing(abs(libm[0]))
