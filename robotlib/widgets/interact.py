"""`interact`: ipywidgets' ``interact`` for a plotting function, but it answers at once.

``ipywidgets.interact(f, x=slider)`` keeps the old figure and says nothing
until ``f`` has drawn the new one (a second or more for a planner's flood).
This one, on every change, first shows that it is working (a status line
reading "running ...", the old figure greyed), then calls ``f`` with the
controls' values, shows its figure (``plt.show()`` inside ``f``, or any
figure ``f`` leaves open) in place of the old one and says how long it took.
An error in ``f`` shows as its traceback in the figure's place. The status
line is a `StatusLine`: in the browser it reads "running ..." and greys the
figure the moment a control moves, even while the kernel still draws the
previous change (``f`` itself runs on the kernel's main thread, as pyplot
wants).

Used by the labs' small panels (Lab 1's likelihood exponent, Lab 4's A*
weight). Imports nothing of robotlib but the panels' shared pieces.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from ._live import STALE_CSS, status_line

__all__ = ["InteractPanel", "interact"]


class InteractPanel:
    """Controls above the figure ``function(**values)`` draws, redrawn on change.

    Parameters
    ----------
    function : callable
        Draws one figure from keyword arguments (``plt.show()`` at its end).
    **controls : ipywidgets.ValueWidget
        One widget per keyword argument of ``function`` (a slider, a
        dropdown); their ``value`` is what ``function`` receives.

    Attributes
    ----------
    widget : ipywidgets.VBox
        The controls, the status line and the figure.
    status : ipywidgets.Label
    runs : int
        Figures drawn so far (it draws once when made).
    seconds : float
        How long the last figure took, s.
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
        self.runs, self.seconds = 0, 0.0
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
        """Say that it is working, grey the old figure, draw the new one."""
        shown, front = self.describe(), self.status.values()
        self.status.value = f"running: {shown} ..."
        self.status.busy = True
        self.output.add_class("robotlib-stale")
        t0 = time.perf_counter()
        failed = True
        with self.output:  # in a kernel an error shows here, as a traceback
            self.output.clear_output(wait=True)
            _draw(self.function, {k: c.value for k, c in self.controls.items()})
            failed = False
        self.output.remove_class("robotlib-stale")
        self.runs += 1
        self.seconds = time.perf_counter() - t0
        self.status.value = (
            f"{shown}: failed" if failed else f"{shown} (drawn in {self.seconds:.1f} s)"
        )
        self.status.answered(front)

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)


def interact(function: Callable, **controls) -> None:
    """Show an `InteractPanel` of ``function`` (like ``ipywidgets.interact``).

    Returns None, so a cell that ends with this line shows the panel once.
    """
    from IPython.display import display

    display(InteractPanel(function, **controls))


def _draw(function: Callable, values: dict) -> None:
    """Call ``function``, then show any figure it left open (as ``interact`` does)."""
    from ipywidgets.widgets.interaction import show_inline_matplotlib_plots

    function(**values)
    show_inline_matplotlib_plots()
