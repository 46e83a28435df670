"""Experiments and benchmarks: the paper's MCL experiment, routes, ``robotlib bench``.

- `routes`: `drive_route`, `RouteLog` (the paper's seeded drive, logged)
- `reproduce`: `FilterConfig`, `PAPER`, `BEST_CONFIG`, `run_filter`,
  `summarize`, ``robotlib reproduce``
- `benchmarks`: ``robotlib bench TOPIC``, one ``bench_<topic>`` module each

Experiments sit above the estimators and the simulator; they never plot
(`robotlib.plotting` draws their results).
"""

from .reproduce import (
    BEST_CONFIG,
    PAPER,
    TOLERANCE,
    FilterConfig,
    reproduce,
    run_filter,
    summarize,
)
from .routes import MAX_STEPS, RouteLog, drive_route

__all__ = [
    "BEST_CONFIG",
    "MAX_STEPS",
    "PAPER",
    "TOLERANCE",
    "FilterConfig",
    "RouteLog",
    "drive_route",
    "reproduce",
    "run_filter",
    "summarize",
]
