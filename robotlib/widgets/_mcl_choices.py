"""The MCL panel's choices as plain functions: `mcl_filter`, `run_mcl`.

`SENSORS`, `RESAMPLERS` and `PRESETS` name what the panel offers;
`mcl_filter` builds the `MCL` those choices make and `run_mcl` runs it over
a logged route into a `History`. Tested headless; `robotlib.widgets.mcl`
re-exports them beside its `MCLPanel`. Imports the localization only.
"""

from __future__ import annotations

import time

import numpy as np

from ..localization import (
    BEST,
    MCL,
    AugmentedInjection,
    BeamParameters,
    BeamSensorModel,
    History,
    KLDResampling,
    LikelihoodFieldSensorModel,
    PaperResampling,
    PaperSensorModel,
    ThresholdResampling,
)
from ..localization.paper import RESIZE_FLOOR

__all__ = ["SENSORS", "RESAMPLERS", "PRESETS", "mcl_filter", "run_mcl"]

SENSORS = ("paper", "beam", "beam (tempered)", "likelihood field")
"""Sensor models the MCL panel offers.

``"beam (tempered)"`` is the beam model with the parameters of `MCL.best`
(``BEST["beam"]``: its log-likelihood scaled down, so that one scan does not
leave a handful of particles carrying all the weight).
"""
RESAMPLERS = (
    "paper (select + resize)",
    "low variance",
    "KLD",
    "KLD when ESS < N/2",
    "low variance + augmented",
)
"""Resampling schemes the MCL panel offers.

``"KLD when ESS < N/2"`` is the KLD-sampling of `MCL.best` (``BEST["kld"]``),
from the initial particle count down to no fewer than ``BEST["kld"]["n_min"]``.
"""
PRESETS = {
    "paper": {
        "sensor": "paper",
        "resampler": "paper (select + resize)",
        "n": 300,
        "lam": 0.5,
    },
    "best (beam + KLD)": {
        "sensor": "beam (tempered)",
        "resampler": "KLD when ESS < N/2",
        "n": int(BEST["n"]),
    },
}
"""Named sets of choices: the paper's filter (`MCL.paper`'s defaults) and the
configuration of `MCL.best` (tempered beam model, KLD-sampling from
``BEST["n"]`` particles)."""

_DEFAULTS = {"n": 300, "lam": 0.5, "sensor": "paper", "resampler": RESAMPLERS[0]}


def mcl_filter(
    world,
    n: int | None = None,
    lam: float | None = None,
    sensor: str | None = None,
    resampler: str | None = None,
    floor: int = RESIZE_FLOOR,
    rng=None,
    init=None,
    preset: str | None = None,
) -> MCL:
    """Build an `MCL` from the MCL panel's choices.

    Parameters
    ----------
    world : World
        The map.
    n : int, optional
        Initial particle count (default: the preset's, else 300).
    lam : float, optional
        The paper's resize lambda (used by ``"paper (select + resize)"``
        only; default: the preset's, else 0.5).
    sensor : str, optional
        One of `SENSORS` (default: the preset's, else ``"paper"``).
    resampler : str, optional
        One of `RESAMPLERS` (default: the preset's, else the paper's): the
        paper's multinomial selection and resize; low-variance (systematic)
        resampling when the effective sample size falls below N/2;
        KLD-sampling every step (at most ``max(n, 2000)`` particles); the
        KLD-sampling of `MCL.best` (when ESS < N/2, from ``n`` particles
        down to ``BEST["kld"]["n_min"]``); or low variance with augmented
        MCL's random injection.
    floor : int
        Smallest population of the paper's resize.
    rng : numpy.random.Generator, int or None
        The filter's randomness.
    init : array_like, shape (3,), optional
        Start around this pose (tracking) instead of uniformly (global).
    preset : str, optional
        A key of `PRESETS`, giving the choices not passed explicitly.
        ``preset="best (beam + KLD)"`` builds the filter `MCL.best` builds.

    Returns
    -------
    MCL
    """
    if preset is not None and preset not in PRESETS:
        raise ValueError(f"unknown preset {preset!r}; choose from {tuple(PRESETS)}")
    given = {"n": n, "lam": lam, "sensor": sensor, "resampler": resampler}
    chosen = {**_DEFAULTS, **PRESETS.get(preset, {})}
    chosen.update({k: v for k, v in given.items() if v is not None})
    n, lam = int(chosen["n"]), float(chosen["lam"])
    sensor, resampler = chosen["sensor"], chosen["resampler"]
    if sensor not in SENSORS:
        raise ValueError(f"unknown sensor {sensor!r}; choose from {SENSORS}")
    if resampler not in RESAMPLERS:
        raise ValueError(f"unknown resampler {resampler!r}; choose from {RESAMPLERS}")
    if n < 1:
        raise ValueError(f"n must be at least 1, got {n}")
    if sensor == "paper":
        model = PaperSensorModel(world)
    elif sensor == "beam":
        model = BeamSensorModel(world, fast=True)
    elif sensor == "beam (tempered)":
        model = BeamSensorModel(world, fast=True, params=BeamParameters(**BEST["beam"]))
    else:
        model = LikelihoodFieldSensorModel(world, fast=True)
    injection = None
    if resampler == RESAMPLERS[0]:
        policy = PaperResampling(lam, int(min(floor, n)))
    elif resampler == "KLD":
        policy = KLDResampling(n_min=min(n, 300), n_max=max(n, 2000))
    elif resampler == "KLD when ESS < N/2":
        kld = dict(BEST["kld"])
        kld["n_min"] = min(n, int(kld["n_min"]))
        kld["n_max"] = n
        policy = KLDResampling(**kld)
        if BEST.get("augmented") is not None:
            injection = AugmentedInjection(**BEST["augmented"])
    else:
        policy = ThresholdResampling("systematic", 0.5)
        if resampler.endswith("augmented"):
            injection = AugmentedInjection()
    return MCL(
        world,
        model,
        resampling=policy,
        n=n,
        injection=injection,
        rng=rng,
        init=init,
    )


def run_mcl(
    route,
    n_steps: int | None = None,
    tracking: bool = False,
    seed=0,
    on_step=None,
    snapshot_steps=(),
    **choices,
):
    """Run a filter built by `mcl_filter` over a logged route.

    Parameters
    ----------
    route : robotlib.experiments.RouteLog
        Odometry, sonar and truth per step.
    n_steps : int, optional
        Use only the first steps.
    tracking : bool
        Start at the true start pose instead of uniformly.
    seed : int or numpy.random.Generator
        The filter's randomness.
    on_step : callable, optional
        ``on_step(k, steps)`` after each step ``k`` (1-based) of ``steps``:
        a progress bar, or a panel's cancellation check (it may raise).
    snapshot_steps : iterable of int
        Steps (1-based) whose particles to keep, in ``history.snapshots``
        (a dict: step to ``particles``, ``weights``, ``truth``,
        ``estimate``), for `plot_particle_snapshots`.
    **choices
        ``n``, ``lam``, ``sensor``, ``resampler``, ``floor``, ``preset`` (see
        `mcl_filter`).

    Returns
    -------
    History
        With the wall time of each step (``time_ms``) and ``snapshots``.
    """
    init = route.truth[0] if tracking else None
    mcl = mcl_filter(route.world, rng=seed, init=init, **choices)
    hist = History()
    hist.snapshots = {}
    keep = {int(k) for k in snapshot_steps}
    steps = len(route) if n_steps is None else min(int(n_steps), len(route))
    for k in range(steps):
        t0 = time.perf_counter()
        mcl.step(route.odometry[max(k - 1, 0)], route.odometry[k], route.sonar[k])
        hist.record(route.truth[k], mcl, 1e3 * (time.perf_counter() - t0))
        if k + 1 in keep:
            hist.snapshots[k + 1] = {
                "particles": np.array(mcl.particles),
                "weights": np.array(mcl.weights),
                "truth": np.array(route.truth[k], dtype=float),
                "estimate": np.array(mcl.last_estimate, dtype=float),
            }
        if on_step is not None:
            on_step(k + 1, steps)
    return hist
