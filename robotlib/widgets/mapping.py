"""Notebook panel for mapping (Lab 5): log-odds weights, sensor, particles.

`build_map` (plain, tested) maps a recorded drive with the chosen sensor and
log-odds weights, at the true poses, the odometry's, or FastSLAM's with a
chosen particle count; `MappingPanel` puts sliders over it and redraws the
map beside the truth (``continuous_update=False``). In a kernel the map is
built on a worker thread (`LiveRunner`: a newer change supersedes it), so the
panel keeps answering; its `StatusLine` greys it in the browser at once.
"""

from __future__ import annotations

from matplotlib.figure import Figure

from ..mapping import (
    InverseLaserModel,
    InverseSonarModel,
    map_laser,
    map_score,
    map_sonar,
    run_fastslam,
)
from ..plotting.mapping import plot_map_vs_truth
from ._live import (
    STALE_CSS,
    Cancelled,
    LiveRunner,
    error_output,
    figure_output,
    status_line,
)

__all__ = ["build_map", "MappingPanel"]


def build_map(log, sensor="sonar", poses="true", l_occ=0.9, l_free=-0.35,
              n_particles=30, rng=0):  # fmt: skip
    """Map ``log`` and return ``(grid, score)``.

    ``poses``: ``"true"``, ``"odometry"`` or ``"fastslam"`` (``n_particles``).
    """
    res = 0.1 if sensor == "sonar" else 0.05
    if poses == "fastslam":
        r = run_fastslam(log, n_particles, sensor, rng=rng)
        return r.map, r.score
    p = log.truth if poses == "true" else log.odometry
    if sensor == "sonar":
        g = map_sonar(log.world, p, log.sonar, res, log.sonar_model,
                      InverseSonarModel(l_occ=l_occ, l_free=l_free))  # fmt: skip
    else:
        g = map_laser(log.world, p, log.laser, res, log.laser_model,
                      InverseLaserModel(l_occ=l_occ, l_free=l_free))  # fmt: skip
    return g, map_score(g, log.world, res)


class MappingPanel:
    """Sliders for the log-odds weights and particle count; sensor and poses."""

    def __init__(self, log):
        import ipywidgets as w

        self.log = log
        opts = dict(continuous_update=False)
        self.l_occ = w.FloatSlider(
            0.9, min=0.1, max=3.0, step=0.1, description="l_occ", **opts
        )
        self.l_free = w.FloatSlider(
            -0.35, min=-2.0, max=-0.05, step=0.05, description="l_free", **opts
        )
        self.n = w.IntSlider(
            30, min=5, max=100, step=5, description="particles", **opts
        )
        self.sensor = w.ToggleButtons(options=["sonar", "laser"], description="sensor")
        self.poses = w.ToggleButtons(
            options=["true", "odometry", "fastslam"], description="poses"
        )
        self.out = w.Output()
        self.out.add_class("robotlib-figure")
        self.status = status_line()
        controls = (self.l_occ, self.l_free, self.n, self.sensor, self.poses)
        for c in controls:
            c.observe(lambda _: self.redraw(), names="value")
        self.status.watch(*controls)
        self.widget = w.VBox(
            [
                w.HTML(STALE_CSS),
                self.sensor,
                self.poses,
                self.l_occ,
                self.l_free,
                self.n,
                self.status,
                self.out,
            ]  # fmt: skip
        )
        self.widget.add_class("robotlib-panel")
        self.widget.add_class(f"robotlib-kind-{type(self).__name__}")  # for the test
        self.score = None
        self.runner = LiveRunner(self._job, self._done, self._failed)
        inline, self.runner.background = self.runner.background, False
        try:  # the first map is drawn before the cell ends
            self.redraw()
        finally:
            self.runner.background = inline

    def redraw(self):
        """Rebuild the map from the current choices and draw it.

        Says at once that it runs; inline (tests, scripts, the first map) the
        map is drawn on return, in a kernel on a worker thread.
        """
        request = {
            "what": f"{self.sensor.value}, {self.poses.value} poses",
            "args": (self.sensor.value, self.poses.value, self.l_occ.value,
                     self.l_free.value, self.n.value),
            "front": self.status.values(),
        }  # fmt: skip
        self.status.value = f"mapping: {request['what']} ..."
        self.status.busy = True
        self.out.add_class("robotlib-stale")  # the old map greys at once
        self.runner.submit(request)

    def _job(self, request):
        try:
            grid, score = build_map(self.log, *request["args"])
        except Cancelled:
            raise
        except Exception as e:  # say so in the panel, keep the trace
            self.status.value = f"the map failed: {type(e).__name__}: {e}"
            self.status.answered(request["front"], busy=self.runner.newer_waiting)
            raise
        self.runner.check()
        fig = Figure(figsize=(6, 4.5))
        plot_map_vs_truth(fig.add_subplot(), grid, self.log.world,
                          title=f"F1 {score.f1:.2f}")  # fmt: skip
        return score, figure_output(fig)

    def _done(self, request, result) -> None:
        self.score, shown = result
        self.out.outputs = (shown,)
        self.out.remove_class("robotlib-stale")
        self.status.value = f"{request['what']}: F1 {self.score.f1:.2f}"
        self.status.answered(request["front"], busy=self.runner.newer_waiting)

    def _failed(self, request, text) -> None:
        self.out.outputs = (error_output(text),)

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)
