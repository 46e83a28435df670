"""Experiments and benchmarks: the paper's MCL experiment, routes, ``robotlib bench``.

- `routes`: `drive_route`, `RouteLog` (the paper's seeded drive, logged)
- `reproduce`: `FilterConfig`, `PAPER`, `BEST_CONFIG`, `run_filter`,
  `summarize`, ``robotlib reproduce``
- `tours`: `drive_tour` (a seeded A* + pure pursuit drive through any
  world's free space, optionally with a kidnapping), `TourSpace`
- `benchmarks`: ``robotlib bench TOPIC``, one ``bench_<topic>`` module each

Experiments sit above the estimators and the simulator; they never plot
(`robotlib.plotting` draws their results).
"""

from .reproduce import (
    BEST_CONFIG,
    PAPER,
    RECOVERY_CONFIG,
    TOLERANCE,
    FilterConfig,
    recovery_steps,
    reproduce,
    run_filter,
    summarize,
)
from .routes import MAX_STEPS, RouteLog, drive_route
from .tours import TourSpace, drive_tour

__all__ = [
    "BEST_CONFIG",
    "MAX_STEPS",
    "PAPER",
    "RECOVERY_CONFIG",
    "TOLERANCE",
    "TourSpace",
    "FilterConfig",
    "RouteLog",
    "drive_route",
    "drive_tour",
    "recovery_steps",
    "reproduce",
    "run_filter",
    "summarize",
]
