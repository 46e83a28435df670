"""Notebook helpers for the course tools: markers, check cells, release.

A lab's source notebook (in ``solutions/``) marks

- solutions, in code or markdown cells, between ``### BEGIN SOLUTION`` and
  ``### END SOLUTION`` lines; the release replaces each region with
  ``# YOUR CODE HERE`` / ``raise NotImplementedError()`` (code, at the
  marker's indentation) or ``YOUR ANSWER HERE`` (markdown);
- graded check cells, by their metadata
  ``{"robotlib": {"grade_id": "weights", "points": 2}}``; a check cell may
  hold hidden tests between ``### BEGIN HIDDEN TESTS`` and
  ``### END HIDDEN TESTS``, removed on release and put back at grading.

Notebooks are written deterministically (sorted keys, one-space indent, a
final newline, no outputs or execution counts in released labs, cell ids kept
from the source), so regenerating ``labs/`` gives no diff.
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass
from pathlib import Path

import nbformat
from nbformat import NotebookNode

__all__ = [
    "META_KEY",
    "NotebookError",
    "CheckCell",
    "read_notebook",
    "notebook_text",
    "write_notebook",
    "check_meta",
    "check_cells",
    "check_graded_exercises",
    "cell_id",
    "strip_region",
    "release_notebook",
    "NBVAL_TAGS",
    "Exercise",
    "exercises",
    "setup_cell",
]

META_KEY = "robotlib"
"""Cell metadata key holding ``grade_id`` and ``points`` of a check cell."""

SOLUTION = ("### BEGIN SOLUTION", "### END SOLUTION")
HIDDEN = ("### BEGIN HIDDEN TESTS", "### END HIDDEN TESTS")
CODE_STUB = ("# YOUR CODE HERE", "raise NotImplementedError()")
ANSWER_STUB = ("YOUR ANSWER HERE",)

NBVAL_TAGS = frozenset(
    {
        "nbval-ignore-output",
        "nbval-check-output",
        "nbval-raises-exception",
        "nbval-skip",
        "raises-exception",
        "pytest-validate-ignore-output",
    }
)
"""Cell tags that change what nbval does with a cell."""

KERNELSPEC = {
    "display_name": "Python 3 (ipykernel)",
    "language": "python",
    "name": "python3",
}

_GRADE_ID = re.compile(r"^[A-Za-z][A-Za-z0-9_.-]{0,63}$")


class NotebookError(ValueError):
    """A lab notebook is malformed (bad markers, bad check metadata, ...)."""


@dataclass(frozen=True)
class CheckCell:
    """A graded check cell of a lab.

    Attributes
    ----------
    grade_id : str
        The check's name (a gradebook column).
    points : float
        Points earned when the check passes.
    cell_id : str
        The cell's id (stable across releases).
    index : int
        Position of the cell in the notebook (all cells counted).
    """

    grade_id: str
    points: float
    cell_id: str
    index: int
    exercises: tuple[str, ...] = ()
    manual: bool = False
    rubric: str = ""


@dataclass(frozen=True)
class Exercise:
    """A cell where the student writes code.

    Attributes
    ----------
    exercise_id : str
        The exercise's name (``{"robotlib": {"exercise": ...}}``).
    cell_id : str
        The cell's id.
    index : int
        Position of the cell in the notebook (all cells counted).
    writes : tuple of str
        Dotted names of the library functions whose work the exercise asks
        for (an answer reaching them scores zero).
    names : tuple of str
        The top-level names the student writes (definitions that hold a
        solution region); the checks call these.
    """

    exercise_id: str
    cell_id: str
    index: int
    writes: tuple[str, ...] = ()
    names: tuple[str, ...] = ()


def read_notebook(path: str | Path) -> NotebookNode:
    """Read a notebook (nbformat 4) from ``path``.

    Raises
    ------
    NotebookError
        If the file is not a readable notebook.
    """
    try:
        return nbformat.read(str(path), as_version=4)
    except Exception as exc:  # json, validation and encoding errors alike
        raise NotebookError(f"{path}: not a readable notebook ({exc})") from exc


def notebook_text(nb: NotebookNode) -> str:
    """Serialise ``nb`` deterministically (sorted keys, final newline)."""
    return nbformat.writes(nb, version=4) + "\n"


def write_notebook(nb: NotebookNode, path: str | Path) -> bool:
    """Write ``nb`` to ``path`` if its text changed; return True if written."""
    path = Path(path)
    text = notebook_text(nb)
    if path.exists() and path.read_text(encoding="utf-8") == text:
        return False
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(path)
    return True


def check_meta(cell: dict, where: str = "cell") -> dict | None:
    """Return the grading metadata of a check or written-answer cell, or None.

    The dict has ``grade_id``, ``points``, ``exercises`` (the exercises the
    check grades, default ``[grade_id]``), ``manual`` and ``rubric``.

    Parameters
    ----------
    cell : dict
        A notebook cell.
    where : str
        Names the cell in error messages.

    Raises
    ------
    NotebookError
        If the cell carries malformed check metadata.
    """
    meta = cell.get("metadata", {}).get(META_KEY)
    if not isinstance(meta, dict) or "grade_id" not in meta:
        return None
    gid = meta["grade_id"]
    if not isinstance(gid, str) or not _GRADE_ID.match(gid):
        raise NotebookError(f"{where}: bad grade_id {gid!r} (letters, digits, _.-)")
    points = meta.get("points", 1)
    if isinstance(points, bool) or not isinstance(points, int | float) or points <= 0:
        raise NotebookError(f"{where}: points of {gid!r} must be > 0, got {points!r}")
    manual = meta.get("manual", False) is True
    if manual and cell.get("cell_type") != "markdown":
        raise NotebookError(f"{where}: written answer {gid!r} must be a markdown cell")
    if not manual and cell.get("cell_type") != "code":
        raise NotebookError(f"{where}: check {gid!r} must be a code cell")
    exs = meta.get("exercises", [gid])
    if not isinstance(exs, list) or not all(isinstance(e, str) for e in exs):
        raise NotebookError(f"{where}: exercises of {gid!r} must be a list of str")
    rubric = meta.get("rubric", "")
    return {
        "grade_id": gid,
        "points": points,
        "exercises": list(exs),
        "manual": manual,
        "rubric": str(rubric),
    }


def cell_id(cell: dict, name: str, index: int) -> str:
    """Return the cell's id, or one derived from ``name`` and ``index``."""
    cid = cell.get("id")
    if cid:
        return str(cid)
    return hashlib.sha1(f"{name}:{index}".encode()).hexdigest()[:12]


def check_cells(nb: NotebookNode, name: str = "notebook") -> list[CheckCell]:
    """List the check cells of a lab notebook, in order.

    Raises
    ------
    NotebookError
        On malformed metadata or a grade id used twice.
    """
    out: list[CheckCell] = []
    seen: set[str] = set()
    for i, cell in enumerate(nb.cells):
        meta = check_meta(cell, f"{name}: cell {i}")
        if meta is None:
            continue
        if meta["grade_id"] in seen:
            raise NotebookError(
                f"{name}: cell {i}: grade_id {meta['grade_id']!r} used twice"
            )
        seen.add(meta["grade_id"])
        out.append(
            CheckCell(
                meta["grade_id"],
                meta["points"],
                cell_id(cell, name, i),
                i,
                tuple(meta["exercises"]),
                meta["manual"],
                meta["rubric"],
            )
        )
    return out


def setup_cell(nb: NotebookNode) -> int | None:
    """Index of the lab's set-up cell (its first code cell), or None."""
    return next((i for i, c in enumerate(nb.cells) if c.cell_type == "code"), None)


def _written_names(source: str) -> list[str]:
    """Top-level names bound by statements that hold a solution region."""
    import ast

    from .astlock import parse

    try:
        tree = parse(source)
    except SyntaxError:
        return []
    lines = source.splitlines()
    names = []
    for node in tree.body:
        span = lines[node.lineno - 1 : node.end_lineno]
        if not any(ln.strip() == SOLUTION[0] for ln in span):
            continue
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            names.append(node.name)
        elif isinstance(node, ast.Assign | ast.AnnAssign | ast.AugAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for t in targets:
                names += [n.id for n in ast.walk(t) if isinstance(n, ast.Name)]
    if not names and any(ln.strip() == SOLUTION[0] for ln in lines):
        for node in tree.body:  # a cell that is all solution: every name it binds
            if isinstance(node, ast.FunctionDef | ast.ClassDef):
                names.append(node.name)
            elif isinstance(node, ast.Assign):
                for t in node.targets:
                    names += [n.id for n in ast.walk(t) if isinstance(n, ast.Name)]
    return list(dict.fromkeys(names))


def exercises(nb: NotebookNode, name: str = "notebook") -> list[Exercise]:
    """List the exercise cells of a lab source notebook, in order.

    An exercise cell carries ``{"robotlib": {"exercise": id, "writes": [...]}}``.
    A code cell with a solution region and no such metadata is an exercise
    too, named after the first check cell that follows it (labs written
    before the convention).

    Raises
    ------
    NotebookError
        On malformed metadata or an exercise id used twice.
    """
    out: list[Exercise] = []
    seen: set[str] = set()
    checks = check_cells(nb, name)
    for i, cell in enumerate(nb.cells):
        if cell.cell_type != "code" or check_meta(cell) is not None:
            continue
        meta = cell.get("metadata", {}).get(META_KEY) or {}
        where = f"{name}: cell {i}"
        eid = meta.get("exercise")
        if eid is None:
            if not _has_marker(cell.source, SOLUTION):
                continue
            eid = next((c.grade_id for c in checks if c.index > i), None)
            if eid is None:
                continue
        if not isinstance(eid, str) or not _GRADE_ID.match(eid):
            raise NotebookError(f"{where}: bad exercise id {eid!r}")
        if eid in seen:
            raise NotebookError(f"{where}: exercise {eid!r} used twice")
        seen.add(eid)
        writes = meta.get("writes", [])
        if not isinstance(writes, list) or not all(
            isinstance(w, str) and re.fullmatch(r"[A-Za-z_][\w.]*\.\w+", w)
            for w in writes
        ):
            raise NotebookError(f"{where}: writes must be a list of dotted names")
        names = tuple(_written_names(cell.source))
        out.append(Exercise(eid, cell_id(cell, name, i), i, tuple(writes), names))
    return out


def strip_region(
    source: str, markers: tuple[str, str], stub: tuple[str, ...], where: str = "cell"
) -> str:
    """Replace every ``markers`` region of ``source`` by ``stub`` lines.

    Each stub line gets the indentation of the begin marker. With an empty
    ``stub`` the region is removed.

    Raises
    ------
    NotebookError
        On an unclosed, unopened or nested region.
    """
    begin, end = markers
    out: list[str] = []
    inside = False
    for n, line in enumerate(source.splitlines(), 1):
        stripped = line.strip()
        if stripped == begin:
            if inside:
                raise NotebookError(f"{where}, line {n}: nested {begin!r}")
            inside = True
            indent = line[: len(line) - len(line.lstrip())]
            out.extend(indent + s for s in stub)
        elif stripped == end:
            if not inside:
                raise NotebookError(f"{where}, line {n}: {end!r} without {begin!r}")
            inside = False
        elif not inside:
            out.append(line)
    if inside:
        raise NotebookError(f"{where}: {begin!r} is never closed")
    return "\n".join(out)


def _has_marker(source: str, markers: tuple[str, str]) -> bool:
    return any(line.strip() in markers for line in source.splitlines())


def _raises_at_top(cell) -> bool:
    """Whether a released code cell raises its stub outside any function."""
    return cell.cell_type == "code" and any(
        line == CODE_STUB[1] for line in cell.source.splitlines()
    )


def check_graded_exercises(nb: NotebookNode, name: str = "notebook") -> None:
    """Make sure every automatic check of a solution grades exercises it has.

    A check grades the exercises its metadata lists (``"exercises"``, by
    default its own ``grade_id``). One naming no exercise cell of the lab
    would run the solution's code in every student's place, so the lab
    would hand out its points for nothing.

    Raises
    ------
    NotebookError
        Naming the check and what it grades.
    """
    known = {e.exercise_id for e in exercises(nb, name)}
    for c in check_cells(nb, name):
        unknown = sorted(set(c.exercises or (c.grade_id,)) - known)
        if not c.manual and unknown:
            raise NotebookError(
                f"{name}: check {c.grade_id!r} grades {', '.join(unknown)}, which no "
                "exercise cell defines; list the exercises it tests in its metadata "
                "('exercises': [...])"
            )


def release_notebook(nb: NotebookNode, name: str = "notebook") -> NotebookNode:
    """Return the student version of a solution notebook.

    Solutions are replaced by stubs, hidden tests removed, outputs and
    execution counts cleared, cell metadata reduced to the check tag (check
    cells are also marked not deletable and not editable), cells that fail
    until solved (check cells, and stubs outside a function) tagged
    ``raises-exception`` so that JupyterLab's Run All goes past them to the
    demonstrations further down, cell ids kept
    (or derived from ``name`` and the position when missing), notebook
    metadata reduced to the kernelspec and the ``robotlib`` entry.

    Raises
    ------
    NotebookError
        On malformed markers or check metadata.
    """
    check_cells(nb, name)  # validates
    cells = []
    for i, cell in enumerate(nb.cells):
        where = f"{name}: cell {i}"
        meta = check_meta(cell, where)
        source = cell.source
        if meta is not None and meta["manual"]:
            source = strip_region(source, SOLUTION, ANSWER_STUB, where)
        elif meta is not None:
            if _has_marker(source, SOLUTION):
                raise NotebookError(f"{where}: a check cell cannot hold a solution")
            source = strip_region(source, HIDDEN, (), where).rstrip()
        else:
            if _has_marker(source, HIDDEN):
                raise NotebookError(f"{where}: hidden tests outside a check cell")
            stub = CODE_STUB if cell.cell_type == "code" else ANSWER_STUB
            source = strip_region(source, SOLUTION, stub, where)
        cid = cell_id(cell, name, i)
        if cell.cell_type == "code":
            new = nbformat.v4.new_code_cell(source)
        elif cell.cell_type == "markdown":
            new = nbformat.v4.new_markdown_cell(source)
            if cell.get("attachments"):
                new.attachments = cell.attachments
        else:
            new = nbformat.v4.new_raw_cell(source)
        new.id = cid
        if meta is not None and meta["manual"]:  # the rubric stays with you
            keep = {k: meta[k] for k in ("grade_id", "points", "manual")}
            new.metadata = {META_KEY: keep}
        elif meta is not None:
            keep = {k: meta[k] for k in ("grade_id", "points")}
            new.metadata = {META_KEY: keep, "deletable": False, "editable": False}
        if meta is not None and not meta["manual"]:
            new.metadata["tags"] = ["graded"]  # JupyterLab shows it: a graded check
        if (meta is not None and not meta["manual"]) or _raises_at_top(new):
            # fails until solved; JupyterLab's Run All goes on past it
            new.metadata.setdefault("tags", []).append("raises-exception")
        cells.append(new)
    out = nbformat.v4.new_notebook(cells=cells)
    out.metadata = {"kernelspec": dict(KERNELSPEC), "language_info": {"name": "python"}}
    if META_KEY in nb.metadata:
        out.metadata[META_KEY] = nb.metadata[META_KEY]
    out.nbformat, out.nbformat_minor = 4, 5
    return out
