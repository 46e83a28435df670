"""Why avoidance episodes on the generated worlds fail: each miss classified.

``python bench/bench_nav_failures.py VFH [--aim "" | +MCL | +MCL+A*]
[--kinds ...] [--worlds 3] [--pairs 20]`` runs the episodes of
``robotlib bench worlds`` (same worlds, pairs and seeds, seed 0) for one
controller and aim and prints every episode that is not truly reached with
its class, then the counts:

- ``collision``, ``local_minimum``: as the episode ended;
- ``drift``: the controller said "reached" (odometry within its tolerance)
  but truly ended more than 0.5 m off;
- ``timeout_near``: the odometry came within 0.6 m of the goal, yet the
  controller never stopped there (it passed by);
- ``timeout_stuck``: the robot moved less than 1.5 m in its last 60 s;
- ``timeout_oscillate``: it moved, but within 1.5 m of one spot;
- ``timeout_wander``: it kept moving over a wider area (a door or a way
  round not found).

CPU seconds are printed (rates come from simulated time and do not depend
on the load).
"""

from __future__ import annotations

import argparse
import time
from collections import Counter

import numpy as np

from robotlib.avoidance import CONTROLLERS, run_episodes
from robotlib.experiments.bench_worlds import world_pairs
from robotlib.planning import Localized
from robotlib.world import KINDS


def classify(e) -> str:
    """Return the class of episode ``e`` (``"ok"`` when truly reached)."""
    if e.true_success:
        return "ok"
    if e.collisions:
        return "collision"
    if e.outcome in ("local_minimum", "reached"):
        return "drift" if e.outcome == "reached" else e.outcome
    last = e.truth[-600:, :2]  # the last 60 s
    moved = float(np.hypot(*np.diff(last, axis=0).T).sum())
    spread = float(np.hypot(*(last - last.mean(axis=0)).T).max())
    if np.hypot(*(e.odometry[:, :2] - e.goal).T).min() < 0.6:
        return "timeout_near"
    if moved < 1.5:
        return "timeout_stuck"
    return "timeout_oscillate" if spread < 1.5 else "timeout_wander"


def main() -> int:
    """Run the episodes; print the misses and the counts."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("controller", choices=list(CONTROLLERS))
    p.add_argument("--aim", default="", choices=["", "+MCL", "+MCL+A*"])
    p.add_argument("--kinds", nargs="+", default=list(KINDS), choices=KINDS)
    p.add_argument("--worlds", type=int, default=3)
    p.add_argument("--pairs", type=int, default=20)
    args = p.parse_args()
    t0, counts = time.process_time(), Counter()
    for kind in args.kinds:
        for k in range(args.worlds):
            world, pairs = world_pairs(kind, k, args.pairs, 0)
            c = CONTROLLERS[args.controller]()
            if args.aim:
                c = Localized(c, world, rng=[0, k], plan=args.aim == "+MCL+A*")
            for i, e in enumerate(run_episodes(world, c, pairs, seed=k)):
                why = classify(e)
                counts[why] += 1
                if why != "ok":
                    print(  # noqa: T201 - the bench's report
                        f"{kind:10s} {k} {i:2d} {why:18s} true error "
                        f"{e.true_error:5.2f} m, {e.duration:4.0f} s, "
                        f"{e.path_length:5.1f} m driven"
                    )
    print(dict(counts), f"CPU {time.process_time() - t0:.0f} s")  # noqa: T201
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
