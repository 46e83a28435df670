"""Pose-graph SLAM beside odometry and grid FastSLAM on the simulated laser, by truth.

``python bench/bench_graphslam_worlds.py [--worlds loop office] [--seeds 5]
[--first 0] [--degenerate 0 0.1] [--no-fastslam]`` records, per world
and seed, the shipped tour (`robotlib.mapping.record_drive`, a record every
0.2 s, seeded) and runs on the same log: the odometry alone, graph SLAM
(`robotlib.mapping.graph_slam`) with each ``match_degenerate`` asked for
(default: the settings' own, 0, every sequential match kept whole; 0.1
keeps the odometry along what ICP barely pins) and laser FastSLAM with 30 particles
(`robotlib.mapping.run_fastslam`, the filter seeded with the seed). Each
row: the trajectory RMS against the true poses (m), the F1 at 5 cm of the
laser map built from that trajectory (`map_laser`, `map_score`; for
FastSLAM also its own map's), graph SLAM's loop edges, and the CPU seconds
of the run; then a Markdown table of each method's mean and worst over the
seeds, and the load average.

Targets (issue 30, measured not asserted): on the loop world graph SLAM's
RMS at most half the odometry's and at most FastSLAM's, its F1 at least
0.95.
"""

from __future__ import annotations

import argparse
import os
import time
from dataclasses import replace

import numpy as np

from robotlib.mapping import GraphSLAMSettings, graph_slam, record_drive, run_fastslam
from robotlib.mapping.metrics import map_score, trajectory_rms
from robotlib.mapping.occupancy import map_laser


def _row(log, poses) -> tuple[float, float]:
    """Trajectory RMS (m) and laser map F1 at 5 cm of ``poses`` on ``log``."""
    grid = map_laser(log.world, poses, log.laser, 0.05, laser=log.laser_model)
    return trajectory_rms(poses, log.truth), map_score(grid, log.world, 0.05).f1


def _print(world, seed, name, rms, f1, cpu, extra="") -> None:
    print(  # noqa: T201 - the bench's report
        f"{world:7s} seed {seed:2d} {name:10s}: RMS {rms:6.3f} m, F1 {f1:5.3f}"
        f"{extra} ({cpu:5.1f} CPU s, load {os.getloadavg()[0]:.1f})",
        flush=True,
    )


def main() -> int:
    """Run the worlds and seeds; print the rows and the summary."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--worlds", nargs="+", default=["loop"], choices=["loop", "office"])
    p.add_argument("--seeds", type=int, default=5)
    p.add_argument("--first", type=int, default=0)
    p.add_argument(
        "--degenerate", nargs="+", type=float,
        default=[GraphSLAMSettings().match_degenerate],
    )  # fmt: skip
    p.add_argument("--no-fastslam", action="store_true", help="skip FastSLAM")
    args = p.parse_args()
    variants = {f"graph {d:g}": replace(GraphSLAMSettings(), match_degenerate=d)
                for d in args.degenerate}  # fmt: skip
    names = ["odometry", *variants] + ([] if args.no_fastslam else ["FastSLAM"])
    for world in args.worlds:
        rows = {n: [] for n in names}
        for seed in range(args.first, args.first + args.seeds):
            log = record_drive(world, seed=seed, every=2)
            m = log.laser_model
            rows["odometry"].append(_row(log, log.odometry))
            _print(world, seed, "odometry", *rows["odometry"][-1], 0.0)
            for v, settings in variants.items():
                t0 = time.process_time()
                r = graph_slam(log.odometry, log.laser, m.angles, m.max_range,
                               settings, mount=m.mount)  # fmt: skip
                cpu = time.process_time() - t0
                rows[v].append(_row(log, r.poses))
                _print(world, seed, v, *rows[v][-1], cpu, f", {r.loops} loops")
            if not args.no_fastslam:
                t0 = time.process_time()
                f = run_fastslam(log, 30, "laser", rng=seed)
                cpu = time.process_time() - t0
                rows["FastSLAM"].append(_row(log, f.path))
                own = f", own map F1 {f.score.f1:5.3f}"
                _print(world, seed, "FastSLAM", *rows["FastSLAM"][-1], cpu, own)
        print("| world | method | seeds | RMS m, mean / max | F1, mean / min |")  # noqa: T201
        print("|---|---|---|---|---|")  # noqa: T201
        for n, r in rows.items():
            (rms, f1), k = np.array(r).T, len(r)
            print(f"| {world} | {n} | {k} | {rms.mean():.3f} / {rms.max():.3f} | "  # noqa: T201
                  f"{f1.mean():.3f} / {f1.min():.3f} |")  # fmt: skip
    print("load average: {:.1f} {:.1f} {:.1f}".format(*os.getloadavg()))  # noqa: T201
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
