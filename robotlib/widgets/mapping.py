"""Notebook panel for mapping (Lab 5): log-odds weights, sensor, particles.

`build_map` (plain, tested) maps a recorded drive with the chosen sensor and
log-odds weights, at the true poses, the odometry's, or FastSLAM's with a
chosen particle count; `MappingPanel` puts sliders over it and redraws the
map beside the truth (``continuous_update=False``).
"""

from __future__ import annotations

import matplotlib.pyplot as plt

from ..mapping import (
    InverseLaserModel,
    InverseSonarModel,
    map_laser,
    map_score,
    map_sonar,
    run_fastslam,
)
from ..plotting.mapping import plot_map_vs_truth
from ._live import STALE_CSS

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
        self.status = w.Label()
        for c in (self.l_occ, self.l_free, self.n, self.sensor, self.poses):
            c.observe(lambda _: self.redraw(), names="value")
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
        self.score = None
        self.redraw()

    def redraw(self):
        """Rebuild the map from the current choices and draw it."""
        what = f"{self.sensor.value}, {self.poses.value} poses"
        self.status.value = f"mapping: {what} ..."
        self.out.add_class("robotlib-stale")  # the old map greys at once
        try:
            grid, self.score = build_map(
                self.log, self.sensor.value, self.poses.value, self.l_occ.value,
                self.l_free.value, self.n.value,
            )  # fmt: skip
        except Exception as e:  # say so in the panel, keep the trace
            self.status.value = f"the map failed: {type(e).__name__}: {e}"
            raise
        with self.out:
            self.out.clear_output(wait=True)
            fig, ax = plt.subplots(figsize=(6, 4.5))
            plot_map_vs_truth(ax, grid, self.log.world,
                              title=f"F1 {self.score.f1:.2f}")  # fmt: skip
            plt.show()
        self.out.remove_class("robotlib-stale")
        self.status.value = f"{what}: F1 {self.score.f1:.2f}"

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)
