"""The MCL object, the history, the experiment runner and its CLI (few steps)."""

import json

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from robotlib import experiments as experiment  # noqa: E402
from robotlib.cli import main  # noqa: E402
from robotlib.localization import (  # noqa: E402
    MCL,
    BeamSensorModel,
    History,
    KLDResampling,
    localized_step,
)
from robotlib.plotting.mcl import (  # noqa: E402
    plot_error,
    plot_particle_count,
    plot_trajectories,
)
from robotlib.world import load_world  # noqa: E402


@pytest.fixture(scope="module")
def corridor():
    return load_world("corridor")


@pytest.fixture(scope="module")
def route(corridor):
    return experiment.drive_route(corridor, seed=0, n_steps=12)


def test_route_is_seeded_and_moves_along(corridor, route):
    again = experiment.drive_route(corridor, seed=0, n_steps=12)
    np.testing.assert_array_equal(route.odometry, again.odometry)
    np.testing.assert_array_equal(route.sonar, again.sonar)
    assert route.truth[-1, 0] - route.truth[0, 0] > 3.0  # east along the corridor
    assert route.sonar.shape == (12, 8)


def test_localized_step():
    assert localized_step([1, 1, 0.2, 0.3]) == 3
    assert localized_step([0.1, 0.6, 0.1]) == 3
    assert localized_step([0.1, 0.2]) == 1
    assert localized_step([0.1, 0.9]) is None


@pytest.mark.slow
@pytest.mark.parametrize("fast", [False, True])
def test_paper_filter_is_reproducible_bit_for_bit(route, fast):
    config = experiment.FilterConfig("p", "paper", {"n": 200, "fast": fast})
    a = experiment.run_filter(route, config, seed=3).arrays()
    b = experiment.run_filter(route, config, seed=3).arrays()
    for key in ("true_pose", "estimate", "error", "n_particles", "ess"):
        np.testing.assert_array_equal(a[key], b[key])
    c = experiment.run_filter(route, config, seed=4).arrays()
    assert not np.array_equal(a["estimate"], c["estimate"])


def test_paper_resize_shrinks_population(route):
    config = experiment.FilterConfig("p", "paper", {"n": 300, "lam": 2.0, "floor": 80})
    hist = experiment.run_filter(route, config, seed=0)
    n = hist.arrays()["n_particles"]
    assert n[0] == 300 and np.all(np.diff(n) <= 0) and n[-1] >= 80 and n[-1] < 300


def test_tracking_from_start_stays_close(route):
    for config in (experiment.PAPER, experiment.BEST_CONFIG):
        hist = experiment.run_filter(route, config, seed=1, tracking=True)
        assert hist.error.mean() < 0.25


def test_kld_population_falls_when_tracking(corridor, route):
    mcl = MCL(
        corridor,
        BeamSensorModel(corridor, fast=True),
        resampling=KLDResampling(n_min=100, n_max=3000),
        n=3000,
        rng=0,
        init=route.truth[0],
    )
    for k in range(1, 6):
        mcl.step(route.odometry[k - 1], route.odometry[k], route.sonar[k])
    assert 100 <= mcl.n < 3000


def test_summary_and_plots(route):
    runs = [experiment.run_filter(route, experiment.PAPER, seed=s) for s in (0, 1)]
    track = [experiment.run_filter(route, experiment.PAPER, 0, tracking=True)]
    summary = experiment.summarize(runs, track, experiment.PAPER)
    for key in (
        "success_rate",
        "success_rate_75",
        "localized_step_median",
        "tracking_error_mean_m",
        "tracking_error_std_m",
        "tracking_from_start_error_mean_m",
        "particles_final_median",
        "ms_per_step_median",
        "settings",
    ):
        assert key in summary
    assert 0 <= summary["success_rate"] <= summary["success_rate_75"] <= 1
    fig, axes = plt.subplots(1, 3)
    plot_trajectories(axes[0], runs[0], route.world)
    plot_error(axes[1], track[0])
    plot_particle_count(axes[2], runs[0])
    assert len(axes[1].lines) >= 2 and axes[2].get_ylabel() == "particles"
    plt.close(fig)


def test_history_record_and_dict(route):
    mcl = MCL.paper(route.world, n=50, rng=0)
    hist = History()
    for k in range(3):
        mcl.step(route.odometry[max(k - 1, 0)], route.odometry[k], route.sonar[k])
        hist.record(route.truth[k], mcl, 1.0)
    d = hist.to_dict()
    assert d["step"] == [1, 2, 3] and len(d["estimate"]) == 3
    json.dumps(d)


def test_reproduce_cli_writes_json(tmp_path, monkeypatch):
    small = experiment.FilterConfig("best", "best", {"n": 500, "kld": {"n_max": 500}})
    monkeypatch.setattr(experiment, "BEST_CONFIG", small)
    out = tmp_path / "r.json"
    assert main(["reproduce", "--seeds", "1", "--steps", "4", "--json", str(out)]) == 0
    result = json.loads(out.read_text())
    assert set(result) >= {"paper", "best"}
    assert result["paper"]["settings"]["n"] == 300
    assert "success_rate" in result["best"]


@pytest.mark.parametrize("seed", [0, 1])
def test_best_localizes_globally_in_the_corridor(corridor, seed):
    """The best configuration finds the robot from a uniform start by step 15.

    (Over 20 seeds `robotlib reproduce` measured every corridor run localized by
    step 13; the corridor's door sequence at the west end is unique.)
    """
    route = experiment.drive_route(corridor, seed=seed, n_steps=20)
    hist = experiment.run_filter(route, experiment.BEST_CONFIG, seed)
    step = hist.localized_step(experiment.TOLERANCE)
    assert step is not None and step <= 15
    assert hist.error[step - 1 :].mean() < 0.15
    assert hist.n_particles[0] == 50_000 and hist.n_particles[-1] < 2000


def test_periodic_corridor_fools_the_best_filter_early():
    """In the exactly periodic corridor the first 10 steps cannot be told apart.

    The filter's particles stay split over look-alike places (4 m apart, or
    turned round), so the estimate is not localized at step 10.
    """
    world = load_world("corridor_periodic")
    route = experiment.drive_route(world, seed=0, n_steps=10)
    hist = experiment.run_filter(route, experiment.BEST_CONFIG, 0)
    assert hist.error[-1] > 0.5 and hist.n_particles[-1] > 1000


@pytest.mark.slow
def test_bench_mcl_cli_writes_json(tmp_path):
    """The bench runs (tiny sizes) and reports median and fastest per path."""
    out = tmp_path / "b.json"
    args = ["bench", "mcl", "--n", "50", "--reps", "2", "--table-world", ""]
    assert main([*args, "--no-first-step", "--no-peers", "--json", str(out)]) == 0
    results = json.loads(out.read_text())["results"]
    assert {r["path"] for r in results} == {"robotlib", "exact", "plain"}
    assert all(0 < r["ms_min"] <= r["ms_per_step"] for r in results)


@pytest.mark.slow
def test_bench_buildings_times_the_set_up_and_the_step_in_a_fresh_process():
    """A small building: the fast path, its parts, its peak and a timed step."""
    from robotlib.experiments.bench_buildings import bench_building, verdict

    r = bench_building(8.0, timeout=300, steps=[40])
    assert "error" not in r and r["walls"] > 4
    assert 0 < r["table_mb"] and r["ready_peak_mb"] >= r["table_mb"] / 1.048576
    assert all(r[k] >= 0 for k in ("free_space_s", "cone_table_s", "mcl_best_s"))
    (step,) = r["steps"]
    assert step["path"] == "fast" and step["n"] == 40
    assert 0 < step["ms_min"] <= step["ms_per_step"]
    assert verdict(r) is None  # no target for 8 m


def test_bench_buildings_verdict_against_the_targets():
    from robotlib.experiments.bench_buildings import verdict

    fast = {"free_space_s": 0.1, "cone_table_s": 1.0, "mcl_best_s": 0.1}
    assert verdict({"side_m": 50.0, **fast, "ready_peak_mb": 286.0}).startswith(
        "target ready in 3 s and 300 MB: met with the fast path: ready in 1.20 s "
        "at 300 MB (286 MiB)"
    )  # MiB measured, MB the target's unit
    assert "MISSED" in verdict({"side_m": 50.0, **fast, "ready_peak_mb": 287.0})
    assert "MISSED" in verdict({"side_m": 50.0, **fast, "cone_table_s": 2.9,
                                "ready_peak_mb": 200.0})  # fmt: skip
    exact = {"free_space_s": 0.4, "mcl_best_exact_s": 0.3}
    text = verdict({"side_m": 200.0, "error": "too large", **exact,
                    "cone_table_s": 0.0, "ready_peak_mb": 300.0})  # fmt: skip
    assert text.startswith("target ready in 30 s and 1500 MB: met with the exact")
    assert "ready in 0.70 s" in text
    assert "did not finish" in verdict({"side_m": 200.0, "timeout": 120.0})


def test_bench_plain_pipeline_is_the_fast_beam_model():
    """The bench's plain numba pipeline computes the library's beam model."""
    from robotlib.experiments.bench_mcl import _plain_pipeline
    from robotlib.localization import BeamParameters, BeamSensorModel
    from robotlib.world import load_world

    plain = _plain_pipeline()
    world = load_world("corridor")
    params = BeamParameters(exponent=0.2)
    model = BeamSensorModel(world, fast=True, params=params)
    t = model.table
    particles = world.sample_free_poses(500, rng=3)
    z = model.expected(np.array([world.start]))[0]
    z[2] = 5.0  # one max reading
    mm = np.empty((500, 8), dtype=np.int64)
    plain.expected(particles, t.sonar.sensors, t.table, *t.origin, 20.0, mm)
    np.testing.assert_allclose(mm * 0.001, model.expected(particles))
    ll = np.empty(500)
    q = (params.sigma_hit, params.lambda_short, params.z_max, params.z_rand / 5.0,
         5.0, params.exponent)  # fmt: skip
    plain.beam_loglik(mm, z, model._hit_norm, model._short_norm, np.array(q), ll)
    np.testing.assert_allclose(ll, model.log_likelihood(particles, z), rtol=1e-12)


@pytest.mark.slow  # one generated world, three ways (its cone table)
def test_bench_worlds_rows_plain_localized_and_planned():
    from robotlib.experiments.bench_worlds import bench_rows

    aims = ("", "+MCL", "+MCL+A*")
    rows = bench_rows(["traps"], ["VFH"], n_worlds=1, n_pairs=2, aims=aims)
    assert [r["controller"] for r in rows] == ["VFH", "VFH+MCL", "VFH+MCL+A*"]
    for r in rows:
        assert r["episodes"] == 2 and r["collisions"] == 0
        assert 0 <= r["true_success"] <= r["odometry_success"] <= 1
