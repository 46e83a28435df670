"""``robotlib bench kalman``: the belief's moments and a short run."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robotlib.experiments.bench_kalman import belief_moments, bench_kalman, summary


def test_belief_moments_average_headings_across_the_wrap():
    poses = np.array([[1.0, 2.0, math.pi - 0.1], [3.0, 2.0, -math.pi + 0.1]])
    mu, P = belief_moments(poses, [1.0, 1.0], extra=(0.01, 0.0, 0.0))
    assert mu[:2] == pytest.approx([2.0, 2.0])
    assert abs(abs(mu[2]) - math.pi) < 1e-9  # not 0: the two headings straddle pi
    assert P[0, 0] == pytest.approx(1.0 + 0.01) and P[2, 2] == pytest.approx(0.01)
    assert P[0, 2] == pytest.approx(0.1)  # x and heading grow together


@pytest.mark.slow  # two whole office drives recorded
def test_a_short_run_gives_a_row_per_scenario_and_filter():
    rows = bench_kalman(seeds=1, every=4, steps=12, filters=("EKF landmarks",))
    assert [r["scenario"] for r in rows] == ["track", "wrong start", "kidnap"]
    track = summary(rows)[0]
    assert track["error_m"] < 0.2 and track["ended_within_0.3"] == 1
    assert 0 <= track["nees_in_band"] <= 1 and track["cpu_ms_per_step"] > 0
