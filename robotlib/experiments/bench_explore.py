"""``robotlib bench explore``: coverage against time for teams of 1-4 robots.

``robotlib bench explore [--robots 1,2,3] [--seeds 10] [--worlds building
office gen-office gen-hall] [--sensor laser] [--pose true] [--strategy
coordinated] [--max-time 1200] [--json [FILE]]`` explores each world with
each team size once per seed (`robotlib.exploration.explore_team`; a named
world is the same map every seed, only the noise changes; ``gen-KIND`` is a
fresh `robotlib.world.generate_world` of that kind per seed, seeded
``[seed, kind]``, so nothing is tuned to one map) and prints, per world and
team size: the mean and least explored fraction of the reachable free
area, the mean map F1 against the true walls, the median simulated time to
90 % and 99 % explored, the median ratio of the time to 90 % to one robot's
on the same seed, the mean coverage after 60/120/240 s, collisions (wall
and robot, summed), the runs that came home, and the mean wall-clock
seconds per run (one process, one core). ``--json`` writes every run and
the table (to FILE, or to standard output without one).

Targets (issue 29, measured, not asserted): one robot with the laser
explores ``building`` to at least 95 % with F1 at least 0.9, with the sonar
90 % and 0.75; two robots reach 90 % in at most 0.65 of one robot's time,
three in at most 0.5; no collision in any run; three robots explore the
building in at most 60 s of wall time.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from dataclasses import asdict, replace

import numpy as np

__all__ = ["add_arguments", "run", "bench_rows"]

SAMPLE_TIMES = (60.0, 120.0, 240.0)
"""Simulated times at which the coverage is reported, s."""


def _coverage_at(times, coverage, t: float) -> float:
    times = np.asarray(times)
    k = np.searchsorted(times, t, side="right") - 1
    return float(coverage[k]) if k >= 0 else 0.0


def _one(name: str, seed: int, n: int, settings) -> dict:
    from ..exploration import explore_team
    from ..world import seeded_world

    world = seeded_world(name, seed)
    t0 = time.perf_counter()
    res = explore_team(world, n, settings, rng=seed)
    out = {"world": name, "seed": seed, **res.summary()}
    out["wall_s"] = time.perf_counter() - t0
    for t in SAMPLE_TIMES:
        out[f"cov_{int(t)}s"] = _coverage_at(res.times, res.coverage, t)
    return out


def bench_rows(worlds, robots, seeds, settings) -> tuple[list, list]:
    """Run every world, team size and seed; return ``(runs, table rows)``."""
    runs = [
        _one(w, s, n, settings) for w in worlds for s in range(seeds) for n in robots
    ]
    rows = []
    for w in worlds:
        alone = {
            r["seed"]: r["t90_s"] for r in runs if r["world"] == w and r["robots"] == 1
        }
        for n in robots:
            rs = [r for r in runs if r["world"] == w and r["robots"] == n]
            ratio = [r["t90_s"] / alone[r["seed"]] for r in rs if r["seed"] in alone]
            rows.append(
                {
                    "world": w,
                    "robots": n,
                    "runs": len(rs),
                    "explored_mean": float(np.mean([r["explored"] for r in rs])),
                    "explored_min": float(np.min([r["explored"] for r in rs])),
                    "f1_mean": float(np.mean([r["f1"] for r in rs])),
                    "t90_median_s": float(np.median([r["t90_s"] for r in rs])),
                    "t99_median_s": float(np.median([r["t99_s"] for r in rs])),
                    "t90_ratio_median": float(np.median(ratio))
                    if ratio
                    else float("nan"),
                    **{
                        f"cov_{int(t)}s": float(
                            np.mean([r[f"cov_{int(t)}s"] for r in rs])
                        )
                        for t in SAMPLE_TIMES
                    },
                    "wall_collisions": int(sum(r["wall_collisions"] for r in rs)),
                    "robot_collisions": int(sum(r["robot_collisions"] for r in rs)),
                    "home": int(sum(r["outcome"] == "home" for r in rs)),
                    "wall_s_mean": float(np.mean([r["wall_s"] for r in rs])),
                }
            )
    return runs, rows


def _print(rows, settings) -> None:
    print(  # noqa: T201 - the bench's report
        f"sensor {settings.sensor}, pose {settings.pose}, "
        f"strategy {settings.strategy}\n"
        f"{'world':12s} {'n':>2s} {'runs':>4s} {'expl':>6s} {'min':>6s} {'F1':>5s} "
        f"{'t90 s':>6s} {'t99 s':>6s} {'t90/1':>6s} {'@60s':>5s} {'@120s':>5s} "
        f"{'@240s':>5s} {'wall':>4s} {'robot':>5s} {'home':>4s} {'wall s':>6s}"
    )
    for r in rows:
        print(  # noqa: T201 - the bench's report
            f"{r['world']:12s} {r['robots']:2d} {r['runs']:4d} "
            f"{r['explored_mean']:6.1%} {r['explored_min']:6.1%} {r['f1_mean']:5.2f} "
            f"{r['t90_median_s']:6.0f} {r['t99_median_s']:6.0f} "
            f"{r['t90_ratio_median']:6.2f} {r['cov_60s']:5.0%} {r['cov_120s']:5.0%} "
            f"{r['cov_240s']:5.0%} {r['wall_collisions']:4d} "
            f"{r['robot_collisions']:5d} {r['home']:4d} {r['wall_s_mean']:6.1f}"
        )


def _robots(text: str) -> list[int]:
    try:
        out = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"not a list of team sizes: {text!r}"
        ) from None
    if not out or any(not 1 <= n <= 4 for n in out):
        raise argparse.ArgumentTypeError("team sizes are 1 to 4, e.g. 1,2,3")
    return out


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``robotlib bench explore``."""
    from ..exploration import POSES, SENSORS, STRATEGIES

    parser.add_argument("--robots", type=_robots, default=[1, 2, 3], help="e.g. 1,2,3")
    parser.add_argument("--seeds", type=int, default=10, help="runs per world and team")
    parser.add_argument(
        "--worlds", nargs="+", default=["building", "office", "gen-office", "gen-hall"],
        help="shipped world names, or gen-KIND for a generated world per seed",
    )  # fmt: skip
    parser.add_argument("--sensor", choices=SENSORS, default="laser")
    parser.add_argument("--pose", choices=POSES, default="true")
    parser.add_argument("--strategy", choices=STRATEGIES, default="coordinated")
    parser.add_argument("--max-time", type=float, default=1200.0, help="simulated s")
    parser.add_argument(
        "--json", nargs="?", const="-", default=None,
        help="write every run and the table as JSON (to FILE, or standard output)",
    )  # fmt: skip


def run(args: argparse.Namespace) -> int:
    """Run the benchmark; print the table (and the JSON); return 0."""
    from ..exploration import ExploreSettings

    if args.seeds < 1:
        raise SystemExit("--seeds must be at least 1")
    settings = replace(
        ExploreSettings(), sensor=args.sensor, pose=args.pose, strategy=args.strategy,
        max_time=args.max_time,
    )  # fmt: skip
    runs, rows = bench_rows(args.worlds, args.robots, args.seeds, settings)
    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    doc = {"settings": asdict(settings), "load": load, "table": rows, "runs": runs}
    if args.json == "-":
        json.dump(doc, sys.stdout, indent=1)
        print()  # noqa: T201
        return 0
    _print(rows, settings)
    print(f"load average: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")  # noqa: T201
    if args.json is not None:
        with open(args.json, "w") as f:
            json.dump(doc, f, indent=1)
    return 0
