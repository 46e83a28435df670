"""Notebook panels for Monte Carlo localization (Lab 3).

Each panel is a thin wrapper over plain, tested functions:

- `mcl_filter` builds a filter from the panel's choices (or a preset of
  them, `PRESETS`: the paper's filter, or the configuration of `MCL.best`),
  `run_mcl` runs it over a logged route (`robotlib.experiments.drive_route`)
  and returns its `History`, `plot_mcl_run` draws the paper's Figs. 2-4 from
  that history; `MCLPanel` adds sliders for lambda and the particle count
  (``continuous_update=False``: a run starts when a slider is released),
  choices of sensor model, resampler, preset and world.

Panels run headless (their callbacks are plain methods), so tests set their
values programmatically and read the results.
"""

from __future__ import annotations

import matplotlib.pyplot as plt

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
from ..plotting import plot_trajectory, plot_world

__all__ = [
    "SENSORS",
    "RESAMPLERS",
    "PRESETS",
    "mcl_filter",
    "run_mcl",
    "plot_mcl_run",
    "MCLPanel",
]

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
    route, n_steps: int | None = None, tracking: bool = False, seed=0, **choices
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
    **choices
        ``n``, ``lam``, ``sensor``, ``resampler``, ``floor``, ``preset`` (see
        `mcl_filter`).

    Returns
    -------
    History
    """
    init = route.truth[0] if tracking else None
    mcl = mcl_filter(route.world, rng=seed, init=init, **choices)
    hist = History()
    steps = len(route) if n_steps is None else min(int(n_steps), len(route))
    for k in range(steps):
        mcl.step(route.odometry[max(k - 1, 0)], route.odometry[k], route.sonar[k])
        hist.record(route.truth[k], mcl)
    return hist


def plot_mcl_run(history: History, world, fig=None, tolerance: float = 0.5):
    """Draw the paper's Figs. 2-4 for one run: trajectories, error, particles.

    Parameters
    ----------
    history : History
        The run.
    world : World
        Its map.
    fig : matplotlib.figure.Figure, optional
        Drawn into (cleared first); a new figure by default.
    tolerance : float
        The "localized" error bound drawn on the error plot, m.

    Returns
    -------
    matplotlib.figure.Figure
    """
    if fig is None:
        fig = plt.figure(figsize=(10, 5.5))
    fig.clear()
    grid = fig.add_gridspec(2, 2, height_ratios=(1.1, 1))
    ax_map = fig.add_subplot(grid[0, :])
    ax_err = fig.add_subplot(grid[1, 0])
    ax_n = fig.add_subplot(grid[1, 1])
    a = history.arrays()
    plot_world(ax_map, world, color="0.4", linewidth=1)
    plot_trajectory(ax_map, a["true_pose"], label="true", color="k")
    plot_trajectory(
        ax_map, a["estimate"], label="estimated", color="tab:red", marker="."
    )
    ax_map.legend(loc="upper right", ncols=2)
    ax_map.set_title("true and estimated trajectory (Fig. 2)")
    ax_err.plot(a["step"], a["error"], color="tab:red")
    ax_err.axhline(tolerance, color="0.5", ls=":", lw=1)
    ax_err.set_xlabel("step")
    ax_err.set_ylabel("position error [m]")
    loc = history.localized_step(tolerance)
    ax_err.set_title(f"error per step (Fig. 3); localized from {loc or '-'}")
    ax_n.plot(a["step"], a["n_particles"], color="tab:blue")
    ax_n.set_xlabel("step")
    ax_n.set_ylabel("particles")
    ax_n.set_ylim(0, None)
    ax_n.set_title("particles per step (Fig. 4)")
    fig.tight_layout()
    return fig


class MCLPanel:
    """Sliders and choices that re-run MCL on a route and redraw Figs. 2-4.

    Parameters
    ----------
    route : robotlib.experiments.RouteLog
        The logged drive to localize on. Choosing another world drives the
        robot there (`robotlib.experiments.drive_route`, with this route's
        seed and length) and localizes on that route instead.
    n_steps : int, optional
        Steps to run (default: the whole route).
    seed : int
        The filter's seed (fixed, so a change of result comes from a setting).
    **initial
        Initial ``lam``, ``n``, ``sensor``, ``resampler``, ``tracking``, or a
        ``preset`` (a key of `PRESETS`) for the choices not given.

    Attributes
    ----------
    history : History
        The last run.
    figure : matplotlib.figure.Figure
        The last drawing.
    widget : ipywidgets.VBox
        The panel (displaying the object displays it).
    """

    CUSTOM = "custom"
    """The preset shown when the choices match no preset."""

    def __init__(self, route, n_steps=None, seed=0, **initial):
        import ipywidgets as w

        from ..world import world_names

        unknown = set(initial) - {*_DEFAULTS, "tracking", "preset"}
        if unknown:
            raise TypeError(f"unknown settings {sorted(unknown)}")
        preset = initial.get("preset")
        if preset is not None and preset not in PRESETS:
            raise ValueError(f"unknown preset {preset!r}; choose from {tuple(PRESETS)}")
        start = {**_DEFAULTS, **PRESETS.get(preset, {})}
        start.update({k: initial[k] for k in _DEFAULTS if k in initial})
        self.n_steps, self.seed = n_steps, seed
        here = route.world.name or "(this route)"
        self._routes = {here: route}
        self._route_seed, self._route_len = route.seed, len(route)
        self._holding = False
        self.lam = w.FloatSlider(
            value=start["lam"], min=0.0, max=5.0, step=0.1,
            description="lambda", continuous_update=False,
        )  # fmt: skip
        self.n = w.IntSlider(
            value=start["n"], min=50, max=max(50_000, int(BEST["n"])), step=50,
            description="particles", continuous_update=False,
        )  # fmt: skip
        self.sensor = w.Dropdown(
            options=SENSORS, value=start["sensor"], description="sensor"
        )
        self.resampler = w.Dropdown(
            options=RESAMPLERS, value=start["resampler"], description="resampler"
        )
        self.tracking = w.Checkbox(
            value=initial.get("tracking", False), description="tracking"
        )
        self.preset = w.Dropdown(
            options=(self.CUSTOM, *PRESETS), value=self.CUSTOM, description="preset"
        )
        self.preset.value = self.matching_preset()
        worlds = world_names()
        self.world = w.Dropdown(
            options=worlds if here in worlds else [here, *worlds],
            value=here,
            description="world",
        )
        self.status = w.Label()
        self.output = w.Output()
        for control in (self.lam, self.n, self.sensor, self.resampler, self.tracking):
            control.observe(self._changed, names="value")
        self.preset.observe(self._preset_changed, names="value")
        self.world.observe(self._changed, names="value")
        self.widget = w.VBox(
            [
                w.HBox([self.world, self.preset, self.tracking]),
                w.HBox([self.lam, self.n]),
                w.HBox([self.sensor, self.resampler]),
                self.status,
                self.output,
            ]
        )
        self.figure = plt.figure(figsize=(10, 5.5))
        plt.close(self.figure)  # shown through the output widget only
        self.history: History | None = None
        self.refresh()

    @property
    def route(self):
        """The route of the chosen world (driven on first use)."""
        name = self.world.value
        if name not in self._routes:
            from ..experiments import drive_route
            from ..world import load_world

            self._routes[name] = drive_route(
                load_world(name), seed=self._route_seed, n_steps=self._route_len
            )
        return self._routes[name]

    def settings(self) -> dict:
        """Return the current choices, as `run_mcl` keywords."""
        return {
            "lam": float(self.lam.value),
            "n": int(self.n.value),
            "sensor": self.sensor.value,
            "resampler": self.resampler.value,
            "tracking": bool(self.tracking.value),
        }

    def matching_preset(self) -> str:
        """Return the preset the current choices make, or `CUSTOM`."""
        now = self.settings()
        for name, values in PRESETS.items():
            if all(now[k] == v for k, v in values.items()):
                return name
        return self.CUSTOM

    def _changed(self, change) -> None:
        if self._holding:
            return
        self._set(preset=self.matching_preset())
        self.refresh()

    def _preset_changed(self, change) -> None:
        if self._holding or change["new"] not in PRESETS:
            return
        self._set(**PRESETS[change["new"]])
        self.refresh()

    def _set(self, **values) -> None:
        """Set controls without a run per control."""
        self._holding = True
        try:
            for name, value in values.items():
                getattr(self, name).value = value
        finally:
            self._holding = False

    def refresh(self) -> History:
        """Run the filter with the current settings and redraw."""
        from IPython.display import display

        route = self.route
        self.history = run_mcl(route, self.n_steps, seed=self.seed, **self.settings())
        plot_mcl_run(self.history, route.world, self.figure)
        loc = self.history.localized_step()
        err = self.history.error
        self.status.value = f"{self.world.value}, {self.preset.value}: " + (
            f"localized from step {loc}; mean error then: {err[loc - 1 :].mean():.2f} m"
            if loc
            else f"not localized (final error {err[-1]:.2f} m)"
        )
        self.output.clear_output(wait=True)
        with self.output:
            display(self.figure)
        return self.history

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)
