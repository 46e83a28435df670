"""Laser FastSLAM once round seeded ring buildings (long blank corridors), by truth.

``python bench/bench_slam_worlds.py [--seeds 10] [--first 0] [--particles 30]
[--degenerate 0.0 0.2] [--loop]`` draws ring worlds
(`robotlib.world.generate_world`, kind ``"ring"``: a corridor 2.5 to 3.5 m
wide round a closed atrium, its walls blank for up to 24 m but for a few
pilasters), drives the simulated robot once round the corridor's centre line
and 5 m on (`robotlib.mapping.record_drive`, seeded), and runs laser FastSLAM
(`robotlib.mapping.run_fastslam`) with each ``match_degenerate`` asked for
(`FastSLAMSettings`; 0: the whole scan fit). Prints per seed the trajectory
RMS against the true poses, the map's F1 and the odometry's RMS, then per
setting the mean and worst, with the load average. ``--loop`` runs the
shipped loop world's tour instead (the world the defaults were tuned on).
Targets (issue 31, measured not asserted): RMS at most 0.08 m and F1 at least
0.9 on every seed.
"""

from __future__ import annotations

import argparse
import os
from dataclasses import replace

import numpy as np

from robotlib.mapping import FastSLAMSettings, record_drive, run_fastslam
from robotlib.world import generate_world


def ring_route(world) -> list[tuple[float, float]]:
    """Once round a generated ring's corridor on its centre line, then 5 m on."""
    x0, y0, _ = world.start  # the start sits on the centre line, in a corner
    s = np.asarray(world.segments)
    w, h = s[:, [0, 2]].max(), s[:, [1, 3]].max()
    return [(w - x0, y0), (w - x0, h - y0), (x0, h - y0), (x0, y0), (x0 + 5.0, y0)]


def main() -> int:
    """Run the seeds; print the table."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=int, default=10)
    p.add_argument("--first", type=int, default=0)
    p.add_argument("--particles", type=int, default=30)
    p.add_argument("--degenerate", type=float, nargs="+", default=[0.0, 0.2])
    p.add_argument("--loop", action="store_true", help="the shipped loop world")
    args = p.parse_args()
    rows = {d: [] for d in args.degenerate}
    for seed in range(args.first, args.first + args.seeds):
        if args.loop:
            log = record_drive("loop", seed=seed, every=2)
        else:
            world = generate_world("ring", seed)
            log = record_drive(world, ring_route(world), seed=seed, every=2)
        for d in args.degenerate:
            settings = replace(FastSLAMSettings(), match_degenerate=d)
            r = run_fastslam(log, args.particles, "laser", rng=seed, settings=settings)
            rows[d].append((r.rms, r.score.f1))
            print(  # noqa: T201
                f"seed {seed:3d} match_degenerate {d:4.2f}: RMS {r.rms:6.3f} m, "
                f"F1 {r.score.f1:5.3f} (odometry RMS {r.odometry_rms:5.2f} m)",
                flush=True,
            )
    for d, r in rows.items():
        a = np.array(r)
        print(  # noqa: T201
            f"match_degenerate {d:4.2f}, {len(a)} seeds: RMS mean {a[:, 0].mean():.3f} "
            f"max {a[:, 0].max():.3f} m; F1 mean {a[:, 1].mean():.3f} "
            f"min {a[:, 1].min():.3f}"
        )
    load = np.round(os.getloadavg(), 2)
    print(f"load average: {load[0]} {load[1]} {load[2]}")  # noqa: T201
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
