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


def _line(k):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(3, 2))
    fig.add_subplot().plot([0, 1], [0, k])
    return fig


def test_interact_panel_drops_a_superseded_change_and_coalesces_the_waiting_ones(
    monkeypatch,
):
    """On the worker, a change made while an older one runs is the only one drawn."""
    import threading

    from robotlib.widgets import _live
    from robotlib.widgets._live import figure_output
    from robotlib.widgets.interact import InteractPanel

    monkeypatch.setattr(_live, "in_kernel", lambda: True)  # changes go to the worker
    calls, started, gate = [], threading.Event(), threading.Event()

    def show(k=1.0):
        calls.append(k)
        if k == 2.0:  # the first change: still running when the next ones come
            started.set()
            assert gate.wait(5), "the change ran on the thread that made it"
        return _line(k)

    slider = w.FloatSlider(value=1.0, min=0.0, max=3.0, step=0.5)
    panel = InteractPanel(show, k=slider)  # the first figure: drawn inline
    assert panel.runs == 1 and calls == [1.0]
    slider.value = 2.0  # returns at once: k = 2 runs on the worker
    assert started.wait(30) and panel.status.value == "running: k = 2 ..."
    slider.value = 2.5  # both while k = 2 runs: coalesced into one run of 3
    slider.value = 3.0
    assert panel.status.value == "running: k = 3 ..." and panel.status.busy
    gate.set()
    assert panel.runner.wait(30)
    assert calls == [1.0, 2.0, 3.0]  # 2.5 never ran
    assert panel.runs == 2 and panel.runner.cancelled == 1  # 2's figure not drawn
    (shown,) = panel.output.outputs
    assert shown == figure_output(_line(3.0))  # the newest change's own figure
    assert panel.status.value.startswith("k = 3 (drawn in")
    assert panel.status.drawn == panel.status.values() and not panel.status.busy
    assert "robotlib-stale" not in panel.output._dom_classes


def test_interact_panel_on_the_worker_shows_an_error_in_the_figures_place(
    monkeypatch,
):
    from robotlib.widgets import _live
    from robotlib.widgets.interact import InteractPanel

    monkeypatch.setattr(_live, "in_kernel", lambda: True)

    def show(k=1.0):
        if k > 2.0:
            raise ValueError("too big")
        return _line(k)

    slider = w.FloatSlider(value=1.0, min=0.0, max=3.0, step=0.5)
    panel = InteractPanel(show, k=slider)
    assert panel.runner.background and panel.returns_figure
    slider.value = 2.5
    assert panel.runner.wait(30)
    (shown,) = panel.output.outputs
    assert shown["output_type"] == "error" and shown["ename"] == "ValueError"
    assert "too big" in "".join(shown["traceback"])
    assert panel.status.value == "k = 2.5: failed" and panel.runs == 1
    slider.value = 1.5  # and it recovers
    assert panel.runner.wait(30) and panel.runs == 2
    assert panel.output.outputs[0]["data"]["image/png"]


def test_interact_panel_runs_only_the_newest_of_queued_pyplot_changes(monkeypatch):
    """In a kernel, changes read back to back give one pyplot run, the newest."""
    import asyncio

    from robotlib.widgets import interact as panel_module

    monkeypatch.setattr(panel_module, "in_kernel", lambda: True)
    calls = []

    def show(k=1.0):  # draws with pyplot: returns no figure
        import matplotlib.pyplot as plt

        calls.append(k)
        plt.plot([0, 1], [0, k])
        plt.close("all")

    async def session():
        slider = w.FloatSlider(value=1.0, min=0.0, max=3.0, step=0.5)
        panel = panel_module.InteractPanel(show, k=slider)
        assert calls == [1.0] and panel.returns_figure is False  # drawn at once
        for k in (2.0, 2.5, 3.0):  # queued while an older change drew
            slider.value = k
        assert calls == [1.0] and panel.status.value == "running: k = 3 ..."
        await asyncio.sleep(4 * panel_module.COALESCE_S)
        return panel

    panel = asyncio.run(session())
    assert calls == [1.0, 3.0]
    assert panel.runs == 2 and panel.status.value.startswith("k = 3 (drawn in")
    assert not panel.status.busy
