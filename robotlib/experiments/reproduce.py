"""The paper's experiment: MCL with eight sonars in an aliased corridor.

Every filter configuration (`FilterConfig`: the paper's, `MCL.best`) runs on
the same logged routes (`robotlib.experiments.routes.drive_route`), one
filter step per motion step, at most 75 steps (`run_filter`).

"Localized at step k" means the estimate stays within 0.5 m of the true
position from step k (1-based) to the end. The tracking error is the mean
position error over those steps. A tracking-only run starts the filter at the
true start pose.

``robotlib reproduce [--world W] --seeds 20 --json FILE`` runs the paper's
configuration and the best one this project offers over many seeds.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..localization import BEST, MCL, History
from ..localization.paper import RESIZE_FLOOR
from ..world import World, load_world
from .routes import MAX_STEPS, RouteLog, drive_route

__all__ = [
    "FilterConfig",
    "PAPER",
    "BEST_CONFIG",
    "run_filter",
    "summarize",
    "reproduce",
    "add_arguments",
    "run",
]

SUCCESS_STEP = 25
"""The paper localized from step 25."""
TOLERANCE = 0.5
"""Localized: position error at most this, m."""


@dataclass(frozen=True)
class FilterConfig:
    """A named MCL configuration the runner can build for any world.

    Attributes
    ----------
    name : str
        A label.
    kind : str
        ``"paper"`` (`MCL.paper`) or ``"best"`` (`MCL.best`).
    options : dict
        Keyword arguments for the factory (e.g. ``n``, ``lam``, ``floor``,
        ``fast``).
    """

    name: str
    kind: str = "paper"
    options: dict = field(default_factory=dict)

    def build(self, world: World, rng, init=None) -> MCL:
        """Make the filter (``init``: start around that pose instead of uniform)."""
        factory = {"paper": MCL.paper, "best": MCL.best}[self.kind]
        return factory(world, rng=rng, init=init, **self.options)

    def settings(self) -> dict:
        """Return the settings used, for the report."""
        out = {"name": self.name, "kind": self.kind, **self.options}
        if self.kind == "paper":
            out = {"n": 300, "lam": 0.5, "floor": RESIZE_FLOOR, **out}
            out.setdefault("sensor", "paper innovation")
            out.setdefault("resampling", "multinomial + resize + admissibility")
        else:
            out = {**BEST, **out}
            out.setdefault("sensor", "beam (tempered), cone table")
            out.setdefault("resampling", "KLD-sampling when ESS < N/2")
        return out


PAPER = FilterConfig("paper", "paper", {"n": 300, "lam": 0.5, "floor": RESIZE_FLOOR})
"""The paper's filter as written (300 particles)."""
BEST_CONFIG = FilterConfig("best", "best", {})
"""The strongest configuration (`robotlib.localization.BEST`)."""


def run_filter(
    route: RouteLog,
    config: FilterConfig,
    seed: int,
    tracking: bool = False,
    n_steps: int | None = None,
) -> History:
    """Run one filter configuration over a logged route.

    Parameters
    ----------
    route : RouteLog
        The log (the same for every configuration at a seed).
    config : FilterConfig
        What to run.
    seed : int
        The filter's seed.
    tracking : bool
        Start at the true start pose instead of uniform (global).
    n_steps : int, optional
        Use only the first steps of the log.

    Returns
    -------
    History
    """
    rng = np.random.default_rng([seed, 2])
    init = route.truth[0] if tracking else None
    mcl = config.build(route.world, rng, init=init)
    hist = History()
    n = len(route) if n_steps is None else min(n_steps, len(route))
    for k in range(n):
        prev = route.odometry[max(k - 1, 0)]
        t0 = time.perf_counter()
        mcl.step(prev, route.odometry[k], route.sonar[k])
        hist.record(route.truth[k], mcl, 1000 * (time.perf_counter() - t0))
    return hist


def _nan_stat(values, fn) -> float | None:
    v = np.asarray([x for x in values if x is not None and np.isfinite(x)], float)
    return float(fn(v)) if len(v) else None


def summarize(
    runs: list[History], tracking_runs: list[History], config: FilterConfig
) -> dict:
    """Compute the reproduce figures of one configuration over seeds.

    Parameters
    ----------
    runs : list of History
        Global-localization runs, one per seed.
    tracking_runs : list of History
        Tracking-only runs, one per seed.
    config : FilterConfig
        Their configuration (for the settings).

    Returns
    -------
    dict
        ``success_rate`` (share localized by step 25), ``success_rate_75``,
        ``localized_step_median``, ``tracking_error_mean_m`` and
        ``tracking_error_std_m`` (over the steps after localization, pooled
        over the seeds that localized), ``tracking_from_start_error_mean_m``,
        ``particles_final_median``, ``ms_per_step_median``, ``localized_steps``
        (per seed) and ``settings``.
    """
    steps = [h.localized_step(TOLERANCE) for h in runs]
    after = [h.error[s - 1 :] for h, s in zip(runs, steps, strict=True) if s]
    pooled = np.concatenate(after) if after else np.zeros(0)
    track = np.concatenate([h.error for h in tracking_runs]) if tracking_runs else []
    n = max(len(runs), 1)
    return {
        "success_rate": sum(1 for s in steps if s and s <= SUCCESS_STEP) / n,
        "success_rate_75": sum(1 for s in steps if s) / n,
        "localized_step_median": _nan_stat(steps, np.median),
        "tracking_error_mean_m": float(pooled.mean()) if len(pooled) else None,
        "tracking_error_std_m": float(pooled.std()) if len(pooled) else None,
        "tracking_from_start_error_mean_m": (
            float(np.mean(track)) if len(track) else None
        ),
        "particles_final_median": _nan_stat(
            [h.n_particles[-1] for h in runs], np.median
        ),
        "ms_per_step_median": _nan_stat(
            np.concatenate([h.time_ms for h in runs]) if runs else [], np.median
        ),
        "localized_steps": steps,
        "settings": config.settings(),
    }


def reproduce(
    world: World,
    seeds,
    configs: dict[str, FilterConfig] | None = None,
    n_steps: int = MAX_STEPS,
) -> dict:
    """Run configurations over seeds on one world; return their summaries.

    Parameters
    ----------
    world : World
        The world.
    seeds : iterable of int
        One route and one filter seed each.
    configs : dict of str to FilterConfig, optional
        Default: ``{"paper": PAPER, "best": BEST_CONFIG}``.
    n_steps : int
        Steps per run.

    Returns
    -------
    dict
        ``{name: summarize(...)}`` plus ``"world"`` and ``"seeds"``.
    """
    configs = {"paper": PAPER, "best": BEST_CONFIG} if configs is None else configs
    seeds = list(seeds)
    runs = {name: ([], []) for name in configs}
    for seed in seeds:
        route = drive_route(world, seed, n_steps)
        for name, config in configs.items():
            runs[name][0].append(run_filter(route, config, seed))
            runs[name][1].append(run_filter(route, config, seed, tracking=True))
    out = {name: summarize(*runs[name], configs[name]) for name in configs}
    out["world"] = world.name or str(world.source)
    out["seeds"] = seeds
    return out


def _fmt(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.3f}"
    return str(v)


def format_table(result: dict) -> str:
    """Format `reproduce`'s figures as a plain-text table."""
    keys = [
        "success_rate",
        "success_rate_75",
        "localized_step_median",
        "tracking_error_mean_m",
        "tracking_error_std_m",
        "tracking_from_start_error_mean_m",
        "particles_final_median",
        "ms_per_step_median",
    ]
    names = [k for k, v in result.items() if isinstance(v, dict)]
    lines = [f"world {result.get('world')}, {len(result.get('seeds', []))} seeds"]
    lines.append(f"{'':34s}" + "".join(f"{n:>12s}" for n in names))
    for k in keys:
        lines.append(f"{k:34s}" + "".join(f"{_fmt(result[n][k]):>12s}" for n in names))
    return "\n".join(lines)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``robotlib reproduce``."""
    parser.description = "Run the paper's MCL experiment and the best configuration."
    parser.add_argument("--world", default="corridor", help="world name or path")
    parser.add_argument("--seeds", type=int, default=20, help="number of seeds")
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--steps", type=int, default=MAX_STEPS, help="steps per run")
    parser.add_argument("--particles", type=int, default=300, help="paper's N")
    parser.add_argument("--lam", type=float, default=0.5, help="paper's lambda")
    parser.add_argument("--floor", type=int, default=RESIZE_FLOOR, help="resize floor")
    parser.add_argument("--json", type=Path, default=None, help="write results here")


def run(args: argparse.Namespace) -> int:
    """Run ``robotlib reproduce``; return the exit status."""
    world = load_world(args.world)
    paper = FilterConfig(
        "paper", "paper", {"n": args.particles, "lam": args.lam, "floor": args.floor}
    )
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    t0 = time.perf_counter()
    result = reproduce(world, seeds, {"paper": paper, "best": BEST_CONFIG}, args.steps)
    result["seconds"] = time.perf_counter() - t0
    print(format_table(result))  # noqa: T201
    if args.json is not None:
        args.json.write_text(json.dumps(result, indent=2, default=_json_default))
    return 0


def _json_default(o):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, tuple):
        return list(o)
    return str(o)
