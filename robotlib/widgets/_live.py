"""Running a panel's job so the panel answers at once: `LiveRunner`, `Cancelled`.

A panel's slider change must show within 100 ms that something is running,
and a newer change must not wait for an older run to finish. `LiveRunner`
runs the panel's job on one worker thread (numba kernels release the GIL,
so the kernel keeps reading the slider messages meanwhile): each `submit`
supersedes the run before it, which stops at its next `LiveRunner.check`
(raising `Cancelled`), and submissions that arrive during a run are
coalesced into one run of the newest. Without a Jupyter kernel (tests,
scripts) or with ``background=False`` it runs the job inline, so a test
that sets a slider can read the result on the next line.

Imports nothing of robotlib but the leaf `robotlib._ipython` (whose
`in_kernel` and `ipython_shell` it re-exports); panels in this package use it.
"""

from __future__ import annotations

import threading
import traceback
from collections.abc import Callable

from .._ipython import in_kernel, ipython_shell

__all__ = [
    "STALE_CSS",
    "Cancelled",
    "LiveRunner",
    "in_kernel",
    "ipython_shell",
    "figure_output",
    "error_output",
    "status_line",
]

STALE_CSS = "<style>.robotlib-stale,.robotlib-stale img{opacity:.45}</style>"
"""A panel puts this in its box; its last figure, class ``robotlib-stale``,
shows greyed while a newer one computes."""


class Cancelled(Exception):
    """Raised inside a job by `LiveRunner.check` when a newer run was asked for."""


class LiveRunner:
    """Run the newest of a panel's requests, cancelling and coalescing older ones.

    Parameters
    ----------
    job : callable
        ``job(request) -> result``; called on the worker thread (inline when
        not in the background). It should call `check` between steps.
    done : callable
        ``done(request, result)``, called after a job that was not
        superseded (on the same thread as the job).
    failed : callable, optional
        ``failed(request, text)`` with the formatted traceback when a job
        raises anything but `Cancelled`.
    background : bool, optional
        Run on a worker thread; default: inside a Jupyter kernel only.

    Attributes
    ----------
    runs, cancelled : int
        Jobs started, and jobs stopped by a newer request.
    """

    def __init__(
        self,
        job: Callable,
        done: Callable,
        failed: Callable | None = None,
        background: bool | None = None,
    ):
        self.job, self.done, self.failed = job, done, failed
        self.background = in_kernel() if background is None else bool(background)
        self.runs = self.cancelled = 0
        self._generation = 0
        self._pending = None
        self._busy = False
        self._cond = threading.Condition()
        self._thread: threading.Thread | None = None

    def submit(self, request) -> None:
        """Ask for a run of ``request``; supersede any run before it."""
        with self._cond:
            self._generation += 1
            self._pending = (self._generation, request)
            if self.background:
                if self._thread is None or not self._thread.is_alive():
                    self._thread = threading.Thread(
                        target=self._work, name="robotlib-panel", daemon=True
                    )
                    self._thread.start()
                self._cond.notify_all()
                return
        self._run_pending()

    def check(self, generation: int | None = None) -> None:
        """Raise `Cancelled` if a newer request came after the running one."""
        mine = self._running if generation is None else generation
        if mine != self._generation:
            raise Cancelled

    @property
    def newer_waiting(self) -> bool:
        """True when a request newer than the running one waits."""
        with self._cond:
            return self._pending is not None

    @property
    def busy(self) -> bool:
        """True while a request is waiting or running."""
        with self._cond:
            return self._busy or self._pending is not None

    def wait(self, timeout: float | None = None) -> bool:
        """Block until no request is waiting or running; return False on timeout."""
        with self._cond:
            return self._cond.wait_for(
                lambda: not self._busy and self._pending is None, timeout
            )

    _running = 0

    def _run_pending(self) -> None:
        with self._cond:
            if self._pending is None:
                return
            (self._running, request), self._pending = self._pending, None
            self._busy = True
        self.runs += 1
        try:
            result = self.job(request)
            self.check()
            self.done(request, result)
        except Cancelled:
            self.cancelled += 1
        except Exception:  # shown in the panel, never lost in a thread
            if self.failed is None or not self.background:
                raise
            self.failed(request, traceback.format_exc())
        finally:
            with self._cond:
                self._busy = False
                self._cond.notify_all()

    def _work(self) -> None:
        while True:
            with self._cond:
                if not self._cond.wait_for(lambda: self._pending is not None, 60.0):
                    self._thread = None
                    return
            self._run_pending()


def figure_output(figure) -> dict:
    """Return ``figure`` as an output (PNG) to put in an ``ipywidgets.Output``.

    Setting ``output.outputs = (figure_output(fig),)`` shows it from any
    thread (no ``with output:`` capture, which belongs to the kernel's main
    thread); drawn as Jupyter's inline backend draws (tight box).
    """
    import base64
    import io

    buf = io.BytesIO()
    figure.savefig(buf, format="png", bbox_inches="tight")
    return {
        "output_type": "display_data",
        "data": {
            "image/png": base64.b64encode(buf.getvalue()).decode("ascii"),
            "text/plain": f"<Figure of {len(figure.axes)} axes>",
        },
        "metadata": {},
    }


def error_output(text: str) -> dict:
    """Return a traceback's text as an ``ipywidgets.Output`` output (stderr)."""
    return {"output_type": "stream", "name": "stderr", "text": text}


def status_line():
    """Return a new `robotlib.widgets._status.StatusLine` (anywidget loads on use).

    Imported here, not at the top of the panels' modules, so that importing
    a panel (a lab's first cell) does not load anywidget.
    """
    from ._status import StatusLine

    return StatusLine()
