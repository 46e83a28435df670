"""The status line of a lab's first cell: ``robotlib.notebook.loading()``.

``robotlib.notebook.loading()`` shows a line that moves while the cell
imports (the seconds so far and the package importing now, redrawn from a
thread); ``robotlib.notebook.setup()`` ends it with how long it all took
(`loaded`). Public means only: a finder on ``sys.meta_path`` that finds
nothing (it notes names), IPython's display handles and its
``post_run_cell`` event.

A leaf (layer 0): imports nothing of robotlib's (`robotlib.notebook` hands
it the shell).
"""

from __future__ import annotations

import sys
import threading
import time

__all__ = ["start", "now", "loaded"]


class _Importing:
    """A finder on ``sys.meta_path`` that finds nothing: it notes what imports now."""

    def __init__(self):
        self.package = ""

    def find_spec(self, name, path=None, target=None):
        """Note ``name``'s top-level package (a public one); find nothing."""
        if not name.startswith("_"):
            self.package = name.partition(".")[0]


class _LoadingLine:
    """The first cell's status line (`loading`): redrawn from a thread, ended once."""

    def __init__(self, shell, every: float):
        from IPython.display import display

        self.t0, self.now = time.perf_counter(), ""
        self.importing = _Importing()
        self.handle = display(
            {"text/plain": "importing ..."}, raw=True, display_id=True
        )
        self.lock, self.done = threading.Lock(), threading.Event()
        sys.meta_path.insert(0, self.importing)
        shell.events.register("post_run_cell", self._cell_ended)
        self.shell = shell
        threading.Thread(
            target=self._run, args=(every,), name="loading-line", daemon=True
        ).start()

    def _text(self) -> str:
        doing = self.now or f"importing {self.importing.package}".rstrip()
        return f"{self.seconds():.1f} s: {doing} ..."

    def _run(self, every: float) -> None:
        while not self.done.wait(every):
            with self.lock:
                if not self.done.is_set():
                    self.handle.update({"text/plain": self._text()}, raw=True)

    def end(self, text: str) -> None:
        """Stop the line's thread and show ``text`` in its place (once)."""
        with self.lock:
            if self.done.is_set():
                return
            self.done.set()
            self.handle.update({"text/plain": text}, raw=True)
        if self.importing in sys.meta_path:
            sys.meta_path.remove(self.importing)
        self.shell.events.unregister("post_run_cell", self._cell_ended)

    def _cell_ended(self, *_args) -> None:  # before `setup` (an error, say)
        self.end(f"stopped after {self.seconds():.1f} s.")

    def seconds(self) -> float:
        """Seconds since the line showed."""
        return time.perf_counter() - self.t0


LINES: list[_LoadingLine] = []  # the line `setup` ends


def start(shell, every: float) -> None:
    """Show a new line in the running cell of ``shell`` (`robotlib.notebook.loading`).

    Parameters
    ----------
    shell : IPython.core.interactiveshell.InteractiveShell
        A Jupyter kernel's shell.
    every : float
        Seconds between redraws.
    """
    for line in LINES:
        line.end(f"stopped after {line.seconds():.1f} s.")
    LINES[:] = [_LoadingLine(shell, every)]


def now(step: str) -> None:
    """Name the step `loading`'s line shows (instead of the package importing)."""
    for line in LINES:
        line.now = step


def loaded() -> None:
    """End `loading`'s line: how long it all took."""
    while LINES:
        line = LINES.pop()
        line.end(f"Ready ({line.seconds():.1f} s of imports and set-up).")
