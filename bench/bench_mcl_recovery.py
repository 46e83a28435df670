"""`MCL.best`'s recovery from a kidnapping on seeded generated worlds, by truth.

``python bench/bench_mcl_recovery.py [--kind office] [--seeds 20] [--first 0]
[--kidnap 40]`` draws a world per seed (`robotlib.world.seeded_world`,
``gen-KIND``), drives its seeded tour with the robot carried to a random free
pose before step ``--kidnap`` (`robotlib.reproduce`'s kidnapping runs,
without its global and tracking runs) and runs on it:

- ``best``: `MCL.best`, no recovery;
- ``rec 20k/5%/mean``: augmented MCL adding up to 20,000 random particles
  carrying a 5 % share, the weighted mean reported (the recovery's earlier
  settings; the particles now come on any step, not only when the filter
  resamples, as they did before);
- ``best+rec``: `RECOVERY_CONFIG` (200,000 particles at the start, up to
  200,000 added carrying up to half the weight, the heaviest place
  reported).

Prints per seed the steps to recover ("-": not within the run) and per
configuration the share recovered within 30 steps, with the load average.
Target (issue 31, measured not asserted): at least 90 %.
"""

from __future__ import annotations

import argparse
import os

from robotlib.experiments.reproduce import (
    BEST_CONFIG,
    RECOVERY,
    RECOVERY_CONFIG,
    RECOVERY_STEPS,
    FilterConfig,
    make_route,
    recovery_steps,
    run_filter,
)
from robotlib.world import seeded_world

EARLIER = FilterConfig(
    "rec 20k/5%/mean",
    "best",
    {"augmented": {**RECOVERY, "grow": 20_000, "share": 0.05}},
)


def main() -> int:
    """Run the seeds; print the table."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--kind", default="office")
    p.add_argument("--seeds", type=int, default=20)
    p.add_argument("--first", type=int, default=0)
    p.add_argument("--kidnap", type=int, default=40)
    p.add_argument("--steps", type=int, default=75)
    args = p.parse_args()
    configs = [BEST_CONFIG, EARLIER, RECOVERY_CONFIG]
    print("seed " + "".join(f"{c.name:>18s}" for c in configs))  # noqa: T201
    steps = {c.name: [] for c in configs}
    for seed in range(args.first, args.first + args.seeds):
        world = seeded_world(f"gen-{args.kind}", seed)
        taken = make_route(world, seed, args.steps, "tour", args.kidnap)
        row = f"{seed:4d} "
        for c in configs:
            r = recovery_steps(run_filter(taken, c, seed).error, args.kidnap)
            steps[c.name].append(r)
            row += f"{'-' if r is None else r:>18}"
        print(row, flush=True)  # noqa: T201
    for c in configs:
        ok = sum(1 for r in steps[c.name] if r is not None and r <= RECOVERY_STEPS)
        print(  # noqa: T201
            f"{c.name}: recovered within {RECOVERY_STEPS} steps {ok}/{args.seeds}"
        )
    print(f"load average {os.getloadavg()[0]:.1f}")  # noqa: T201
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
