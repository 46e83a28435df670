"""Lab 2's panels, driven programmatically (headless)."""

from __future__ import annotations

import numpy as np
import pytest

from robotlib.avoidance import VFH, run_episode, start_goal_pairs
from robotlib.widgets import avoidance as panels


def test_make_controller_kinds():
    for kind in panels.KINDS:
        assert panels.make_controller(kind).name.startswith(kind.split()[0])
    vfh = panels.make_controller("VFH", threshold=300.0)
    assert vfh.threshold_high == 300.0 and vfh.threshold_low == 150.0
    assert panels.make_controller("DWA", clearance=1.5).settings.clearance_weight == 1.5
    with pytest.raises(ValueError, match="controller"):
        panels.make_controller("teleport")


def test_episode_panel_reruns_on_a_change():
    panel = panels.EpisodePanel("utrap", kind="potential field")
    assert panel.episode.outcome == "local_minimum"
    panel.kind.value = "VFH"
    assert panel.episode.controller == "VFH"
    panel.threshold.value = 300.0
    assert "VFH" in panel.status.value
    panel.kind.value = "DWA"
    panel.clearance.value = 1.0  # DWA's slider re-runs it with the new weight
    assert panel.episode.controller == "DWA" and "DWA" in panel.status.value


def test_replay_matches_the_controller_that_drove():
    pair = start_goal_pairs("clutter", 1, seed=2)[0]
    ep = run_episode("clutter", VFH(), pair.goal, start=pair.start, seed=2, max_time=15)
    replay = panels.vfh_replay(ep)
    # the same sonar and odometry through the same VFH give the same commands
    c = VFH(goal=pair.goal)
    for k in range(len(ep.time) - 1):
        assert c.command(ep.sonar[k], ep.odometry[k]) == tuple(ep.commands[k])
        np.testing.assert_array_equal(c.histogram, replay.histograms[k])
    hp = panels.HistogramPanel(ep)
    hp.step.value = len(ep.time) // 2
    assert len(hp.figure.axes) == 2


def test_episode_panel_says_it_runs_first_and_what_failed():
    seen = []

    def histogram(*args, **kwargs):  # a student's piece, watched, then broken
        seen.append((panel.status.value, set(panel.output._dom_classes)))
        raise RuntimeError("not written yet")

    panel = panels.EpisodePanel("utrap", kind="potential field")
    assert "robotlib-stale" not in panel.output._dom_classes
    assert panel.status.value.startswith("potential field: local minimum")
    panel.parts["histogram"] = histogram
    with pytest.raises(RuntimeError, match="not written yet"):
        panel.kind.value = "VFH"
    assert seen and seen[0][0] == "running VFH on pair 0 ..."  # said before the run
    assert "robotlib-stale" in seen[0][1]  # and the old figure greyed
    assert panel.status.value == "the run failed: RuntimeError: not written yet"
