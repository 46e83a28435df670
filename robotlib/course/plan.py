"""What each grading process runs, built from the lab's source and a submission.

- `lab_plan` (once per lab, from ``solutions/``): the set-up cell, the
  exercises and the names they define, the checks (hidden tests in, a
  marker before them so their lines are reported as hidden), and the
  instructor's definitions the checks need: each check's free names are
  followed back through the solution's top-level statements (functions,
  classes, imports, assignments) until only the set-up cell's names and the
  exercises' names are left. A check never sees a name the student's
  notebook defines, except the exercises' own, through proxies; and only
  those of the exercises it grades (its ``exercises``): for the others it
  gets the solution's versions (``LabPlan.answers``), so one mistake costs
  the checks of its own exercise, not every later check that uses it.
- `student_cells` (per submission): the student's code for each exercise
  (their cell matched by exercise id, cell id, or the names it defines) and
  the cells they added, in order; check cells and the lab's other cells
  (matched by content, whatever their ids) are left out.
- `scan_submission`: the static answers-not-shipped pass over those cells.

Imports `notebooks` and `answers` only.
"""

from __future__ import annotations

import ast
import builtins
import difflib
import symtable
from dataclasses import dataclass, field

from nbformat import NotebookNode

from . import answers, scan
from .astlock import parse
from .notebooks import (
    ANSWER_STUB,
    HIDDEN,
    META_KEY,
    SOLUTION,
    CheckCell,
    Exercise,
    check_cells,
    check_meta,
    exercises,
    setup_cell,
)
from .worker import HIDDEN_MARK

__all__ = [
    "LabPlan",
    "lab_plan",
    "normalized",
    "release_notes",
    "student_cells",
    "scan_submission",
]


@dataclass
class LabPlan:
    """Everything about a lab the grader needs, computed once."""

    name: str
    setup: str
    checks: list[CheckCell]
    manual: list[CheckCell]
    exercises: list[Exercise]
    check_specs: list[dict]
    defs: list[str]
    names: dict[str, dict]  # exercise name -> {"exercise", "kind"}
    writes: list[str]
    aliases: dict[str, str] = field(default_factory=dict)
    solution_ids: set[str] = field(default_factory=set)
    lab_sources: set[str] = field(default_factory=set)  # `normalized` lab cells
    prompts: dict[str, str] = field(default_factory=dict)  # written answer -> question
    answers: list[str] = field(default_factory=list)  # the solution's exercise cells
    same: dict[str, list[str]] = field(default_factory=dict)  # listed -> equals
    released: dict[str, str] = field(default_factory=dict)  # check -> `normalized`

    def lists(self, exercise: str, function: str) -> bool:
        """Return whether ``exercise`` lists ``function`` (under any of its names).

        Each exercise lists the library functions its answer may not use,
        another exercise's among them where that would do its work (Lab 4's
        ``astar`` lists ``wavefront``); what it does not list it may use.
        """
        ex = next((e for e in self.exercises if e.exercise_id == exercise), None)
        same = self.same.get(function, [function])
        return ex is not None and any(w in same for w in ex.writes)

    def listed_as(self, function: str, exercise: str | None) -> str:
        """Return the name ``exercise``'s ``writes`` gives ``function``'s object.

        A note names the function as the exercise lists it, even when another
        exercise lists the same object under another name.
        """
        ex = next((e for e in self.exercises if e.exercise_id == exercise), None)
        if ex is None:
            return function
        same = self.same.get(function, [function])
        return next((w for w in ex.writes if w in same), function)

    @property
    def max_points(self) -> float:
        """Points of the automatic checks and the written answers."""
        return float(sum(c.points for c in self.checks + self.manual))


def _free_names(source: str) -> set[str]:
    """Global names a snippet reads and does not bind itself."""
    try:
        top = symtable.symtable(source, "<cell>", "exec")
    except SyntaxError:
        return set()
    out: set[str] = set()

    def walk(t, module: bool) -> None:
        for s in t.get_symbols():
            if module:
                if s.is_referenced() and not (s.is_assigned() or s.is_imported()):
                    out.add(s.get_name())
            elif s.is_global() and s.is_referenced():
                out.add(s.get_name())
        for child in t.get_children():
            walk(child, False)

    walk(top, True)
    return out - set(dir(builtins))


def _bound(node: ast.stmt) -> set[str]:
    if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
        return {node.name}
    if isinstance(node, ast.Import | ast.ImportFrom):
        return {(a.asname or a.name).split(".")[0] for a in node.names}
    if isinstance(node, ast.Assign | ast.AnnAssign | ast.AugAssign):
        targets = node.targets if isinstance(node, ast.Assign) else [node.target]
        return {n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name)}
    return set()


def _with_marker(source: str) -> str:
    lines = []
    for line in source.splitlines():
        if line.strip() == HIDDEN[0]:
            indent = line[: len(line) - len(line.lstrip())]
            lines.append(f"{indent}print({HIDDEN_MARK!r})")
        elif line.strip() != HIDDEN[1]:
            lines.append(line)
    return "\n".join(lines)


def lab_plan(solution: NotebookNode, name: str) -> LabPlan:
    """Compute what grading ``solution``'s lab runs.

    Raises
    ------
    NotebookError
        On malformed metadata.
    ImportError
        If an exercise lists a library function that does not exist.
    """
    items = check_cells(solution, name)
    checks = [c for c in items if not c.manual]
    manual = [c for c in items if c.manual]
    exs = exercises(solution, name)
    i0 = setup_cell(solution)
    setup = solution.cells[i0].source if i0 is not None else ""
    ex_cells = {e.index: e for e in exs}
    names: dict[str, dict] = {}
    for e in exs:
        try:
            tree = parse(solution.cells[e.index].source)
        except SyntaxError:
            continue
        for node in tree.body:
            for n in _bound(node) & set(e.names):
                kind = (
                    "function"
                    if isinstance(node, ast.FunctionDef | ast.ClassDef)
                    else "value"
                )
                names[n] = {"exercise": e.exercise_id, "kind": kind}
    # the instructor's top-level statements, latest binding of each name first
    stmts: list[tuple[int, ast.stmt, str]] = []
    for i, cell in enumerate(solution.cells):
        if cell.cell_type != "code" or i == i0 or check_meta(cell) is not None:
            continue
        try:
            tree = parse(cell.source)
        except SyntaxError:
            continue
        lines = cell.source.splitlines()
        for node in tree.body:
            bound = _bound(node)
            if i in ex_cells and bound & set(names):
                continue  # the student's part of an exercise cell
            if bound:
                src = "\n".join(lines[node.lineno - 1 : node.end_lineno])
                stmts.append((i, node, src))
    setup_names = _bound_all(setup)
    check_specs, needed = [], []
    for c in checks:
        src = solution.cells[c.index].source
        free = _free_names(src)
        values = sorted(n for n in free if names.get(n, {}).get("kind") == "value")
        check_specs.append(
            {
                "gid": c.grade_id,
                "source": _with_marker(src),
                "values": values,
                "exercises": list(c.exercises) or [c.grade_id],
            }
        )
        todo = list(free)
        while todo:
            n = todo.pop()
            if n in names or n in setup_names:
                continue
            hit = next(
                (s for s in reversed(stmts) if s[0] < c.index and n in _bound(s[1])),
                None,
            )
            if hit is None or hit in needed:
                continue
            needed.append(hit)
            todo += list(_free_names(hit[2]))
    needed.sort(key=lambda s: (s[0], s[1].lineno))
    writes = list(dict.fromkeys(w for e in exs for w in e.writes))  # listed order
    plan = LabPlan(
        name,
        setup,
        checks,
        manual,
        exs,
        check_specs,
        [s[2] for s in needed],
        names,
        writes,
    )
    plan.aliases = answers.aliases(writes) if writes else {}
    plan.same = answers.equivalents(writes) if writes else {}
    plan.solution_ids = {c.get("id") for c in solution.cells}
    plan.lab_sources = _lab_sources(solution, exs)
    plan.answers = [solution.cells[e.index].source for e in exs]
    for c in checks:  # as students have them: without the hidden tests
        plan.released[c.grade_id] = normalized(
            _without_hidden(solution.cells[c.index].source)
        )
    for c in manual:  # the question, above the solution region
        source = solution.cells[c.index].source  # a released lab: the stub
        question = source.split(SOLUTION[0])[0].split(ANSWER_STUB[0])[0]
        plan.prompts[c.grade_id] = normalized(question)
    return plan


def release_notes(plan: LabPlan, nb: dict) -> list[str]:
    """Say whether ``nb`` was made from another release of the lab than ``plan``'s.

    Students cannot edit check cells: a check cell (by its grade id) that
    differs from the current release's, or a check one of them lacks, means
    the notebook came from an older release (or was edited outside Jupyter),
    and a renamed function can cost points. Without any check metadata (an
    old nbformat, pasted cells) the checks are looked for by content.
    Returns one note, or none.
    """
    cells = [c for c in nb.get("cells", []) if isinstance(c, dict)]
    code = [c for c in cells if c.get("cell_type") == "code"]
    theirs: dict[str, str] = {}
    for cell in code:
        meta = (cell.get("metadata") or {}).get(META_KEY) or {}
        gid = meta.get("grade_id") if isinstance(meta, dict) else None
        if isinstance(gid, str) and gid not in theirs:
            theirs[gid] = normalized(_without_hidden(_source(cell)))
    if theirs:
        ids = list(dict.fromkeys([*plan.released, *theirs]))
        differ = [g for g in ids if theirs.get(g) != plan.released.get(g)]
    else:
        present = {normalized(_without_hidden(_source(c))) for c in code}
        differ = [g for g, src in plan.released.items() if src not in present]
    if not differ:
        return []
    return [
        f"made from an older release of {plan.name}? its check cells "
        f"{', '.join(differ)} differ from the current release's (the current "
        "checks were run; a renamed function may have cost points)"
    ]


def _bound_all(source: str) -> set[str]:
    try:
        tree = parse(source)
    except SyntaxError:
        return set()
    return set().union(*(_bound(n) for n in tree.body)) if tree.body else set()


def _source(cell: dict) -> str:
    src = cell.get("source", "")
    return "".join(src) if isinstance(src, list) else str(src)


def normalized(source: str) -> str:
    """Return a cell's source as compared by content: no trailing or blank lines."""
    return "\n".join(ln.rstrip() for ln in source.splitlines() if ln.strip())


def _lab_sources(solution: NotebookNode, exs: list[Exercise]) -> set[str]:
    """Return the lab's own code cells' sources, as released and as solved.

    Exercise cells are left out; check cells are there without their hidden
    tests (as students have them).
    """
    own = {e.index for e in exs}
    out = set()
    for i, cell in enumerate(solution.cells):
        if cell.cell_type == "code" and i not in own:
            out.add(normalized(cell.source))
            out.add(normalized(_without_hidden(cell.source)))
    out.discard("")
    return out


def _without_hidden(source: str) -> str:
    lines, hidden = [], False
    for line in source.splitlines():
        if line.strip() in HIDDEN:
            hidden = line.strip() == HIDDEN[0]
        elif not hidden:
            lines.append(line)
    return "\n".join(lines)


def _is_lab_cell(plan: LabPlan, source: str) -> bool:
    """Return whether ``source`` is one of the lab's own cells (or a near copy).

    A near copy (90 % of its characters in common with a lab cell of three
    lines or more) is a demonstration the student touched (a parameter
    changed): like an edited lab cell that kept its id, it is not run. An
    empty cell is nobody's.
    """
    src = normalized(source)
    if not src or src in plan.lab_sources:
        return True
    for lab in plan.lab_sources:
        if lab.count("\n") < 2:
            continue
        m = difflib.SequenceMatcher(None, src, lab, autojunk=False)
        if m.real_quick_ratio() >= 0.9 and m.quick_ratio() >= 0.9 and m.ratio() >= 0.9:
            return True
    return False


def student_cells(plan: LabPlan, student: dict) -> list[dict]:
    """Return the student's cells the student process runs, in notebook order.

    Each is ``{"id", "exercise", "source"}``; ``exercise`` is None for a
    cell the student added. Cells are told apart by metadata and content
    first, ids last (an old nbformat has none, pasting a cell into another
    notebook or duplicating one gives it a new one):

    - a cell tagged with a ``grade_id`` is a check (run by the check process);
    - a cell tagged with an ``exercise`` is that exercise's;
    - a cell whose source is one of the lab's own cells (set-up,
      demonstrations, checks as released) is the lab's, whatever its id or
      metadata, and does not run;
    - a cell with an exercise cell's id is that exercise's;
    - a cell that defines an exercise's name (``def steer``) is that
      exercise's, if no cell above claimed it;
    - another cell with one of the lab's ids is the lab's, edited;
    - anything else was added by the student.
    """
    by_cell = {e.cell_id: e for e in plan.exercises}
    by_id = {e.exercise_id: e for e in plan.exercises}
    kinds: list[tuple[str, dict, object]] = []  # (kind, cell, exercise)
    for n, cell in enumerate(student.get("cells", [])):
        if not isinstance(cell, dict) or cell.get("cell_type") != "code":
            continue
        meta = cell.get("metadata", {})
        meta = meta.get(META_KEY) if isinstance(meta, dict) else None
        meta = meta if isinstance(meta, dict) else {}
        src = _source(cell)
        cell = {**cell, "id": str(cell.get("id") or f"cell{n}")[:64]}
        if "grade_id" in meta:
            continue  # a check cell (canonical ones run in the check process)
        ex = by_id.get(meta.get("exercise"))
        if ex is None and _is_lab_cell(plan, src):
            continue
        ex = ex or by_cell.get(cell["id"])
        if ex is not None:
            kinds.append(("exercise", cell, ex))
        else:
            defines = _bound_all(src) & set(plan.names)
            kinds.append(("maybe", cell, {plan.names[d]["exercise"] for d in defines}))
    claimed = {ex.exercise_id for kind, _, ex in kinds if kind == "exercise"}
    out, done = [], set()
    for kind, cell, ex in kinds:
        if kind == "maybe":
            free = sorted(e for e in ex if e not in claimed)
            if len(free) == 1:
                claimed.add(free[0])
                kind, ex = "exercise", by_id[free[0]]
        if kind == "exercise":
            if ex.exercise_id in done:
                continue
            done.add(ex.exercise_id)
            ex = ex.exercise_id
        elif cell["id"] in plan.solution_ids:
            continue  # the lab's cell, edited
        else:
            ex = None
        out.append({"id": cell["id"], "exercise": ex, "source": _source(cell)})
    return out


def scan_submission(plan: LabPlan, cells: list[dict]) -> tuple[dict, list[str]]:
    """Run the static pass; return ``({exercise: [notes]}, flags)``.

    A route in an exercise's cell to a function that exercise lists zeroes
    it (and is flagged). Elsewhere (cells the student added, helper modules,
    another exercise's function) a listed function named is nothing: if it
    is called, at the top of a cell or while a check runs the student's
    functions, its tripwire refuses (the student sees why) and reports the
    exercise running, if any (`grade.grade_notebook`). So an honest cell
    comparing with the library or re-running a demonstration costs no
    points, and Lab 4's ``steer`` cell reaching the library's A* (which
    ``steer`` does not list) is refused, not accused. Machinery is flagged
    everywhere and zeroes the exercise whose cell holds it.
    """
    zero: dict[str, list[str]] = {}
    flags: list[str] = []
    for cell in cells:
        for f in scan.scan_code(cell["source"], plan.aliases):
            ex = cell["exercise"]
            if f.listed:
                if ex is None or not plan.lists(ex, f.function):
                    continue
                name = plan.listed_as(f.function, ex)
                how = f.how + (f", through {f.via}" if f.via and f.via != name else "")
                note = f"reaches {name} ({how}), the exercise's own work"
            else:
                note = f"uses {f.function} ({f.how})"
                if f.function == "solutions/":
                    note = "reads notebooks or solutions/"
            if ex is not None:
                zero.setdefault(ex, [])
                if note not in zero[ex]:
                    zero[ex].append(note)
            if note not in flags:
                flags.append(note)
    return zero, flags
