"""Honest notebooks that lost their cell ids are never taken for cheats.

An older tool writes nbformat 4.4 (no cell ids); pasting cells into a new
notebook gives them new ids and drops their metadata; duplicating a
demonstration cell gives the copy a new id. The lab's own cells (which may
call the very library functions an exercise lists) are then recognised by
their content, the exercise cells by the names they define, the written
answers by their question: such a notebook scores what the solution does.
"""

from __future__ import annotations

import copy
import json
import subprocess
import sys
import uuid
import warnings
from pathlib import Path

import nbformat
import pytest

from robotlib.course import grade as g
from robotlib.course.notebooks import read_notebook, write_notebook
from robotlib.course.plan import lab_plan, scan_submission, student_cells
from tests.course.test_course_grade import FULL, MEAN, solution
from tests.sandboxing import need_sandbox

ROOT = Path(__file__).resolve().parents[2]
DEMO = "print('the library says', np.mean([1.0, 2.0, 4.0]))  # numpy.mean is listed"


def _old_format(nb) -> nbformat.NotebookNode:
    """The notebook as nbformat 4.4 writes it: no cell ids."""
    raw = json.loads(nbformat.writes(nb))
    raw["nbformat_minor"] = 4
    for cell in raw["cells"]:
        cell.pop("id", None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return nbformat.reads(json.dumps(raw), as_version=4)


def _pasted(nb) -> nbformat.NotebookNode:
    """Every cell pasted into a new notebook: new ids, no metadata."""
    nb = copy.deepcopy(nb)
    for i, cell in enumerate(nb.cells):
        cell.id = uuid.UUID(int=i + 1).hex[-8:]
        cell.metadata = {}
    return nb


def _duplicated_demo(nb, demo_source: str) -> nbformat.NotebookNode:
    nb = copy.deepcopy(nb)
    i = next(i for i, c in enumerate(nb.cells) if c.source == demo_source)
    twin = copy.deepcopy(nb.cells[i])
    twin.id = "twin-of-demo"
    nb.cells.insert(i + 1, twin)
    return nb


@pytest.mark.slow
@pytest.mark.parametrize(
    "lab",
    ["lab2_avoidance", "lab3_mcl", "lab4_navigation", "lab5_slam", "lab7_exploration"],
)
def test_real_labs_without_ids_reach_nothing(lab):
    """The case of the report: Lab 4's demonstrations zeroed honest students."""
    sol = read_notebook(ROOT / "solutions" / f"{lab}.ipynb")
    plan = lab_plan(sol, lab)
    want = [c["exercise"] for c in student_cells(plan, sol)]
    demo = next(
        c.source
        for c in sol.cells
        if c.cell_type == "code" and c.metadata.get("robotlib") is None and c.source
    )
    for nb in (_old_format(sol), _pasted(sol), _duplicated_demo(sol, demo)):
        cells = student_cells(plan, nb)
        assert [c["exercise"] for c in cells] == want
        assert scan_submission(plan, cells) == ({}, [])


def _tiny_with_demo(folder: Path) -> Path:
    """The tiny lab with a demonstration cell calling ``numpy.mean`` (listed)."""
    nb = solution()
    at = next(i for i, c in enumerate(nb.cells) if c.id == MEAN) + 2
    demo = nbformat.v4.new_code_cell(DEMO)
    demo.id = "tiny-demo"
    nb.cells.insert(at, demo)
    path = folder / "tiny.ipynb"
    write_notebook(nb, path)
    return path


@pytest.mark.slow
def test_honest_notebooks_that_lost_ids_get_full_marks(tmp_path):
    need_sandbox()
    lab = _tiny_with_demo(tmp_path)
    sol = read_notebook(lab)
    subs = tmp_path / "subs"
    cheat = copy.deepcopy(sol)  # the answer reaches numpy.mean: still zeroed
    next(
        c for c in cheat.cells if c.id == MEAN
    ).source = "def mean(xs):\n    return float(np.mean(xs))"
    cases = {
        "old_format": _old_format(sol),
        "pasted": _pasted(sol),
        "duplicated_demo": _duplicated_demo(sol, DEMO),
        "cheat_pasted": _pasted(cheat),
    }
    for name, nb in cases.items():
        (subs / name).mkdir(parents=True)
        (subs / name / "tiny.ipynb").write_text(nbformat.writes(nb))
    opts = g.Options(cell_timeout=20, timeout=120)
    results, _ = g.grade(subs, "tiny", lab, jobs=2, opts=opts, progress=False)
    rows = {r.student: r for r in results}
    for name in ("old_format", "pasted", "duplicated_demo"):
        r = rows[name]
        assert {k: r.points[k] for k in FULL} == {k: float(v) for k, v in FULL.items()}
        assert r.flags == [], (name, r.flags)
        assert "Vectorised" in r.answers.get("why", ""), (name, r.answers)
    r = rows["cheat_pasted"]
    assert r.points["mean"] == 0 and r.points["add"] == 1, r.reasons
    assert "numpy.mean" in r.reasons["mean"]


def test_listed_functions_are_known_by_identity_not_a_recycled_id():
    """A listed function replaced by a tripwire may be freed; its id then reused.

    The grader named a call of ``astar`` as ``pure_pursuit`` when a later
    object took a freed function's id: the listed objects are held, and
    compared by identity.
    """
    import gc

    from robotlib.course.answers import _Targets

    targets = _Targets()

    def listed():
        return 0

    targets.add(listed, "m.listed")
    assert targets.get(listed) == "m.listed"
    del listed
    gc.collect()
    made = [(lambda i=i: i) for i in range(2000)]
    assert [m for m in made if targets.get(m) is not None] == []


def test_a_listed_table_trips_when_read():
    """Lab 2 lists the ``BRAITENBERG`` table (a value, not a function): the
    vehicle read through the library's class is reported, not a library error."""
    listed = "robotlib.avoidance.reactive.BRAITENBERG"
    code = (
        "from robotlib.avoidance import Braitenberg\n"
        "import robotlib.avoidance.reactive as r\n"
        "from robotlib.course import tripwires\n"
        "hits = []\n"
        f"tripwires.arm([{listed!r}], lambda f, via: hits.append((f, via)))\n"
        "for read in (lambda: Braitenberg('fear').weights,\n"
        "             lambda: r.BRAITENBERG.keys(), lambda: list(r.BRAITENBERG)):\n"
        "    try:\n        read()\n    except tripwires.Tripwire:\n        pass\n"
        "repr(r.BRAITENBERG), hasattr(r.BRAITENBERG, '__len_hint__')  # not reads\n"
        "print(hits)\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 0, proc.stderr
    hits = eval(proc.stdout.strip().splitlines()[-1])  # noqa: S307 - our own output
    assert hits == [(listed, listed)] * 3
