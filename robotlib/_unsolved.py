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
function. A ``NameError`` for a name an exercise asks for (one no code cell
of the notebook binds, written in backticks after an exercise's heading) or
for one a cell above binds but did not get to is said as plainly (the first
shown as the exercise's ``NotImplementedError``, `_shown_type`). Any other
error keeps IPython's traceback; the cell still fails.

`Demo` (``with robotlib.notebook.demo():``) wraps a demonstration that calls
a student's code: while that code is unsolved, the block stops and the cell
prints one line, ``This demonstration needs your `drive_square` (Exercise
1)...``, instead of failing, so Run All goes on to the next demonstration.

Imports nothing of robotlib (layer 7, beside `robotlib.notebook`).
"""

from __future__ import annotations

import ast
import json
import os
import re
import sys
from pathlib import Path

__all__ = [
    "install",
    "unsolved_message",
    "exercise_of",
    "structured_traceback",
    "missing_name_message",
    "Demo",
]

_EXERCISE = re.compile(r"^#+\s*Exercise\s+([0-9]+[a-z]?)\b", re.M | re.I)
_CACHE: dict[Path, tuple[float, list]] = {}


def install(shell) -> bool:
    """Install the handler on an IPython ``shell``; return True."""
    shell.set_custom_exc((NotImplementedError, NameError), _handler)
    return True


def _handler(shell, etype, value, tb, tb_offset=None):
    lines = _message(shell, value, tb)
    pyplot = sys.modules.get("matplotlib.pyplot")
    if lines is not None and pyplot is not None:
        pyplot.close("all")  # the cell's empty axes would show under the message
    shown = _shown_type(etype, lines)
    stb = _formatted(shell, shown, value, tb, tb_offset, lines)
    if shown is not etype:
        value = shown(lines[0])
    shell._showtraceback(shown, value, stb)
    return None


def _shown_type(etype: type, lines: list[str] | None) -> type:
    """Return the error's type as the cell shows it: an undone exercise's is one.

    A check that reads a name an exercise defines (a matrix, a constant)
    fails with a ``NameError`` while the exercise's cell still ends in
    ``raise NotImplementedError()``; it reads "NotImplementedError: Exercise
    N is not done yet", as a check calling an unsolved function does, and
    not like a typing mistake. A name a cell above binds (a cell that
    stopped early, or was not run) stays a ``NameError``.
    """
    if etype is NameError and lines and " is not done yet" in lines[0]:
        return NotImplementedError
    return etype


def structured_traceback(shell, etype, value, tb, tb_offset=None) -> list[str]:
    """Return the lines the handler shows for an error (IPython's ``stb``).

    The plain message of `unsolved_message` for an unsolved exercise, else
    IPython's own traceback. A panel that runs a cell's function on a worker
    thread shows an error with these lines, as the kernel's thread would.
    """
    lines = _message(shell, value, tb)
    shown = _shown_type(etype, lines)
    return _formatted(shell, shown, value, tb, tb_offset, lines)


def _message(shell, value, tb) -> list[str] | None:
    if isinstance(value, NameError):
        return missing_name_message(getattr(value, "name", None))
    if isinstance(value, NotImplementedError):
        return unsolved_message(shell, tb)
    return None


def _formatted(shell, etype, value, tb, tb_offset, lines) -> list[str]:
    if lines is None:
        return shell.InteractiveTB.structured_traceback(
            etype, value, tb, tb_offset=tb_offset
        )
    red, bold, off = "\x1b[31m", "\x1b[1m", "\x1b[0m"
    return [f"{red}{bold}{etype.__name__}{off}: {lines[0]}", *lines[1:]]


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
    define = re.compile(rf"^\s*(def|class)\s+{re.escape(name)}\b", re.M)
    return _exercise_of_cell(notebook, define.search)


def _exercise_of_cell(notebook, is_it) -> str | None:
    """`exercise_of` the first code cell whose source ``is_it(source)`` says is it."""
    try:
        cells = _cells(Path(notebook))
    except (OSError, ValueError):
        return None
    heading = None
    for cell in cells:
        source = "".join(cell.get("source", ""))
        if cell.get("cell_type") == "markdown":
            found = _EXERCISE.findall(source)
            heading = found[-1] if found else heading
            continue
        if cell.get("cell_type") == "code" and is_it(source):
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
    found = _raised_in_cell(shell, tb)
    if found is None:
        return None
    where, name, top_level = found
    now = getattr(shell, "execution_count", None)
    cell = (
        "in this cell"
        if top_level or where == now
        else f"in the cell above (In [{where}])"
    )
    what = "your code" if top_level else f"`{name}`"
    exercise = _exercise_of_this_cell(shell) if top_level else _exercise(name)
    return [
        f"{exercise or 'This exercise'} is not done yet: write {what} {cell}.",
        "Replace its `raise NotImplementedError()` with your code, run that cell,",
        "then run this one again.",
    ]


def _raised_in_cell(shell, tb) -> tuple[int, str, bool] | None:
    """(cell number, function name, raised at the top level) of a cell's raise."""
    cells = getattr(getattr(shell, "compile", None), "_filename_map", {})
    while tb is not None and tb.tb_next is not None:
        tb = tb.tb_next
    if tb is None:
        return None
    code = tb.tb_frame.f_code
    if code.co_filename not in cells:
        return None  # raised by a library, not by a student's cell
    name = code.co_qualname.split(".<locals>.")[-1]
    return cells[code.co_filename], name, code.co_name == "<module>"


def _exercise(name: str) -> str:
    top = name.split(".")[0]
    found = (e for nb in _notebooks() if (e := exercise_of(nb, top)))
    return next(found, None) or "This exercise"


def _exercise_of_this_cell(shell) -> str | None:
    """Name the running cell's exercise (a cell whose whole answer is a stub)."""
    raw = getattr(getattr(shell, "history_manager", None), "input_hist_raw", None)
    here = raw[-1].strip() if raw else ""
    if not here:
        return None
    found = (
        e
        for nb in _notebooks()
        if (e := _exercise_of_cell(nb, lambda source: source.strip() == here))
    )
    return next(found, None)


def _bound(source: str) -> set[str]:
    """Return the names a cell binds at its top level (not in its functions)."""
    code = "\n".join(
        "" if line.lstrip().startswith(("%", "!")) else line
        for line in source.splitlines()
    )
    try:
        stack = list(ast.parse(code).body)
    except SyntaxError:
        return set()
    names = set()
    while stack:
        node = stack.pop()
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            names.add(node.name)  # its body binds nothing at the top level
            continue
        if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            names.add(node.id)
        elif isinstance(node, ast.alias):
            names.add((node.asname or node.name).split(".")[0])
        if not isinstance(node, ast.Lambda):
            stack.extend(ast.iter_child_nodes(node))
    return names


def _origin(name: str) -> tuple[str, str | None] | None:
    """Where a notebook would bind ``name``: ("exercise", "Exercise N"), ("cell", None).

    None when no notebook found binds it or asks for it.
    """
    asked = re.compile(rf"`{re.escape(name)}`")
    for notebook in _notebooks():
        try:
            cells = _cells(notebook)
        except (OSError, ValueError):
            continue
        code = [c for c in cells if c.get("cell_type") == "code"]
        if any(name in _bound("".join(c.get("source", ""))) for c in code):
            return "cell", None
        for cell in cells:
            source = "".join(cell.get("source", ""))
            headings = list(_EXERCISE.finditer(source))
            if cell.get("cell_type") == "markdown" and headings:
                if asked.search(source, headings[-1].end()):
                    return "exercise", f"Exercise {headings[-1].group(1)}"
    return None


def missing_name_message(name: str | None, demo: bool = False) -> list[str] | None:
    """Return the lines for a ``NameError`` of an unsolved lab (None if it is not one).

    Parameters
    ----------
    name : str or None
        The name that is not defined.
    demo : bool
        Whether a demonstration (`Demo`) asks: one line then.

    Returns
    -------
    list of str or None
        For a name an exercise asks for, or one a cell of the notebook binds.
    """
    found = _origin(name) if name else None
    if found is None:
        return None
    kind, exercise = found
    if kind == "exercise" and demo:
        return [
            f"This demonstration needs your `{name}` ({exercise}): define it,"
            " run its cell, then run this one again."
        ]
    if kind == "exercise":
        return [
            f"{exercise} is not done yet: define `{name}` in its cell.",
            "Replace its `raise NotImplementedError()` with your code, run that cell,",
            "then run this one again.",
        ]
    if demo:
        return [
            f"This demonstration needs `{name}`, which a cell above makes; that cell"
            " stopped early (it needs an exercise you have not done)."
        ]
    return [
        f"`{name}` is not defined yet: a cell above makes it, and it stopped early",
        "(it needs an exercise you have not done yet, or it was not run).",
    ]


class Demo:
    """A demonstration that needs a student's code: ``with robotlib.notebook.demo():``.

    While that code is unsolved (it raises the released lab's
    ``NotImplementedError``, or a name an exercise defines is missing), the
    block stops there, figures it opened are closed, and one line names
    what it needs; the cell does not fail. Any other error propagates, and
    every error does in a notebook with no ``raise NotImplementedError()``
    left (a solution: a fault there must show).
    """

    def __enter__(self):
        pyplot = sys.modules.get("matplotlib.pyplot")
        self._figures = set(pyplot.get_fignums()) if pyplot else set()
        return self

    def __exit__(self, etype, value, tb):
        if value is None or not _unsolved_notebook():
            return False
        if isinstance(value, NameError):
            lines = missing_name_message(getattr(value, "name", None), demo=True)
        elif isinstance(value, NotImplementedError):
            lines = _needs(tb)
        else:
            return False
        if lines is None:
            return False
        pyplot = sys.modules.get("matplotlib.pyplot")
        for number in set(pyplot.get_fignums()) - self._figures if pyplot else ():
            pyplot.close(number)  # its empty axes would show under the message
        sys.stdout.write(lines[0] + "\n")
        return True


def _unsolved_notebook() -> bool:
    stub = re.compile(r"^\s*raise NotImplementedError\(\)", re.M)
    for notebook in _notebooks():
        try:
            cells = _cells(notebook)
        except (OSError, ValueError):
            continue
        code = (
            "".join(c.get("source", "")) for c in cells if c.get("cell_type") == "code"
        )
        if any(stub.search(source) for source in code):
            return True
    return False


def _needs(tb) -> list[str] | None:
    ipython = sys.modules.get("IPython")
    shell = ipython.get_ipython() if ipython else None
    found = _raised_in_cell(shell, tb) if shell is not None else None
    if found is None or found[2]:
        return None  # a library's error, or the block's own raise
    name = found[1]
    return [
        f"This demonstration needs your `{name}` ({_exercise(name)}): write it,"
        " run its cell, then run this one again."
    ]
