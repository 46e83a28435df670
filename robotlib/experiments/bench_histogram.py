"""``robotlib bench histogram``: grid localization against MCL, error and time.

``robotlib bench histogram [--routes N] [--steps T] [--json FILE]`` runs, on
seeded routes (`drive_route`) in the corridor and the office, the 2-D grid
filter (`GridFilter`, 0.2 m cells, 36 headings, the tempered beam model of
`MCL.best`), in the corridor the 1-D filter along its centre line
(`HistogramFilter1D`), and `MCL.best` (`BEST_CONFIG`), and prints for each
the step from which the error stays below 0.5 m, the mean error from step
20 on, and the milliseconds per step.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

__all__ = ["add_arguments", "run", "bench_histogram"]


def _settled(errors, tol: float = 0.5):
    e = np.asarray(errors)
    return next((k + 1 for k in range(len(e)) if np.all(e[k:] < tol)), None)


def bench_histogram(routes: int = 3, steps: int = 40) -> list[dict]:
    """Run the three filters on ``routes`` seeded routes per world."""
    from ..localization import BEST, BeamParameters, BeamSensorModel
    from ..localization.histogram import GridFilter, HistogramFilter1D
    from ..world import load_world
    from .reproduce import BEST_CONFIG, run_filter
    from .routes import drive_route

    out = []
    for name in ("corridor", "office"):
        world = load_world(name)
        params = BeamParameters(**BEST["beam"])
        sensor = BeamSensorModel(world, fast=True, params=params)
        for seed in range(routes):
            route = drive_route(world, seed=seed, n_steps=steps)
            odo = route.odometry
            filters = {"grid 2-D": GridFilter(world, sensor)}
            if name == "corridor":
                line = HistogramFilter1D(world, sensor, world.start[1])
                filters["histogram 1-D"] = line
            for label, f in filters.items():
                t0 = time.perf_counter()
                err = []
                for k in range(len(route)):
                    est = f.step(odo[max(k - 1, 0)], odo[k], route.sonar[k])
                    if np.ndim(est) == 0:
                        err.append(abs(float(est) - route.truth[k, 0]))
                    else:
                        err.append(float(np.hypot(*(est[:2] - route.truth[k, :2]))))
                ms = 1000 * (time.perf_counter() - t0) / len(route)
                out.append(_row(name, seed, label, err, ms))
            t0 = time.perf_counter()
            h = run_filter(route, BEST_CONFIG, seed)
            ms = 1000 * (time.perf_counter() - t0) / len(route)
            out.append(_row(name, seed, "MCL.best", list(h.error), ms))
    return out


def _row(world, seed, label, err, ms) -> dict:
    return {
        "world": world,
        "seed": seed,
        "filter": label,
        "settled_step": _settled(err),
        "mean_error_from_20": float(np.mean(err[20:])) if len(err) > 20 else None,
        "ms_per_step": ms,
    }


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``robotlib bench histogram``."""
    parser.add_argument("--routes", type=int, default=3, help="routes per world")
    parser.add_argument("--steps", type=int, default=40, help="steps per route")
    parser.add_argument("--json", type=Path, default=None, help="write the rows")


def run(args: argparse.Namespace) -> int:
    """Run the benchmark and print a table; return the exit status."""
    rows = bench_histogram(args.routes, args.steps)
    head = ("world", "seed", "filter", "settled", "error", "ms/step")
    print("{:9s} {:>4s} {:14s} {:>7s} {:>7s} {:>8s}".format(*head))  # noqa: T201
    for r in rows:
        err = r["mean_error_from_20"]
        print(  # noqa: T201 - a benchmark prints
            f"{r['world']:9s} {r['seed']:4d} {r['filter']:14s} "
            f"{r['settled_step'] or '-':>7} {err if err is None else round(err, 3):>7} "
            f"{r['ms_per_step']:8.1f}"
        )
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0
