"""Panels on a worker thread and their browser-side status line (headless)."""

from __future__ import annotations

import ipywidgets as w

from robotlib.widgets import avoidance as panels
from robotlib.widgets._status import StatusLine, front_value


def test_status_line_records_what_the_browser_holds():
    slider = w.FloatSlider(value=0.5, min=0, max=1, step=0.1)
    choice = w.Dropdown(options=["a", "b", "c"], value="b")
    status = StatusLine()
    status.watch(slider, choice)
    assert status.controls == [slider.model_id, choice.model_id]
    # a dropdown's browser model holds its index, a slider its value
    assert status.drawn == {slider.model_id: 0.5, choice.model_id: 1}
    asked = status.values()
    slider.value, choice.value = 0.7, "c"
    assert front_value(choice) == 2 and status.drawn != status.values()
    status.answered(asked, busy=True)  # drew the older values; a newer run waits
    assert status.drawn == {slider.model_id: 0.5, choice.model_id: 1} and status.busy
    status.answered()
    assert status.drawn == status.values() and not status.busy


def test_episode_panel_on_a_worker_keeps_the_newest_and_its_numbers():
    panel = panels.EpisodePanel("utrap", kind="potential field")
    inline = panels.episode_for("utrap", 0, "VFH", 0, **panel.settings())
    panel.runner.background = True
    panel.kind.value = "Bug2"  # superseded by the next change
    panel.kind.value = "VFH"
    assert panel.status.busy and "robotlib-stale" in panel.output._dom_classes
    assert panel.runner.wait(120)
    ep = panel.episode
    assert ep.controller == inline.controller == "VFH"
    assert (ep.outcome, ep.duration) == (inline.outcome, inline.duration)
    assert (ep.truth == inline.truth).all()  # same settings, same numbers
    assert panel.runner.runs <= 3  # the first, and at most one stale run
    assert panel.status.drawn == panel.status.values() and not panel.status.busy
    assert "robotlib-stale" not in panel.output._dom_classes
    (shown,) = panel.output.outputs
    assert shown["data"]["image/png"]  # drawn from the worker, no capture
    assert panel.status.value.startswith("VFH: ")
