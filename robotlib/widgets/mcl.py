"""Notebook panels for Monte Carlo localization (Lab 3).

Each panel is a thin wrapper over plain, tested functions:

- `mcl_filter` builds a filter from the panel's choices (or a preset of
  them, `PRESETS`: the paper's filter, or the configuration of `MCL.best`),
  `run_mcl` runs it over a logged route (`robotlib.experiments.drive_route`)
  and returns its `History`, `plot_mcl_run` draws the paper's Figs. 2-4 from
  that history; `MCLPanel` adds sliders for lambda and the particle count
  (``continuous_update=False``: a run starts when a slider is released),
  choices of sensor model, resampler, preset and world, and a kidnapping:
  the "Kidnap" button (or a step typed in "kidnap at") drives a seeded tour
  (`robotlib.experiments.drive_tour`) on which the robot is moved to a
  random free pose before that step, unknown to the filter, and the status
  line says how many steps the filter took to recover.

Panels run headless (their callbacks are plain methods), so tests set their
values programmatically and read the results.
"""

from __future__ import annotations

import io
import time

import numpy as np

from ..localization import History
from ..plotting.mcl import plot_mcl_run, plot_particle_snapshots
from ._live import LiveRunner, status_line
from ._mcl_choices import (
    _DEFAULTS,
    PRESETS,
    RESAMPLERS,
    SENSORS,
    mcl_filter,
    run_mcl,
)

__all__ = [
    "SENSORS",
    "RESAMPLERS",
    "PRESETS",
    "mcl_filter",
    "run_mcl",
    "plot_mcl_run",
    "plot_particle_snapshots",
    "PARTICLE_COUNTS",
    "MCLPanel",
]

PARTICLE_COUNTS = (
    50, 75, 100, 150, 200, 300, 500, 750, 1000, 1500, 2000, 3000, 5000, 7500,
    10_000, 15_000, 20_000, 30_000, 50_000,
)  # fmt: skip
"""The particle slider's stops: a log scale (1, 1.5, 2, 3, 5, 7.5 per decade)
holding the paper's 300, 1,000 and `MCL.best`'s 50,000; the typed box next to
it takes any other count."""

# The last figure greys out while a newer run computes:
_STALE_CSS = "<style>.robotlib-stale,.robotlib-stale img{opacity:.45}</style>"


class MCLPanel:
    """Sliders and choices that re-run MCL on a route and redraw Figs. 2-4.

    A change shows at once that a run has started (the status line, a
    progress bar, the old figure greyed) and runs in the background; a newer
    change cancels a run still going, and changes made during a run are
    coalesced into one run of the newest settings. Lambda is greyed out
    unless the paper's resampler (the only one that uses it) is chosen.

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
    background : bool, optional
        Run changes on a worker thread (default: inside a Jupyter kernel). The
        first run, when the panel is made, is always inline.
    **initial
        Initial ``lam``, ``n``, ``sensor``, ``resampler``, ``tracking``,
        ``kidnap`` (a step, 0 for none), or a ``preset`` (a key of
        `PRESETS`) for the choices not given.

    Attributes
    ----------
    history : History
        The last finished run.
    figure : matplotlib.figure.Figure
        The last drawing (not pyplot's: shown as the panel's image only).
    runner : LiveRunner
        Runs, cancels and coalesces the panel's runs (``runner.wait()``
        blocks until the newest has been drawn).
    widget : ipywidgets.VBox
        The panel (displaying the object displays it).
    """

    CUSTOM = "custom"
    """The preset shown when the choices match no preset."""

    def __init__(self, route, n_steps=None, seed=0, background=None, **initial):
        import ipywidgets as w
        from matplotlib.figure import Figure

        from ..plotting.style import WIDTH
        from ..world import world_names

        unknown = set(initial) - {*_DEFAULTS, "tracking", "preset", "kidnap"}
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
            tooltip="the paper's resize: N <- N exp(-lambda Ip)",
        )  # fmt: skip
        self.n = w.SelectionSlider(
            options=self._count_options(int(start["n"])), value=int(start["n"]),
            description="particles", continuous_update=False,
        )  # fmt: skip
        self.n_typed = w.BoundedIntText(
            value=int(start["n"]), min=1, max=200_000, description="or type",
            layout=w.Layout(width="170px"),
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
        steps = len(route) if n_steps is None else min(n_steps, len(route))
        last = max(1, steps - 1)
        self.kidnap = w.BoundedIntText(
            value=int(initial.get("kidnap", 0)), min=0, max=last,
            description="kidnap at", layout=w.Layout(width="170px"),
            tooltip="move the robot elsewhere before this step (0: never)",
        )  # fmt: skip
        self.kidnap_button = w.Button(
            description="Kidnap", tooltip="kidnap the robot halfway through the run"
        )
        self.kidnap_button.on_click(self._kidnap_clicked)
        self.status = status_line()
        self.progress = w.IntProgress(
            value=0, min=0, max=1, layout=w.Layout(width="200px")
        )
        self.image = w.Image(format="png", layout=w.Layout(max_width="100%"))
        self.image.add_class("robotlib-mcl-figure")
        for control in (self.lam, self.n, self.sensor, self.resampler, self.tracking):
            control.observe(self._changed, names="value")
        self.n_typed.observe(self._typed, names="value")
        self.preset.observe(self._preset_changed, names="value")
        self.world.observe(self._changed, names="value")
        self.kidnap.observe(self._changed, names="value")
        self.status.watch(
            self.lam, self.n, self.sensor, self.resampler, self.tracking,
            self.world, self.kidnap,
        )  # fmt: skip
        self.widget = w.VBox(
            [
                w.HTML(_STALE_CSS),
                w.HBox([self.world, self.preset, self.tracking]),
                w.HBox([self.lam, self.n, self.n_typed]),
                w.HBox([self.sensor, self.resampler]),
                w.HBox([self.kidnap_button, self.kidnap]),
                w.HBox([self.progress, self.status]),
                self.image,
            ]
        )
        self.widget.add_class("robotlib-panel")
        self.widget.add_class(f"robotlib-kind-{type(self).__name__}")  # for the test
        self._grey_unused()
        self.figure = Figure(figsize=(WIDTH, 5.4))
        self.history: History | None = None
        self.recovered_after: int | None = None
        self.runner = LiveRunner(self._job, self._done, self._failed, background)
        self.timings: dict[str, float] = {}
        inline, self.runner.background = self.runner.background, False
        try:
            self.refresh()
        finally:
            self.runner.background = inline

    @staticmethod
    def _count_options(n: int):
        counts = sorted({*PARTICLE_COUNTS, int(n)})
        return [(f"{c:,}", c) for c in counts]

    @property
    def route(self):
        """The route of the chosen world (driven on first use)."""
        return self._route_of(self.world.value)

    def _route_of(self, name, kidnap: int = 0):
        key = name if not kidnap else (name, int(kidnap))
        if key not in self._routes:
            from ..experiments import drive_route
            from ..experiments.tours import drive_tour
            from ..world import load_world

            world = self._route_of(name).world if kidnap else load_world(name)
            if kidnap:
                self._routes[key] = drive_tour(
                    world, self._route_seed, self._route_len, kidnap=int(kidnap)
                )
            else:
                self._routes[key] = drive_route(
                    world, seed=self._route_seed, n_steps=self._route_len
                )
        return self._routes[key]

    def _kidnap_clicked(self, button=None) -> None:
        """Kidnap the robot halfway through the run (or at the step typed)."""
        steps = self._route_len if self.n_steps is None else self.n_steps
        if self.kidnap.value == 0:
            self.kidnap.value = max(1, min(self.kidnap.max, steps // 2))  # runs
        else:
            self.refresh()

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

    def _grey_unused(self) -> None:
        """Disable the controls the chosen settings ignore (lambda)."""
        self.lam.disabled = self.resampler.value != RESAMPLERS[0]

    def _changed(self, change) -> None:
        if self._holding:
            return
        self._set(preset=self.matching_preset(), n_typed=int(self.n.value))
        self._grey_unused()
        self.refresh()

    def _typed(self, change) -> None:
        if self._holding:
            return
        n = int(change["new"])
        if n in [v for _, v in self.n.options]:
            self.n.value = n  # runs through _changed
            return
        self._holding = True
        try:
            self.n.options = self._count_options(n)
            self.n.value = n
        finally:
            self._holding = False
        self._changed(None)

    def _preset_changed(self, change) -> None:
        if self._holding or change["new"] not in PRESETS:
            return
        values = dict(PRESETS[change["new"]])
        if "n" in values:
            values["n_typed"] = values["n"]
        self._set(**values)
        self._grey_unused()
        self.refresh()

    def _set(self, **values) -> None:
        """Set controls without a run per control."""
        self._holding = True
        try:
            for name, value in values.items():
                if value is not None:
                    getattr(self, name).value = value
        finally:
            self._holding = False

    def describe(self, settings=None, world=None) -> str:
        """One line naming a run's settings (the figure's title)."""
        s = self.settings() if settings is None else settings
        text = f"{world or self.world.value}: {s['sensor']} sensor, {s['resampler']}"
        if s["resampler"] == RESAMPLERS[0]:
            text += f", lambda {s['lam']:g}"
        start = "at the true start" if s["tracking"] else "uniform"
        return text + f", {s['n']:,} particles ({start})"

    def refresh(self) -> History | None:
        """Run the filter with the current settings and redraw.

        Shows at once that the run started; returns the new history when
        the run is inline (tests, scripts, the first run), else None (the
        panel redraws itself when the run ends: ``runner.wait()`` waits).
        """
        request = {
            "settings": self.settings(),
            "world": self.world.value,
            "kidnap": int(self.kidnap.value),
            "asked": time.perf_counter(),
            "front": self.status.values(),
        }
        self.status.value = f"running: {self.describe(request['settings'])} ..."
        self.status.busy = True
        self.progress.value = 0
        self.progress.bar_style = "info"
        self.image.add_class("robotlib-stale")
        self.timings["feedback_s"] = time.perf_counter() - request["asked"]
        self.runner.submit(request)
        return None if self.runner.background else self.history

    def _job(self, request):
        route = self._route_of(request["world"], request.get("kidnap", 0))
        last = [0.0]

        def on_step(k, steps):
            self.runner.check()
            now = time.perf_counter()
            if now - last[0] > 0.1 or k == steps:
                last[0] = now
                self.progress.max, self.progress.value = steps, k

        history = run_mcl(
            route, self.n_steps, seed=self.seed, on_step=on_step,
            **request["settings"],
        )  # fmt: skip
        self.runner.check()
        title = self.describe(request["settings"], request["world"])
        kidnap = request.get("kidnap", 0)
        plot_mcl_run(history, route.world, self.figure, title=title, kidnap=kidnap)
        self.runner.check()
        buf = io.BytesIO()
        self.figure.savefig(buf, format="png")
        return history, buf.getvalue(), route

    def _done(self, request, result) -> None:
        history, png, route = result
        self.history = history
        self.image.value = png
        self.image.remove_class("robotlib-stale")
        self.progress.bar_style = "success"
        self.timings["redraw_s"] = time.perf_counter() - request["asked"]
        loc = history.localized_step()
        err = history.error
        step_ms = float(np.nanmean(history.time_ms)) if len(history) else 0.0
        if loc:
            result = f"localized from step {loc}; mean error then: "
            result += f"{err[loc - 1 :].mean():.2f} m"
        else:
            result = f"not localized (final error {err[-1]:.2f} m)"
        kidnap = request.get("kidnap", 0)
        if kidnap and kidnap < len(err):
            from ..experiments.reproduce import HOLD, RECOVERED, recovery_steps

            r = recovery_steps(err, kidnap)
            self.recovered_after = r
            back = f"error under {RECOVERED:g} m for {HOLD} steps"
            result += f"; kidnapped before step {kidnap}: " + (
                f"recovered after {r} steps ({back})"
                if r is not None
                else f"not recovered by the end (no {back})"
            )
        else:
            self.recovered_after = None
        self.status.value = f"{request['world']}, {self.preset.value}: {result}; " + (
            f"{step_ms:.0f} ms per step" if step_ms >= 1 else "under 1 ms per step"
        )
        self.status.answered(request["front"], busy=self.runner.newer_waiting)

    def _failed(self, request, text) -> None:
        self.progress.bar_style = "danger"
        self.status.value = "the run failed: " + text.strip().splitlines()[-1]
        self.status.answered(request["front"], busy=self.runner.newer_waiting)

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)
