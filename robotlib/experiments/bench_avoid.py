"""``robotlib bench avoid``: the avoidance controllers over seeded start/goal pairs.

``robotlib bench avoid [--pairs 20] [--json FILE]`` runs every controller
(`robotlib.avoidance.CONTROLLERS`, default settings) in every avoidance world
(`robotlib.avoidance.AVOID_WORLDS`) on the same seeded start/goal pairs
(`start_goal_pairs(world, n, seed)`), 120 s of simulated time at most each,
and prints per controller and world: the success rate judged by the truth
(reached, no collision, truly within 0.5 m of the goal: ``true``) and by
the odometry (the robot's own word: ``odometry``), the mean time to the
goal of the true successes, the smallest true clearance of any episode, the
episodes that collided, ended in a reported local minimum, or timed out.

It also times one controller step (replaying the sonar and odometry of a
recorded VFH episode in the cluttered arena through each controller), beside
one simulator cycle measured in the same run (CPU time of this process: on a
shared machine wall time counts the waits for a core), and the wall time of 20
episodes of 120 s (VFH in the cluttered arena) in this process and over two
worker processes. ``--json`` writes ``{"table": [...], "step_us": {...},
"batch": {...}}``.

Targets (measured and reported, not asserted): VFH at least 90 % success in
the cluttered arena and the doorway, 80 % in the U-trap, no collision; the
potential field caught in the U-trap and saying so (local minimum); one
step at most 50 us; 20 episodes of 120 s in at most 10 s on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

__all__ = ["add_arguments", "run", "bench_table", "bench_step", "bench_batch"]


def _summary(controller: str, world: str, episodes) -> dict:
    ok = [e for e in episodes if e.true_success]
    return {
        "controller": controller,
        "world": world,
        "episodes": len(episodes),
        "success_rate": len(ok) / len(episodes),
        "odometry_success_rate": sum(e.success for e in episodes) / len(episodes),
        "mean_time_to_goal_s": float(np.mean([e.duration for e in ok])) if ok else None,
        "min_clearance_m": float(min(e.min_clearance for e in episodes)),
        "collisions": sum(e.collisions > 0 for e in episodes),
        "local_minima": sum(e.outcome == "local_minimum" for e in episodes),
        "timeouts": sum(e.outcome == "timeout" for e in episodes),
        "wall_s": float(sum(e.wall_time for e in episodes)),
    }


def bench_table(controllers, worlds, n_pairs=20, seed=0, max_time=120.0, jobs=1):
    """Run every controller in every world on the same pairs; one row each."""
    from ..avoidance import CONTROLLERS, run_episodes, start_goal_pairs

    rows = []
    for world in worlds:
        pairs = start_goal_pairs(world, n_pairs, seed=seed)
        for name in controllers:
            eps = run_episodes(
                world, CONTROLLERS[name](), pairs, max_time, seed=seed, jobs=jobs
            )
            rows.append(_summary(name, world, eps))
    return rows


def bench_step(controllers, reps: int = 5) -> dict:
    """Microseconds per controller step and per simulator cycle (fastest rep)."""
    from ..avoidance import CONTROLLERS, VFH, run_episode, start_goal_pairs
    from ..sim import Simulator
    from ..world import load_world

    pair = start_goal_pairs("clutter", 1, seed=0)[0]
    ep = run_episode("clutter", VFH(), pair.goal, start=pair.start, seed=0)
    out = {}
    for name in controllers:
        best = np.inf
        for _ in range(reps):
            c = CONTROLLERS[name]()
            c.goal = np.array(pair.goal)
            c.reset()
            t0 = time.process_time()
            for s, p in zip(ep.sonar, ep.odometry, strict=True):
                c.command(s, p)
            best = min(best, (time.process_time() - t0) / len(ep.sonar))
        out[name] = best * 1e6
    sim = Simulator(load_world("clutter"), seed=0)
    body = sim.add_robot(pair.start)
    body.command("VEL", 0.3)
    body.command("RVEL", 0.2)
    best = np.inf
    for _ in range(reps):
        t0 = time.process_time()
        for _ in range(500):
            sim.step()
        best = min(best, (time.process_time() - t0) / 500)
    out["simulator cycle"] = best * 1e6
    return out


def bench_batch(n: int = 20, max_time: float = 120.0, jobs=(1, 2)) -> dict:
    """Wall seconds of ``n`` full-length VFH episodes in the clutter, per job count."""
    from ..avoidance import VFH, StartGoal, run_episodes, start_goal_pairs

    # goals out of reach (far outside the arena): every episode runs max_time
    pairs = [StartGoal(p.start, (100.0, 100.0)) for p in start_goal_pairs("clutter", n)]
    out = {}
    for j in jobs:
        t0 = time.perf_counter()
        eps = run_episodes("clutter", VFH(), pairs, max_time, seed=1, jobs=j)
        out[f"jobs={j}"] = {
            "wall_s": time.perf_counter() - t0,
            "simulated_s": float(sum(e.duration for e in eps)),
        }
    return out


def _print_table(rows) -> None:
    head = (
        f"{'controller':16s} {'world':8s} {'true':>6s} {'odometry':>8s} "
        f"{'t goal s':>9s} {'min clr m':>9s} {'collide':>7s} {'loc min':>7s} "
        f"{'timeout':>7s}"
    )
    print(head)  # noqa: T201
    for r in rows:
        t = r["mean_time_to_goal_s"]
        print(  # noqa: T201 - the bench's report
            f"{r['controller']:16s} {r['world']:8s} {r['success_rate']:6.0%} "
            f"{r['odometry_success_rate']:8.0%} "
            f"{'-' if t is None else f'{t:.1f}':>9s} {r['min_clearance_m']:9.2f} "
            f"{r['collisions']:7d} {r['local_minima']:7d} {r['timeouts']:7d}"
        )


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``robotlib bench avoid``."""
    from ..avoidance import AVOID_WORLDS, CONTROLLERS

    parser.add_argument("--json", type=Path, default=None, help="write results here")
    parser.add_argument("--pairs", type=int, default=20, help="start/goal pairs")
    parser.add_argument("--seed", type=int, default=0, help="seed of the pairs")
    parser.add_argument("--max-time", type=float, default=120.0, help="s per episode")
    parser.add_argument("--jobs", type=int, default=1, help="worker processes")
    parser.add_argument("--worlds", nargs="+", default=list(AVOID_WORLDS))
    parser.add_argument("--controllers", nargs="+", default=list(CONTROLLERS))
    parser.add_argument(
        "--timing",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="time the controller step and a batch of 20 episodes",
    )


def run(args: argparse.Namespace) -> int:
    """Run the benchmark; print the table (and write JSON); return 0."""
    rows = bench_table(
        args.controllers, args.worlds, args.pairs, args.seed, args.max_time, args.jobs
    )
    _print_table(rows)
    result = {"table": rows}
    if args.timing:
        steps = bench_step(args.controllers)
        sim = steps["simulator cycle"]
        print("\nstep, us CPU (fastest of 5; ratio to one simulator cycle):")  # noqa: T201
        for name, us in steps.items():
            print(f"  {name:16s} {us:8.1f}  {us / sim:5.2f}")  # noqa: T201
        batch = bench_batch(20, args.max_time)
        print(f"\n20 VFH episodes of {args.max_time:.0f} s in the clutter:")  # noqa: T201
        for k, v in batch.items():
            print(  # noqa: T201 - the bench's report
                f"  {k}: {v['wall_s']:.1f} s wall, {v['simulated_s']:.0f} s simulated"
            )
        result["step_us"] = steps
        result["batch"] = batch
    if args.json is not None:
        args.json.write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    return 0
