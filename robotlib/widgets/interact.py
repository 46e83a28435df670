"""`interact`: ipywidgets' ``interact`` for a plotting function, but it answers at once.

``ipywidgets.interact(f, x=slider)`` keeps the old figure and says nothing
until ``f`` has drawn the new one (a second or more for a planner's flood).
This one, on every change, first shows that it is working (a status line
reading "running ...", the old figure greyed), then calls ``f`` with the
controls' values, shows its figure in place of the old one and says how
long it took. An error in ``f`` shows as its traceback (or an unsolved
exercise's plain message) in the figure's place. The status line is a
`StatusLine`: in the browser it reads "running ..." and greys the figure the
moment a control moves, even while the kernel still draws an older change.

Two kinds of ``f``:

- ``f`` **returns a figure** it made with ``matplotlib.figure.Figure`` (no
  pyplot): in a kernel, every change after the first runs ``f`` and renders
  its figure on a worker thread (`LiveRunner`), so the kernel keeps reading
  the controls. Changes made while ``f`` runs are coalesced into one run of
  the newest, and the figure of a run that a newer change superseded is
  never rendered nor shown. The first figure is drawn before the cell ends.
- ``f`` **draws with pyplot** (``plt.show()``, or figures left open): pyplot
  is not safe from another thread, so ``f`` runs on the kernel's thread, as
  ``ipywidgets.interact`` runs it. In a kernel, a change's run waits
  `COALESCE_S` on the kernel's event loop first, so the changes that queued
  up while an older run drew are read before any runs: only the newest of
  them runs.

Used by the labs' small panels (Lab 1's likelihood exponent, Lab 4's A*
weight). Imports nothing of robotlib but the panels' shared pieces and the
unsolved-exercise message.
"""

from __future__ import annotations

import asyncio
import time
import traceback
from collections.abc import Callable

from ._live import (
    STALE_CSS,
    LiveRunner,
    figure_output,
    in_kernel,
    ipython_shell,
    status_line,
)

__all__ = ["COALESCE_S", "InteractPanel", "interact"]

COALESCE_S = 0.05
"""s a pyplot function's run waits in a kernel, so newer changes supersede it."""


class InteractPanel:
    """Controls above the figure ``function(**values)`` draws, redrawn on change.

    Parameters
    ----------
    function : callable
        Makes one figure from keyword arguments: returns a
        ``matplotlib.figure.Figure`` (then it runs on a worker thread in a
        kernel), or draws with pyplot (``plt.show()`` at its end; then it
        runs on the kernel's thread).
    **controls : ipywidgets.ValueWidget
        One widget per keyword argument of ``function`` (a slider, a
        dropdown); their ``value`` is what ``function`` receives.

    Attributes
    ----------
    widget : ipywidgets.VBox
        The controls, the status line and the figure.
    status : StatusLine
    runner : LiveRunner
        Runs a figure-returning ``function`` for changes after the first
        (``runner.runs``: calls it made; ``runner.cancelled``: calls whose
        figure a newer change superseded).
    runs : int
        Figures drawn so far (it draws once when made).
    seconds : float
        How long the last figure took, s (``function`` and its rendering).
    returns_figure : bool or None
        Whether ``function`` returned a figure when last called without an
        error (None before that).
    """

    def __init__(self, function: Callable, **controls):
        import ipywidgets as w

        self.function, self.controls = function, controls
        self.status = status_line()
        self.output = w.Output()
        self.output.add_class("robotlib-figure")
        self.widget = w.VBox(
            [w.HTML(STALE_CSS), *controls.values(), self.status, self.output]
        )
        self.widget.add_class("robotlib-panel")
        self.widget.add_class(f"robotlib-kind-{type(self).__name__}")  # for the test
        self.runs, self.seconds = 0, 0.0
        self.returns_figure: bool | None = None
        self.runner = LiveRunner(self._job, self._done)
        self._latest: dict | None = None  # the newest change's request
        for name, c in controls.items():
            if hasattr(c, "description") and not c.description:
                c.description = name  # as ipywidgets.interact labels it
            c.observe(self.run, names="value")
        self.status.watch(*controls.values())
        self.run()

    def describe(self) -> str:
        """Return the controls' values, as the status line names them."""
        return ", ".join(
            f"{k} = {c.value:g}" if isinstance(c.value, float) else f"{k} = {c.value}"
            for k, c in self.controls.items()
        )

    def run(self, _change=None) -> None:
        """Say that it is working, grey the old figure, draw the new one.

        A figure-returning ``function`` in a kernel is then run on the worker
        (this returns at once). A pyplot one runs here: for a change, in a
        kernel, `COALESCE_S` later, and not at all if a newer change came
        meanwhile; otherwise at once.
        """
        request = {
            "shown": self.describe(),
            "front": self.status.values(),
            "values": {k: c.value for k, c in self.controls.items()},
            "t0": time.perf_counter(),
        }
        self._latest = request
        self.status.value = f"running: {request['shown']} ..."
        self.status.busy = True
        self.output.add_class("robotlib-stale")
        if self.returns_figure and self.runner.background:
            self.runner.submit(request)
        elif _change is not None and (loop := _kernel_loop()) is not None:
            loop.call_later(COALESCE_S, self._inline_if_newest, request)
        else:
            self._inline(request)

    def _inline_if_newest(self, request: dict) -> None:
        if request is self._latest:  # else the newer change's own run draws
            self._inline(request)

    def _inline(self, request: dict) -> None:
        """Run ``function`` on this thread (the first figure, pyplot, no kernel)."""
        import matplotlib.pyplot as plt
        from matplotlib.figure import Figure

        failed, figure = True, None
        before = set(plt.get_fignums())
        with self.output:  # in a kernel an error shows here, as a traceback
            if not self.returns_figure:
                self.output.clear_output(wait=True)
            figure = self.function(**request["values"])
            if not isinstance(figure, Figure):
                _show_pyplot()
            failed = False
        if failed:  # no half-drawn figure under the error
            for number in set(plt.get_fignums()) - before:
                plt.close(number)
        if not failed:
            self.returns_figure = isinstance(figure, Figure)
        shown = (figure_output(figure),) if self.returns_figure and not failed else None
        self._done(request, (failed, shown))

    def _job(self, request: dict):
        """Call ``function`` and render its figure (the worker's part)."""
        from matplotlib.figure import Figure

        try:
            figure = self.function(**request["values"])
            if not isinstance(figure, Figure):
                raise TypeError(
                    f"{getattr(self.function, '__name__', 'the function')} returned "
                    f"{type(figure).__name__}, not a matplotlib Figure, after it "
                    "had returned one"
                )
        except Exception as e:  # shown in the panel, as the kernel's thread would
            return True, (_error_output(e),)
        self.runner.check()  # superseded by a newer change: never rendered
        return False, (figure_output(figure),)

    def _done(self, request: dict, result) -> None:
        failed, shown = result
        if shown is not None:
            self.output.outputs = shown
        newer = request is not self._latest or self.runner.newer_waiting
        if not newer:
            self.output.remove_class("robotlib-stale")
        self.runs += not failed
        self.seconds = time.perf_counter() - request["t0"]
        said = request["shown"]
        if newer:  # what the status says is what runs now
            self.status.value = f"running: {self._latest['shown']} ..."
        elif failed:
            self.status.value = f"{said}: failed"
        else:
            self.status.value = f"{said} (drawn in {self.seconds:.1f} s)"
        self.status.answered(request["front"], busy=newer)

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)


def interact(function: Callable, **controls) -> None:
    """Show an `InteractPanel` of ``function`` (like ``ipywidgets.interact``).

    Returns None, so a cell that ends with this line shows the panel once.
    """
    from IPython.display import display

    display(InteractPanel(function, **controls))


def _show_pyplot() -> None:
    """Show any figure left open by a pyplot function (as ``interact`` does)."""
    from ipywidgets.widgets.interaction import show_inline_matplotlib_plots

    show_inline_matplotlib_plots()


def _error_output(error: BaseException) -> dict:
    """Return ``error`` as the error output the kernel's thread would show.

    In a kernel: the lines of IPython's traceback, or an unsolved exercise's
    plain message (`robotlib._unsolved`) where the notebook's set-up asked
    for it; outside one, Python's traceback. Starts at ``function``'s frame.
    """
    etype, tb = type(error), error.__traceback__
    tb = tb.tb_next if tb is not None and tb.tb_next is not None else tb
    shell = ipython_shell() if in_kernel() else None
    if shell is None:
        stb = traceback.format_exception(etype, error, tb)
    elif isinstance(error, NotImplementedError) and (
        NotImplementedError in tuple(shell.custom_exceptions)
    ):
        from .._unsolved import structured_traceback

        stb = structured_traceback(shell, etype, error, tb)
    else:
        stb = shell.InteractiveTB.structured_traceback(etype, error, tb)
    return {
        "output_type": "error",
        "ename": etype.__name__,
        "evalue": str(error),
        "traceback": list(stb),
    }


def _kernel_loop() -> asyncio.AbstractEventLoop | None:
    """Return the kernel's running event loop, or None (no kernel, no loop)."""
    if not in_kernel():
        return None
    try:
        return asyncio.get_running_loop()
    except RuntimeError:
        return None
