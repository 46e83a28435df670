"""The paper's experiment: MCL with eight sonars in an aliased corridor.

Every filter configuration (`FilterConfig`: the paper's, `MCL.best`) runs on
the same logged routes (`robotlib.experiments.routes.drive_route`), one
filter step per motion step, at most 75 steps (`run_filter`).

"Localized at step k" means the estimate stays within 0.5 m of the true
position from step k (1-based) to the end. The tracking error is the mean
position error over those steps. A tracking-only run starts the filter at the
true start pose.

``robotlib reproduce [--world W] --seeds 20 --json FILE`` runs the paper's
configuration and the best one this project offers over many seeds. A
bundled corridor drives `drive_route`; any other world (a file, a real
building) a seeded tour (`robotlib.experiments.tours.drive_tour`);
``--world gen-KIND`` tours a world generated afresh for each seed
(`robotlib.world.seeded_world`), so nothing is tuned to one map.

``--kidnap STEP`` adds a run per seed and filter on the same tour with the
robot moved to a random free pose just before step ``STEP`` (the filter is
not told): "recovered after r steps" means the error is under 0.3 m at
steps ``STEP + r`` to ``STEP + r + 4`` (`recovery_steps`).
"""

from __future__ import annotations

import argparse
import functools
import json
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..localization import BEST, MCL, History
from ..localization.paper import RESIZE_FLOOR
from ..world import World, load_world, seeded_world
from .routes import MAX_STEPS, RouteLog, drive_route
from .tours import drive_tour

__all__ = [
    "FilterConfig",
    "PAPER",
    "BEST_CONFIG",
    "RECOVERY",
    "RECOVERY_CONFIG",
    "run_filter",
    "summarize",
    "summarize_kidnap",
    "recovery_steps",
    "make_route",
    "reproduce",
    "add_arguments",
    "run",
]

SUCCESS_STEP = 25
"""The paper localized from step 25."""
TOLERANCE = 0.5
"""Localized: position error at most this, m."""
RECOVERED = 0.3
"""Recovered from a kidnapping: position error under this, m ..."""
HOLD = 5
"""... for this many consecutive steps."""
RECOVERY_STEPS = 30
"""The recovery target: back within this many steps of the kidnapping."""


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
            if out.get("augmented"):
                out.setdefault("recovery", "augmented MCL, random particles added")
            out.setdefault("estimator", "mean")
        return out


PAPER = FilterConfig("paper", "paper", {"n": 300, "lam": 0.5, "floor": RESIZE_FLOOR})
"""The paper's filter as written (300 particles)."""
BEST_CONFIG = FilterConfig("best", "best", {})
"""The strongest configuration (`robotlib.localization.BEST`)."""
RECOVERY = {
    "alpha_slow": 0.05,
    "alpha_fast": 0.5,
    "grow": 200_000,
    "min_probability": 0.3,
    "share": 0.5,
}
"""`MCL.best`'s recovery from a kidnapping: augmented MCL adding up to 200,000
random particles (`AugmentedInjection` with ``grow``), carrying up to half
the weight, on every step the short-term scan likelihood is 30 % or more
below the long-term one. With the mode estimate (`RECOVERY_CONFIG`), a false
alarm's scattered particles do not move the estimate; with a 5 % share and
20,000 particles, the place the robot was carried to won too slowly against
the old cloud: 9 of 20 generated offices recovered within 30 steps, 20 of
20 with 50,000 and half the weight. 200,000 (was 50,000): in a generated
warehouse the place the robot was carried to has look-alikes in every aisle
and a turned twin, and 50,000 uniform particles leave a handful near it
(`bench/results/mcl_recovery.md`)."""
RECOVERY_CONFIG = FilterConfig(
    "best+rec",
    "best",
    {"n": 200_000, "augmented": RECOVERY, "estimator": "mode"},
)
"""`MCL.best` with `RECOVERY` on, started from 200,000 particles (`BEST`:
50,000). A generated warehouse is its own twin turned half round but for
racks' ends a few centimetres apart: over 50 steps the true pose's scans
outscore its twin's by a tempered log-likelihood ratio of only 0-6, and
50,000 uniform particles leave about five within 0.5 m and 0.1 rad of the
truth, so the twin often wins by the luck of the draw in the first steps;
200,000 keep both until the scans tell them apart. KLD-sampling shrinks the
set within a few steps, so only those steps cost more."""


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
        ``success_rate`` (share localized by step 25), ``success_rate_50``,
        ``success_rate_75``,
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
        "success_rate_50": sum(1 for s in steps if s and s <= 50) / n,
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


def recovery_steps(errors, kidnap: int, tolerance: float = RECOVERED, hold: int = HOLD):
    """Count the steps from a kidnapping until the error stays under ``tolerance``.

    Parameters
    ----------
    errors : array_like, shape (T,)
        Position error per step (index = log step), m.
    kidnap : int
        The log step the robot was moved before.
    tolerance : float
        m.
    hold : int
        Consecutive steps the error must stay under ``tolerance``.

    Returns
    -------
    int or None
        The smallest ``r >= 0`` with ``errors[kidnap + r : kidnap + r + hold]``
        all under ``tolerance``; None when the log ends first.
    """
    ok = np.asarray(errors, dtype=float)[int(kidnap) :] < tolerance
    for r in range(len(ok) - hold + 1):
        if ok[r : r + hold].all():
            return r
    return None


def summarize_kidnap(runs: list[History], kidnap: int) -> dict:
    """Recovery figures of one configuration over seeds' kidnapping runs.

    Returns
    -------
    dict
        ``localized_at_kidnap_rate`` (error under 0.3 m at the step before),
        ``recovered_rate`` (back within `RECOVERY_STEPS` steps),
        ``recovered_rate_localized`` (the same among the runs localized at
        the kidnapping), ``recovery_steps_median`` (over recovered runs) and
        ``recovery_steps`` (per seed, None: not recovered).
    """
    steps = [recovery_steps(h.error, kidnap) for h in runs]
    before = [bool(h.error[kidnap - 1] < RECOVERED) for h in runs]
    n = max(len(runs), 1)
    good = [s for s, b in zip(steps, before, strict=True) if b]
    ok = [s is not None and s <= RECOVERY_STEPS for s in steps]
    return {
        "kidnap_step": int(kidnap),
        "localized_at_kidnap_rate": sum(before) / n,
        "recovered_rate": sum(ok) / n,
        "recovered_rate_localized": (
            sum(1 for s in good if s is not None and s <= RECOVERY_STEPS) / len(good)
            if good
            else None
        ),
        "recovery_steps_median": _nan_stat(steps, np.median),
        "recovery_steps": steps,
    }


def make_route(world: World, seed: int, n_steps: int, route: str = "auto", kidnap=None):
    """Drive one seed's route: ``"corridor"`` (`drive_route`), ``"tour"`` or ``"auto"``.

    ``"auto"`` drives `drive_route` in the bundled worlds and a tour
    (`drive_tour`) in any other; a kidnapping needs a tour.
    """
    if route == "auto":
        from ..world.catalog import WORLDS_DIR

        src = world.source
        bundled = src is None or Path(src).resolve().parent == WORLDS_DIR.resolve()
        route = "corridor" if bundled and kidnap is None else "tour"
    if route == "corridor":
        if kidnap is not None:
            raise ValueError("a kidnapping needs a tour (route='tour')")
        return drive_route(world, seed, n_steps)
    if route == "tour":
        return drive_tour(world, seed, n_steps, kidnap=kidnap)
    raise ValueError(f"route must be 'auto', 'corridor' or 'tour', got {route!r}")


def reproduce(
    world: World | Callable[[int], World],
    seeds,
    configs: dict[str, FilterConfig] | None = None,
    n_steps: int = MAX_STEPS,
    kidnap: int | None = None,
    route: str = "auto",
    tracking: bool = True,
) -> dict:
    """Run configurations over seeds on one world; return their summaries.

    Parameters
    ----------
    world : World or callable
        The world, or a function of the seed returning each seed's own world
        (a generated one, `robotlib.world.seeded_world`).
    seeds : iterable of int
        One route and one filter seed each.
    configs : dict of str to FilterConfig, optional
        Default: ``{"paper": PAPER, "best": BEST_CONFIG}``.
    n_steps : int
        Steps per run.
    kidnap : int, optional
        Also run each configuration on the seed's tour with a kidnapping
        before this step; adds the `summarize_kidnap` figures under
        ``"kidnap"`` in each configuration's summary.
    route : str
        See `make_route`.
    tracking : bool
        Also run tracking from the true start pose.

    Returns
    -------
    dict
        ``{name: summarize(...)}`` plus ``"world"`` and ``"seeds"``.
    """
    configs = {"paper": PAPER, "best": BEST_CONFIG} if configs is None else configs
    seeds = list(seeds)
    runs = {name: ([], [], []) for name in configs}
    for seed in seeds:
        w = world(seed) if callable(world) else world
        log = make_route(w, seed, n_steps, route)
        taken = make_route(w, seed, n_steps, "tour", kidnap) if kidnap else None
        for name, config in configs.items():
            runs[name][0].append(run_filter(log, config, seed))
            if tracking:
                runs[name][1].append(run_filter(log, config, seed, tracking=True))
            if taken is not None:
                runs[name][2].append(run_filter(taken, config, seed))
    out = {}
    for name, config in configs.items():
        out[name] = summarize(runs[name][0], runs[name][1], config)
        if kidnap:
            out[name]["kidnap"] = summarize_kidnap(runs[name][2], kidnap)
    if isinstance(world, World):
        out["world"] = world.name or str(world.source)
    else:
        out["world"] = "a world per seed"
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
        "success_rate_50",
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
    kid = [n for n in names if "kidnap" in result[n]]
    if kid:
        step = result[kid[0]]["kidnap"]["kidnap_step"]
        lines.append(f"kidnapped before step {step}:")
        for k in (
            "localized_at_kidnap_rate",
            "recovered_rate",
            "recovered_rate_localized",
            "recovery_steps_median",
        ):
            row = "".join(
                f"{_fmt(result[n]['kidnap'][k]) if n in kid else '-':>12s}"
                for n in names
            )
            lines.append(f"{k:34s}" + row)
    return "\n".join(lines)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``robotlib reproduce``."""
    parser.description = "Run the paper's MCL experiment and the best configuration."
    parser.add_argument(
        "--world",
        default="corridor",
        help="world name or path, or gen-KIND: a world generated afresh per seed",
    )
    parser.add_argument("--seeds", type=int, default=20, help="number of seeds")
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--steps", type=int, default=MAX_STEPS, help="steps per run")
    parser.add_argument("--particles", type=int, default=300, help="paper's N")
    parser.add_argument("--lam", type=float, default=0.5, help="paper's lambda")
    parser.add_argument("--floor", type=int, default=RESIZE_FLOOR, help="resize floor")
    parser.add_argument("--json", type=Path, default=None, help="write results here")
    parser.add_argument(
        "--kidnap",
        type=int,
        default=None,
        metavar="STEP",
        help="also run with the robot moved to a random free pose before STEP",
    )
    parser.add_argument(
        "--recovery",
        action="store_true",
        help="also run MCL.best with its kidnapping recovery on (best+rec)",
    )
    parser.add_argument(
        "--route",
        choices=("auto", "corridor", "tour"),
        default="auto",
        help="the corridor drive (bundled worlds) or a planned tour (any other)",
    )


def run(args: argparse.Namespace) -> int:
    """Run ``robotlib reproduce``; return the exit status."""
    route = args.route
    if args.world.startswith("gen-"):  # a fresh generated world per seed, toured
        world = functools.partial(seeded_world, args.world)
        route = "tour" if route == "auto" else route
    else:
        world = load_world(args.world)
    paper = FilterConfig(
        "paper", "paper", {"n": args.particles, "lam": args.lam, "floor": args.floor}
    )
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    t0 = time.perf_counter()
    if args.kidnap is not None and not 1 <= args.kidnap <= args.steps - HOLD:
        raise SystemExit(f"--kidnap must be in [1, {args.steps - HOLD}]")
    configs = {"paper": paper, "best": BEST_CONFIG}
    if args.recovery:
        configs["best+rec"] = RECOVERY_CONFIG
    result = reproduce(
        world,
        seeds,
        configs,
        args.steps,
        kidnap=args.kidnap,
        route=route,
    )
    result["world"] = args.world
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
