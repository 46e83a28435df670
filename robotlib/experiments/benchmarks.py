"""``robotlib bench TOPIC [options]``: one benchmark module per topic.

Each topic is a module with ``add_arguments(parser)`` and ``run(args) ->
int``, registered in `BENCHES` and imported only when asked for. Benchmarks
print robotlib's figures beside a peer or a plain NumPy reference measured
in the same run; they assert nothing.
"""

from __future__ import annotations

import argparse
import importlib

__all__ = ["BENCHES", "add_arguments", "run"]

BENCHES = {
    "mcl": "robotlib.experiments.bench_mcl",
    "avoid": "robotlib.experiments.bench_avoid",
    "map": "robotlib.experiments.bench_map",
    "slam": "robotlib.experiments.bench_map",
    "graphslam": "robotlib.experiments.bench_graphslam",
    "logs": "robotlib.experiments.bench_logs",
    "histogram": "robotlib.experiments.bench_histogram",
    "kalman": "robotlib.experiments.bench_kalman",
    "plan": "robotlib.experiments.bench_plan",
    "nav": "robotlib.experiments.bench_nav",
    "large-map": "robotlib.experiments.bench_large_map",
    "buildings": "robotlib.experiments.bench_buildings",
    "worlds": "robotlib.experiments.bench_worlds",
    "explore": "robotlib.experiments.bench_explore",
}
"""Topic name to the module that measures it."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``robotlib bench``: the topic, then that topic's own options."""
    parser.add_argument("topic", choices=sorted(BENCHES), help="what to measure")
    parser.add_argument(
        "options", nargs=argparse.REMAINDER, help="the topic's options (-h for them)"
    )


def run(args: argparse.Namespace) -> int:
    """Run ``robotlib bench TOPIC``; return the exit status."""
    module = importlib.import_module(BENCHES[args.topic])
    parser = argparse.ArgumentParser(prog=f"robotlib bench {args.topic}")
    module.add_arguments(parser)
    return int(module.run(parser.parse_args(args.options)) or 0)
