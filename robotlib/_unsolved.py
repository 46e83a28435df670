"""An unsolved exercise said plainly: the IPython handler `robotlib.notebook` installs.

A released lab's exercise ends in ``raise NotImplementedError()``; a check
that calls it would show that error under a screen of library frames. The
handler here recognises a ``NotImplementedError`` raised by code written in
a notebook cell, and shows instead::

    NotImplementedError: Exercise 3 is not done yet: write `drive_and_log`
    in the cell above (In [12]): replace its `raise NotImplementedError()`
    with your code, run that cell, then this one.

The exercise's number (``### Exercise N`` above the cell that defines the
function) and id (the cell's ``robotlib.exercise`` metadata) are read from
the notebook file when the kernel knows it (``JPY_SESSION_NAME``, set by
Jupyter), else from a notebook in the working directory that defines the
function. Any other error keeps IPython's traceback; the cell still fails.

Imports nothing of robotlib (layer 7, beside `robotlib.notebook`).
"""

from __future__ import annotations

import json
import os
import re
import sys
from pathlib import Path

__all__ = ["install", "unsolved_message", "exercise_of", "structured_traceback"]

_EXERCISE = re.compile(r"^#+\s*Exercise\s+([0-9]+[a-z]?)\b", re.M | re.I)
_CACHE: dict[Path, tuple[float, list]] = {}


def install(shell) -> bool:
    """Install the handler on an IPython ``shell``; return True."""
    shell.set_custom_exc((NotImplementedError,), _handler)
    return True


def _handler(shell, etype, value, tb, tb_offset=None):
    lines = unsolved_message(shell, tb)
    pyplot = sys.modules.get("matplotlib.pyplot")
    if lines is not None and pyplot is not None:
        pyplot.close("all")  # the cell's empty axes would show under the message
    stb = _formatted(shell, etype, value, tb, tb_offset, lines)
    shell._showtraceback(etype, value, stb)
    return None


def structured_traceback(shell, etype, value, tb, tb_offset=None) -> list[str]:
    """Return the lines the handler shows for an error (IPython's ``stb``).

    The plain message of `unsolved_message` for an unsolved exercise, else
    IPython's own traceback. A panel that runs a cell's function on a worker
    thread shows an error with these lines, as the kernel's thread would.
    """
    return _formatted(shell, etype, value, tb, tb_offset, unsolved_message(shell, tb))


def _formatted(shell, etype, value, tb, tb_offset, lines) -> list[str]:
    if lines is None:
        return shell.InteractiveTB.structured_traceback(
            etype, value, tb, tb_offset=tb_offset
        )
    red, bold, off = "\x1b[31m", "\x1b[1m", "\x1b[0m"
    return [f"{red}{bold}NotImplementedError{off}: {lines[0]}", *lines[1:]]


def _cells(notebook: Path) -> list:
    mtime = notebook.stat().st_mtime
    cached = _CACHE.get(notebook)
    if cached is None or cached[0] != mtime:
        cells = json.loads(notebook.read_text(encoding="utf-8")).get("cells", [])
        _CACHE[notebook] = cached = (mtime, cells)
    return cached[1]


def exercise_of(notebook, name: str) -> str | None:
    """Name the exercise whose cell defines ``name`` in a notebook file.

    Parameters
    ----------
    notebook : path-like
        The ``.ipynb`` file.
    name : str
        A function's (or class's) name.

    Returns
    -------
    str or None
        ``"Exercise 3"`` (from the nearest ``Exercise N`` heading above the
        cell), else ``"Exercise `id`"`` from the cell's ``robotlib.exercise``
        metadata, else ``"This exercise"``; None when no cell defines it.
    """
    try:
        cells = _cells(Path(notebook))
    except (OSError, ValueError):
        return None
    define = re.compile(rf"^\s*(def|class)\s+{re.escape(name)}\b", re.M)
    heading = None
    for cell in cells:
        source = "".join(cell.get("source", ""))
        if cell.get("cell_type") == "markdown":
            found = _EXERCISE.findall(source)
            heading = found[-1] if found else heading
            continue
        if cell.get("cell_type") == "code" and define.search(source):
            meta = cell.get("metadata", {}).get("robotlib", {})
            if heading is not None:
                return f"Exercise {heading}"
            if meta.get("exercise"):
                return f"Exercise `{meta['exercise']}`"
            return "This exercise"
    return None


def _notebooks():
    session = os.environ.get("JPY_SESSION_NAME", "")
    if session.endswith(".ipynb") and Path(session).is_file():
        yield Path(session)
    yield from sorted(Path.cwd().glob("*.ipynb"))


def unsolved_message(shell, tb) -> list[str] | None:
    """Return the lines for an unsolved exercise's error (None if it is not one).

    Parameters
    ----------
    shell : IPython.core.interactiveshell.InteractiveShell
        The shell (its compiler knows which files are notebook cells).
    tb : traceback
        The error's traceback.

    Returns
    -------
    list of str or None
    """
    cells = getattr(getattr(shell, "compile", None), "_filename_map", {})
    while tb is not None and tb.tb_next is not None:
        tb = tb.tb_next
    if tb is None:
        return None
    code = tb.tb_frame.f_code
    if code.co_filename not in cells:
        return None  # raised by a library, not by a student's cell
    where = cells[code.co_filename]
    name = code.co_qualname.split(".<locals>.")[-1]
    now = getattr(shell, "execution_count", None)
    if code.co_name == "<module>" or where == now:
        cell = "in this cell"
    else:
        cell = f"in the cell above (In [{where}])"
    if code.co_name == "<module>":
        what, exercise = "your code", None
    else:
        what = f"`{name}`"
        top = name.split(".")[0]
        exercise = next((e for nb in _notebooks() if (e := exercise_of(nb, top))), None)
    return [
        f"{exercise or 'This exercise'} is not done yet: write {what} {cell}.",
        "Replace its `raise NotImplementedError()` with your code, run that cell,",
        "then run this one again.",
    ]
