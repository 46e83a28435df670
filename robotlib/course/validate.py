"""``robotlib validate NOTEBOOK``: what a student checks before handing in.

Compares the student's notebook with the lab as handed out (``labs/``, or
``--lab-file``) the way the grader reads it (`plan.student_cells`, cells
told apart by metadata and content): every exercise found and answered (no
``raise NotImplementedError()`` left), every written answer written, every
check cell present and unedited (the grader runs its own copy anyway, but
an edited one misleads its author). With ``--run`` the notebook is executed
top to bottom in a fresh kernel (``nbclient``) and each check cell that
raises is named. Exit status 0 when nothing is wrong, 1 otherwise.
"""

from __future__ import annotations

import argparse
import ast
import sys
from pathlib import Path

import nbformat

from .astlock import parse
from .notebooks import CODE_STUB, META_KEY, NotebookError, read_notebook
from .plan import lab_plan, normalized
from .release import project_dir

__all__ = ["add_arguments", "problems", "run"]


def _lab_file(nb: dict, given: Path | None) -> Path:
    if given is not None:
        return given
    want = ((nb.get("metadata") or {}).get(META_KEY) or {}).get("lab")
    labs = sorted((project_dir() / "labs").glob("*.ipynb"))
    for path in labs:
        meta = read_notebook(path).metadata.get(META_KEY) or {}
        if want is not None and meta.get("lab") == want:
            return path
    names = ", ".join(p.stem for p in labs) or "none found"
    raise NotebookError(
        f"cannot tell which lab this is (metadata lab {want!r}); pass --lab-file "
        f"(labs: {names})"
    )


def _defines(source: str) -> set[str]:
    try:
        tree = parse(source)
    except SyntaxError:
        return set()
    kinds = (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)
    return {n.name for n in tree.body if isinstance(n, kinds)}


def problems(student: nbformat.NotebookNode, lab: nbformat.NotebookNode) -> list[str]:
    """Return what is wrong with ``student`` against the handed-out ``lab``.

    A handed-out lab has no exercise metadata: its exercises are the cells
    holding ``raise NotImplementedError()``, found in the student's notebook
    by cell id or by the names they define.
    """
    plan = lab_plan(lab, "lab")
    out = []
    code = [c for c in student.cells if c.cell_type == "code"]
    for stub in (c for c in lab.cells if c.cell_type == "code"):
        if CODE_STUB[1] not in stub.source:
            continue
        names = _defines(stub.source)
        label = ", ".join(sorted(names)) or stub.get("id", "?")
        mine = [
            c
            for c in code
            if c.get("id") == stub.get("id") or names & _defines(c.source)
        ]
        if not mine:
            out.append(f"exercise {label}: its cell is missing")
        elif all(CODE_STUB[1] in c.source for c in mine):
            out.append(f"exercise {label}: not answered (NotImplementedError)")
    texts = [normalized(c.source) for c in student.cells if c.cell_type == "markdown"]
    for c in plan.manual:
        prompt = plan.prompts.get(c.grade_id, "")
        mine = [t for t in texts if prompt and prompt in t]
        if not mine:
            out.append(f"written answer {c.grade_id!r}: its cell is missing")
        elif any("YOUR ANSWER HERE" in t for t in mine):
            out.append(f"written answer {c.grade_id!r}: not written yet")
    code = {normalized(c.source) for c in student.cells if c.cell_type == "code"}
    for c in plan.checks:
        if normalized(lab.cells[c.index].source) not in code:
            out.append(f"check {c.grade_id!r}: missing or edited (the grader runs "
                       "its own copy; yours may mislead you)")  # fmt: skip
    return out


def _execute(nb: nbformat.NotebookNode, path: Path, timeout: float) -> list[str]:
    from nbclient import NotebookClient
    from nbclient.exceptions import CellExecutionError

    client = NotebookClient(
        nb,
        timeout=timeout,
        allow_errors=True,
        resources={"metadata": {"path": str(path.parent)}},
    )
    try:
        client.execute()
    except CellExecutionError as exc:  # pragma: no cover - allow_errors catches these
        return [str(exc)[:300]]
    out = []
    for cell in nb.cells:
        meta = cell.get("metadata", {}).get(META_KEY) or {}
        errors = [o for o in cell.get("outputs", []) if o.get("output_type") == "error"]
        if errors and "grade_id" in meta and not meta.get("manual"):
            e = errors[0]
            out.append(
                f"check {meta['grade_id']!r} fails: {e['ename']}: {e['evalue']}"[:300]
            )
    return out


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``validate`` options to ``parser``."""
    parser.add_argument("notebook", type=Path, help="your lab notebook")
    parser.add_argument(
        "--lab-file", type=Path, help="the lab as handed out (default: from labs/)"
    )
    parser.add_argument(
        "--run", action="store_true", help="also run it top to bottom in a new kernel"
    )
    parser.add_argument(
        "--timeout",
        type=float,
        default=600.0,
        help="s per cell with --run (default: %(default)s)",
    )


def run(args: argparse.Namespace) -> int:
    """Run ``robotlib validate``; return the exit status."""
    try:
        nb = read_notebook(args.notebook)
        lab = read_notebook(_lab_file(nb, args.lab_file))
        found = problems(nb, lab)
        if args.run:
            found += _execute(nb, args.notebook, args.timeout)
    except (NotebookError, OSError, ValueError) as exc:
        sys.stderr.write(f"robotlib validate: {exc}\n")
        return 2
    for p in found:
        sys.stdout.write(f"- {p}\n")
    if not found:
        sys.stdout.write(f"{args.notebook}: ready to hand in\n")
    return 1 if found else 0
