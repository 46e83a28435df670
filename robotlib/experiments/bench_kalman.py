"""``robotlib bench kalman``: EKF localization against the histogram filter and MCL.

``robotlib bench kalman [--seeds N] [--every K] [--steps T] [--json FILE]``
records, per seed, one office drive (`record_drive`, a record every 0.5 s,
then every ``K``-th kept, the first ``T`` used) and runs on it, in three
scenarios:

- ``track``: every filter starts around the true start (the EKFs 0.3 m and
  0.1 rad off with a covariance covering that; MCL's particles and the grid's
  belief drawn from the same Gaussian);
- ``wrong start``: the EKFs start 3 m and 1 rad off, MCL and the grid know
  nothing (uniform over the free space: global localization);
- ``kidnap``: as ``track``, but halfway the robot is carried to the start of
  another seed's drive and goes on with that drive (the odometry does not
  see the jump).

The filters: the EKF on the corner landmarks (known identities,
`landmark_update`), the EKF on the laser (`laser_update`), the 2-D grid
filter (`GridFilter`, 0.2 m cells, 36 headings) and `MCL.best` with random
injection (augmented MCL, ``grow=50_000``); the grid and MCL weigh the sonar
with the tempered beam model (the course's filters), so the sensors differ.

Each row gives the mean position error of each filter's own estimate (the
EKF's mean, the grid's most probable cell, MCL's estimate) over the whole
run for ``track``, over the last half otherwise; whether the filter ends
within 0.3 m; the NEES's share of steps inside its two-sided 95 % band and
below its upper bound (for the grid and MCL from the belief's own mean and
covariance, the cell's size added for the grid); and the CPU milliseconds
of the filter's step (all threads).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

__all__ = ["add_arguments", "run", "bench_kalman", "belief_moments"]

START_STD = np.array([0.3, 0.3, 0.1])
WRONG = np.array([3.0, 0.0, 1.0])
SCENARIOS = ("track", "wrong start", "kidnap")
FILTERS = ("EKF landmarks", "EKF laser", "grid 2-D", "MCL augmented")


def belief_moments(poses, weights, extra=(0.0, 0.0, 0.0)):
    """Mean and covariance of a weighted set of poses (heading wrapped at its mean).

    Parameters
    ----------
    poses : array_like, shape (N, 3)
    weights : array_like, shape (N,)
        Non-negative, not all zero.
    extra : sequence of float
        Variances added on the diagonal (a cell's own spread), m² and rad².

    Returns
    -------
    mu : numpy.ndarray, shape (3,)
    P : numpy.ndarray, shape (3, 3)
    """
    from ..world import wrap_angle

    p = np.asarray(poses, dtype=float)
    w = np.asarray(weights, dtype=float)
    w = w / w.sum()
    th = math.atan2(float(w @ np.sin(p[:, 2])), float(w @ np.cos(p[:, 2])))
    d = p - np.array([0.0, 0.0, th])
    d[:, 2] = wrap_angle(d[:, 2])
    m = w @ d
    e = d - m
    P = (e * w[:, None]).T @ e + np.diag(extra)
    return np.array([m[0], m[1], wrap_angle(th + m[2])]), P


def _drives(seed: int, every: int, steps: int | None):
    from ..mapping.drive import record_drive

    cut = slice(None, steps)
    a = record_drive("office", seed=seed, every=5, laser=True).every(every)
    b = record_drive("office", seed=seed + 1000, every=5, laser=True).every(every)
    return [
        type(d)(
            d.world,
            d.odometry[cut],
            d.truth[cut],
            d.sonar[cut],
            d.laser[cut],
            d.sonar_model,
            d.laser_model,
            d.time[cut],
        )
        for d in (a, b)
    ]


def _kidnapped(a, b):
    """Half of drive ``a``, then drive ``b`` from its start; the jump's index."""
    half = len(a) // 2
    keys = ("truth", "odometry", "sonar", "laser")
    return {
        k: np.concatenate([getattr(a, k)[:half], getattr(b, k)]) for k in keys
    }, half


class _EKF:
    def __init__(self, world, log, laser: bool, start, seed: int):
        from ..mapping.ekfslam import RangeBearingSensor, world_landmarks

        self.world, self.laser_model, self.laser = world, log.laser_model, laser
        self.corners, self.sensor = world_landmarks(world), RangeBearingSensor()
        self.rng = np.random.default_rng([seed, 7])
        self.mu, self.P = np.array(start, dtype=float), np.diag(START_STD**2)

    def step(self, odo_prev, odo_now, k, run):
        from ..localization.ekf import ekf_predict, landmark_update, laser_update
        from ..mapping.ekfslam import observe_landmarks

        mu, P = ekf_predict(self.mu, self.P, odo_prev, odo_now)
        if self.laser:
            mu, P, _, _ = laser_update(
                mu, P, run["laser"][k], self.world, self.laser_model
            )
        else:
            ids, z = observe_landmarks(
                self.corners, run["truth"][k], self.sensor, self.world, self.rng
            )
            s = self.sensor
            mu, P, _ = landmark_update(
                mu, P, z, self.corners[ids], s.range_std, s.bearing_std
            )
        self.mu, self.P = mu, P
        return mu

    def moments(self):
        return self.mu, self.P


class _Sampled:
    """The grid filter or MCL: its own estimate, and its belief's moments."""

    def __init__(self, world, kind: str, start, seed: int):
        from ..localization import BEST, MCL, BeamParameters, BeamSensorModel
        from ..localization.histogram import GridFilter

        if kind == "grid 2-D":
            sensor = BeamSensorModel(
                world, fast=True, params=BeamParameters(**BEST["beam"])
            )
            self.f = GridFilter(world, sensor)
            if start is not None:
                poses, _ = self.f.weighted_poses()
                d = poses - start
                d[:, 2] = (d[:, 2] + np.pi) % (2 * np.pi) - np.pi
                b = np.zeros_like(self.f.belief)
                b[self.f.belief > 0] = np.exp(
                    -0.5 * np.sum((d / START_STD) ** 2, axis=1)
                )
                self.f.belief = b / b.sum()
        else:
            init = None if start is None else np.asarray(start, dtype=float)
            self.f = MCL.best(
                world,
                rng=seed,
                init=init,
                init_std=tuple(START_STD),
                augmented=dict(grow=50_000),
            )
        self.kind = kind

    def step(self, odo_prev, odo_now, k, run):
        return self.f.step(odo_prev, odo_now, run["sonar"][k])

    def moments(self):
        if self.kind == "grid 2-D":
            f = self.f
            r, width = f.resolution, 2 * math.pi / f.n_headings
            return belief_moments(
                *f.weighted_poses(), (r * r / 12, r * r / 12, width**2 / 12)
            )
        return belief_moments(self.f.particles, self.f.weights)


def _one(world, log, run, jump, kind, start, seed):
    from ..localization.ekf import nees, nis_band

    if kind.startswith("EKF"):
        f = _EKF(world, log, kind == "EKF laser", start, seed)
    else:
        f = _Sampled(world, kind, start, seed)
    lo, hi = nis_band(3)
    truth, odo = run["truth"], run["odometry"]
    errors, ne, cpu = [], [], 0.0
    for k in range(len(truth)):
        prev = odo[k] if k in (0, jump) else odo[k - 1]
        t0 = time.process_time()
        est = f.step(prev, odo[k], k, run)
        cpu += time.process_time() - t0
        errors.append(math.hypot(est[0] - truth[k, 0], est[1] - truth[k, 1]))
        mu, P = f.moments()
        try:
            ne.append(nees(mu, P, truth[k]))
        except np.linalg.LinAlgError:  # a belief collapsed on one cell
            ne.append(math.inf)
    cpu = 1000 * cpu / len(truth)
    e, ne = np.array(errors), np.array(ne)
    return {
        "mean_error": float(e.mean()),
        "mean_error_last_half": float(e[len(e) // 2 :].mean()),
        "ends_within_0.3": bool(e[-5:].max() < 0.3),
        "nees_in_band": float(np.mean((ne >= lo) & (ne <= hi))),
        "nees_below_upper": float(np.mean(ne <= hi)),
        "cpu_ms_per_step": cpu,
        "steps": len(e),
    }


def bench_kalman(
    seeds: int = 3, every: int = 4, steps: int | None = 150, filters=FILTERS
) -> list[dict]:
    """Run every filter in every scenario on ``seeds`` seeded office drives.

    ``every``: keep every ``every``-th record (0.5 s apart); ``steps``: the
    first so many of those (None: the whole drive).
    """
    from ..world import load_world

    world = load_world("office")
    rows = []
    for seed in range(seeds):
        a, b = _drives(seed, every, steps)
        plain = {k: getattr(a, k) for k in ("truth", "odometry", "sonar", "laser")}
        kidnap, jump = _kidnapped(a, b)
        near = a.truth[0] + np.random.default_rng(seed).normal(size=3) * START_STD
        for scenario in SCENARIOS:
            run, j = (kidnap, jump) if scenario == "kidnap" else (plain, None)
            for kind in filters:
                if scenario == "wrong start":
                    start = a.truth[0] + WRONG if kind.startswith("EKF") else None
                else:
                    start = near
                row = _one(world, a, run, j, kind, start, seed)
                rows.append({"seed": seed, "scenario": scenario, "filter": kind, **row})
    return rows


def summary(rows: list[dict]) -> list[dict]:
    """Average the rows over seeds, per scenario and filter."""
    out = []
    for scenario in SCENARIOS:
        for kind in FILTERS:
            got = [r for r in rows if r["scenario"] == scenario and r["filter"] == kind]
            if not got:
                continue
            err = "mean_error" if scenario == "track" else "mean_error_last_half"
            out.append(
                {
                    "scenario": scenario,
                    "filter": kind,
                    "seeds": len(got),
                    "error_m": float(np.mean([r[err] for r in got])),
                    "ended_within_0.3": sum(r["ends_within_0.3"] for r in got),
                    "nees_in_band": float(np.mean([r["nees_in_band"] for r in got])),
                    "nees_below_upper": float(
                        np.mean([r["nees_below_upper"] for r in got])
                    ),
                    "cpu_ms_per_step": float(
                        np.median([r["cpu_ms_per_step"] for r in got])
                    ),
                }
            )
    return out


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``robotlib bench kalman``."""
    parser.add_argument("--seeds", type=int, default=3, help="office drives")
    parser.add_argument(
        "--every", type=int, default=4, help="keep every K-th 0.5 s record"
    )
    parser.add_argument(
        "--steps", type=int, default=150, help="steps of each drive used"
    )
    parser.add_argument("--filters", nargs="+", choices=FILTERS, default=list(FILTERS))
    parser.add_argument("--json", type=Path, default=None, help="write the rows")


def run(args: argparse.Namespace) -> int:
    """Run the benchmark and print the table; return the exit status."""
    rows = bench_kalman(args.seeds, args.every, args.steps, tuple(args.filters))
    head = (
        "scenario",
        "filter",
        "seeds",
        "error m",
        "ended ok",
        "NEES band",
        "NEES<hi",
        "CPU ms",
    )
    print("{:12s} {:14s} {:>5s} {:>8s} {:>8s} {:>9s} {:>8s} {:>7s}".format(*head))  # noqa: T201
    for r in summary(rows):
        cells = (
            f"{r['scenario']:12s} {r['filter']:14s} {r['seeds']:5d}",
            f"{r['error_m']:8.3f} {r['ended_within_0.3']:8d}",
            f"{r['nees_in_band']:9.0%} {r['nees_below_upper']:8.0%}",
            f"{r['cpu_ms_per_step']:7.1f}",
        )
        print(*cells)  # noqa: T201 - a benchmark prints
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0
