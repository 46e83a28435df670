"""Notebook panels for obstacle avoidance (Lab 2).

Thin wrappers over plain, tested functions:

- `make_controller` builds a controller from the panel's choices (`KINDS`,
  with its gains), `episode_for` runs it on one seeded start/goal pair of an
  avoidance world; `EpisodePanel` adds sliders for the gains, the VFH
  threshold and DWA's clearance weight (``continuous_update=False``: an
  episode runs when a slider is released) and redraws the path and the
  clearance.
- `vfh_replay` replays an episode's sonar and odometry through a VFH and
  records its polar histogram, chosen direction and goal bearing at every
  cycle; `HistogramPanel` shows them with a time slider, beside the map.

Panels run headless (their callbacks are plain methods), so tests set their
values programmatically and read the results. In a kernel an episode runs
on a worker thread (`LiveRunner`: a newer change supersedes it), so the
panel keeps answering; its `StatusLine` greys it in the browser at once.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np
from matplotlib.figure import Figure

from ..avoidance import (
    DWA,
    VFH,
    Braitenberg,
    Bug2,
    DWASettings,
    PotentialField,
    VFHSettings,
    run_episode,
    start_goal_pairs,
)
from ..plotting.avoidance import plot_clearance, plot_episode, plot_polar_histogram
from ..world import load_world
from ._live import (
    STALE_CSS,
    Cancelled,
    LiveRunner,
    error_output,
    figure_output,
    status_line,
)

__all__ = [
    "KINDS",
    "make_controller",
    "episode_for",
    "EpisodePanel",
    "Replay",
    "vfh_replay",
    "HistogramPanel",
]

KINDS = ("VFH", "DWA", "potential field", "Braitenberg explorer", "Bug2")
"""Controllers the episode panel offers."""

_DEFAULTS = {
    "threshold": 150.0, "clearance": 0.4, "k_rep": 0.5, "d0": 1.2, "reach": 1.5,
}  # fmt: skip


def make_controller(
    kind: str,
    threshold=150.0,
    clearance=0.4,
    k_rep=0.5,
    d0=1.2,
    reach=1.5,
    histogram=None,
    direction=None,
    force=None,
    weights=None,
):
    """Build a controller of `KINDS` with the panel's gains.

    ``threshold``: VFH's upper threshold (the lower one is half of it);
    ``clearance``: DWA's weight of the free distance along an arc;
    ``k_rep``, ``d0``: the potential field's repulsion; ``reach``: the range
    at which a Braitenberg vehicle's sonars start to respond, m.
    ``histogram``, ``direction`` (VFH), ``force`` (potential field) and
    ``weights`` (the explorer's matrix) replace the library's parts (Lab 2
    passes the student's).
    """
    if kind == "VFH":
        gains = VFHSettings(threshold_high=threshold, threshold_low=threshold / 2)
        return VFH(settings=gains, histogram=histogram, direction=direction)
    if kind == "DWA":
        return DWA(settings=DWASettings(clearance_weight=clearance))
    if kind == "potential field":
        if force is not None:
            return PotentialField(force=partial(force, k_rep=k_rep, d0=d0))
        return PotentialField(k_rep=k_rep, d0=d0)
    if kind == "Braitenberg explorer":
        return Braitenberg("explorer" if weights is None else weights, reach=reach)
    if kind == "Bug2":
        return Bug2()
    raise ValueError(f"unknown controller {kind!r}; choose from {KINDS}")


def episode_for(world: str, pair: int, kind: str, seed: int = 0, **gains):
    """Run one episode of ``kind`` on pair ``pair`` of ``start_goal_pairs(world)``.

    ``gains``: `make_controller` keywords.
    """
    p = start_goal_pairs(world, pair + 1, seed=seed)[pair]
    c = make_controller(kind, **gains)
    return run_episode(world, c, p.goal, start=p.start, seed=seed)


class EpisodePanel:
    """Choose a controller and its gains; the episode re-runs and is redrawn.

    Parameters
    ----------
    world : str
        An avoidance world.
    kind : str
        Initial controller (`KINDS`).
    pair : int
        Initial start/goal pair (index into ``start_goal_pairs(world, .., seed)``).
    seed : int
        Seed of the pairs and of the simulator.
    **gains
        Initial ``threshold``, ``clearance``, ``k_rep``, ``d0``, ``reach``;
        and parts that replace the library's (``histogram``, ``direction``,
        ``force``, ``weights``: see `make_controller`).

    Attributes
    ----------
    episode : robotlib.avoidance.Episode
        The last run.
    figure : matplotlib.figure.Figure
    widget : ipywidgets.VBox
    """

    def __init__(self, world="utrap", kind="VFH", pair=0, seed=0, **gains):
        import ipywidgets as w

        parts = ("histogram", "direction", "force", "weights")
        self.parts = {k: gains.pop(k) for k in parts if k in gains}
        start = {**_DEFAULTS, **gains}
        self.world_name, self.seed = world, seed
        self.world = load_world(world)
        opts = {"continuous_update": False}
        self.kind = w.Dropdown(options=KINDS, value=kind, description="controller")
        self.pair = w.IntSlider(value=pair, min=0, max=19, description="pair", **opts)
        self.threshold = w.FloatSlider(
            value=start["threshold"], min=20.0, max=1000.0, step=10.0,
            description="VFH thr.", **opts,
        )  # fmt: skip
        self.clearance = w.FloatSlider(
            value=start["clearance"], min=0.0, max=2.0, step=0.1,
            description="DWA clear.", **opts,
        )  # fmt: skip
        self.k_rep = w.FloatSlider(
            value=start["k_rep"], min=0.05, max=3.0, step=0.05,
            description="PF k_rep", **opts,
        )  # fmt: skip
        self.d0 = w.FloatSlider(
            value=start["d0"], min=0.4, max=3.0, step=0.1, description="PF d0", **opts
        )
        self.reach = w.FloatSlider(
            value=start["reach"], min=0.3, max=3.0, step=0.1,
            description="Br. reach", **opts,
        )  # fmt: skip
        self.status = status_line()
        self.output = w.Output()
        self.output.add_class("robotlib-figure")
        controls = (
            self.kind, self.pair, self.threshold, self.clearance, self.k_rep,
            self.d0, self.reach,
        )  # fmt: skip
        for c in controls:
            c.observe(lambda change: self.refresh(), names="value")
        self.status.watch(*controls)
        self.widget = w.VBox(
            [
                w.HTML(STALE_CSS),
                w.HBox([self.kind, self.pair]),
                w.HBox([self.threshold, self.clearance]),
                w.HBox([self.k_rep, self.d0]),
                w.HBox([self.reach]),
                self.status,
                self.output,
            ]
        )
        self.widget.add_class("robotlib-panel")
        self.widget.add_class(f"robotlib-kind-{type(self).__name__}")  # for the test
        self.figure = Figure(figsize=(10, 4))
        self.episode = None
        self.runner = LiveRunner(self._job, self._done, self._failed)
        inline, self.runner.background = self.runner.background, False
        try:  # the first figure is drawn before the cell ends
            self.refresh()
        finally:
            self.runner.background = inline

    def settings(self) -> dict:
        """Return the current gains, as `make_controller` keywords."""
        return {
            "threshold": float(self.threshold.value),
            "clearance": float(self.clearance.value),
            "k_rep": float(self.k_rep.value),
            "d0": float(self.d0.value),
            "reach": float(self.reach.value),
        }

    def refresh(self):
        """Run the episode with the current choices and redraw.

        Says at once that it runs; returns the episode when the run is
        inline (tests, scripts, the first run), else None (on a worker
        thread, the panel redraws itself when the run ends).
        """
        request = {
            "kind": self.kind.value, "pair": int(self.pair.value),
            "settings": self.settings(), "front": self.status.values(),
        }  # fmt: skip
        self.status.value = f"running {request['kind']} on pair {request['pair']} ..."
        self.status.busy = True
        self.output.add_class("robotlib-stale")  # the old figure greys at once
        self.runner.submit(request)
        return None if self.runner.background else self.episode

    def _job(self, request):
        try:
            ep = episode_for(
                self.world_name, request["pair"], request["kind"], self.seed,
                **request["settings"], **self.parts,
            )  # fmt: skip
        except Cancelled:
            raise
        except Exception as e:  # a student's piece failed: say so, keep the trace
            self.status.value = f"the run failed: {type(e).__name__}: {e}"
            self.status.answered(request["front"], busy=self.runner.newer_waiting)
            raise
        self.runner.check()
        self.figure.clf()
        a, b = self.figure.subplots(1, 2, gridspec_kw={"width_ratios": [1.3, 1]})
        plot_episode(a, ep, self.world, echoes=False)
        plot_clearance(b, ep)
        self.runner.check()
        return ep, figure_output(self.figure)

    def _done(self, request, result) -> None:
        self.episode = ep = result[0]
        self.output.outputs = (result[1],)
        self.output.remove_class("robotlib-stale")
        outcome = ep.outcome.replace("_", " ")  # "local minimum", not the code's name
        self.status.value = (
            f"{ep.controller}: {outcome} after {ep.duration:.1f} s, "
            f"min clearance {ep.min_clearance:.2f} m, {ep.collisions} collision(s)"
        )
        self.status.answered(request["front"], busy=self.runner.newer_waiting)

    def _failed(self, request, text) -> None:
        self.output.outputs = (error_output(text),)

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)


@dataclass
class Replay:
    """What a VFH saw and chose at each cycle of an episode.

    Attributes
    ----------
    histograms : numpy.ndarray, shape (T, n_sectors)
    steer : numpy.ndarray, shape (T,)
        Chosen direction, rad, robot frame (nan: all blocked).
    target : numpy.ndarray, shape (T,)
        The goal's bearing, rad, robot frame.
    threshold : float
        The VFH's upper threshold.
    controller : VFH
        The controller after the last cycle (its grid is the final map).
    """

    histograms: np.ndarray
    steer: np.ndarray
    target: np.ndarray
    threshold: float
    controller: VFH


def vfh_replay(episode, controller: VFH | None = None) -> Replay:
    """Feed an episode's sonar and odometry through a VFH; record each cycle."""
    c = VFH() if controller is None else controller
    c.goal = None if episode.goal is None else np.array(episode.goal)
    c.reset()
    hists, steer, target = [], [], []
    for s, p in zip(episode.sonar, episode.odometry, strict=True):
        c.command(s, p)
        hists.append(c.histogram.copy())
        steer.append(c.steer)
        target.append(c.goal_direction(p)[0] if c.goal is not None else 0.0)
    return Replay(np.array(hists), np.array(steer), np.array(target),
                  c.threshold_high, c)  # fmt: skip


class HistogramPanel:
    """A time slider over an episode: the robot on the map and VFH's histogram.

    Parameters
    ----------
    episode : robotlib.avoidance.Episode
    world : robotlib.world.World, optional
    controller : VFH, optional
        The VFH to replay the episode through (default settings if None).
    """

    def __init__(self, episode, world=None, controller=None):
        import ipywidgets as w

        self.episode, self.world = episode, world
        self.replay = vfh_replay(episode, controller)
        self.step = w.IntSlider(
            value=0, min=0, max=len(episode.time) - 1, description="cycle",
            continuous_update=False,
        )  # fmt: skip
        self.output = w.Output()
        self.output.add_class("robotlib-figure")
        self.status = status_line()
        self.step.observe(lambda change: self.refresh(), names="value")
        self.status.watch(self.step)
        self.widget = w.VBox([w.HTML(STALE_CSS), self.step, self.status, self.output])
        self.widget.add_class("robotlib-panel")
        self.widget.add_class(f"robotlib-kind-{type(self).__name__}")  # for the test
        self.figure = Figure(figsize=(10, 4))
        self.runner = LiveRunner(self._job, self._done, self._failed)
        inline, self.runner.background = self.runner.background, False
        try:
            self.refresh()
        finally:
            self.runner.background = inline

    def refresh(self):
        """Redraw the map and the histogram at the slider's cycle."""
        k = int(self.step.value)
        self.status.value = f"drawing cycle {k} ..."
        self.status.busy = True
        self.output.add_class("robotlib-stale")
        self.runner.submit({"k": k, "front": self.status.values()})

    def _job(self, request):
        k = request["k"]
        ep, r = self.episode, self.replay
        self.figure.clf()
        a = self.figure.add_subplot(1, 2, 1)
        b = self.figure.add_subplot(1, 2, 2, projection="polar")
        plot_episode(a, ep, self.world, echoes=False, at=k)
        a.set_title(f"t = {ep.time[k]:.1f} s")
        plot_polar_histogram(b, r.histograms[k], r.threshold, r.steer[k], r.target[k])
        self.runner.check()
        return figure_output(self.figure)

    def _done(self, request, result) -> None:
        k, ep = request["k"], self.episode
        self.output.outputs = (result,)
        self.output.remove_class("robotlib-stale")
        self.status.value = f"cycle {k} of {len(ep.time) - 1}, t = {ep.time[k]:.1f} s"
        self.status.answered(request["front"], busy=self.runner.newer_waiting)

    def _failed(self, request, text) -> None:
        self.status.value = "the drawing failed: " + text.strip().splitlines()[-1]
        self.status.answered(request["front"], busy=self.runner.newer_waiting)
        self.output.outputs = (error_output(text),)

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)
