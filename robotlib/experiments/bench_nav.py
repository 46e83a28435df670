"""``robotlib bench nav``: the whole navigation loop over seeded goal runs.

``robotlib bench nav [--runs 10] [--json FILE]`` drives the simulated robot
in the office with the two unmapped boxes (`robotlib.planning.OFFICE_BOXES`:
in the simulator, not in the map) to the office's goals (both goal sets in
turn), each run from global localization with its own seed, and prints per
run the outcome, the true final error, the simulated and the wall time, and
the share of successes (reached, within 0.3 m of the true pose, no stall).

Target (measured, not asserted): at least 9 of 10 runs succeed, each in at
most 180 s simulated time.
"""

from __future__ import annotations

import argparse
import functools
import json
import time

say = functools.partial(print)  # noqa: T201 (a bench prints)

__all__ = ["add_arguments", "run"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``robotlib bench nav``."""
    parser.description = "Seeded navigation runs in the office with unmapped boxes."
    parser.add_argument("--runs", type=int, default=10)
    parser.add_argument(
        "--avoider", choices=["stop", "vfh"], default="vfh",
        help="robotlib.avoidance.VFH (navigate's default) or StopAndTurn",
    )  # fmt: skip
    parser.add_argument("--json", metavar="FILE", help="write the results here")


def run(args: argparse.Namespace) -> int:
    """Run the navigation benchmark; return 0."""
    from ..avoidance import VFH
    from ..planning import GOALS, StopAndTurn, navigate, office_with_boxes
    from ..sim import SimRobot, Simulator
    from ..world import load_world

    world, sim_world = load_world("office"), office_with_boxes()
    goals = [g for gs in GOALS["office"].values() for g in gs]
    rows = []
    for k in range(args.runs):
        goal = goals[k % len(goals)]
        t0 = time.perf_counter()
        avoider = VFH() if args.avoider == "vfh" else StopAndTurn()
        robot = SimRobot(Simulator(sim_world, seed=k))
        nav = navigate(robot, world, goal, rng=k, avoider=avoider)
        row = {
            "seed": k,
            "goal": list(goal),
            "outcome": nav.outcome,
            "success": bool(nav.success),
            "final_error": nav.final_error,
            "simulated_s": nav.duration,
            "wall_s": time.perf_counter() - t0,
            "localized_at": nav.localized_at,
            "relocalized": len(nav.lost_times),
            "plans": len(nav.plans),
        }
        rows.append(row)
        say(
            f"run {k} goal {goal}: {row['outcome']}, success {row['success']}, "
            f"error {row['final_error']:.2f} m, {row['simulated_s']:.0f} s simulated, "
            f"{row['wall_s']:.1f} s wall, re-localized {row['relocalized']}x",
            flush=True,
        )
    n = sum(r["success"] for r in rows)
    say(f"success ({args.avoider}): {n} of {len(rows)}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"runs": rows, "successes": n}, f, indent=2)
    return 0
