"""Finding each student's notebook in the layouts students really hand in."""

from __future__ import annotations

import copy
import os

import pytest

from robotlib.course import grade as g
from robotlib.course.notebooks import (
    NotebookError,
    check_graded_exercises,
    release_notebook,
    write_notebook,
)
from robotlib.course.plan import lab_plan, release_notes
from robotlib.course.release import release
from robotlib.course.submissions import copies, find_submissions, helpers
from tests.course.test_course_grade import (
    ADD,
    ADD_CHECK,
    FULL,
    MEAN,
    TINY,
    by_id,
    solution,
    with_cell,
)
from tests.references import shared
from tests.sandboxing import need_sandbox


def _nb(path, mtime=None):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("{}")
    if mtime is not None:
        os.utime(path, (mtime, mtime))
    return path


def test_the_newest_copy_untitled_sections_outputs_links_and_names(tmp_path):
    subs = tmp_path / "subs"
    old = _nb(subs / "ann" / "tiny.ipynb", mtime=1_000_000)
    new = _nb(subs / "ann" / "tiny (1).ipynb", mtime=2_000_000)
    _nb(subs / "bob" / "Untitled.ipynb")
    bob = _nb(subs / "bob" / "tiny-Copy1.ipynb")
    _nb(subs / "section2" / "cy" / "tiny.ipynb")
    _nb(subs / "section2" / "dee" / "work" / "tiny.ipynb")
    out = subs / "gb.csv"
    out.write_text("student\n")
    _nb(subs / "gb-records" / "x.ipynb")  # the grader's outputs inside the folder
    (subs / "x.ipynb").symlink_to(old)
    latin = os.fsdecode(b"Jos\xe9")
    _nb(subs / latin / "tiny.ipynb")
    listed = find_submissions(subs, "tiny", (out, subs / "gb-records"))
    found = {s: (p, st) for s, p, st in listed}
    assert found["ann"] == (new, "")
    assert copies(new, "tiny") == [old]
    assert found["bob"] == (bob, "")
    assert found["section2/cy"][0].parent.name == "cy"
    assert found["section2/dee"][0].parent.name == "work"
    assert found["x"] == (None, "a symbolic link, not graded")
    assert found["José"][0] is not None
    assert "gb-records" not in found and "gb" not in found
    assert set(found) == {"ann", "bob", "section2/cy", "section2/dee", "x", "José"}


def test_helper_modules_beside_the_notebook(tmp_path):
    """A student's own ``*.py`` files go with their notebook; nobody's do not."""
    subs = tmp_path / "subs"
    nb = _nb(subs / "ann" / "tiny.ipynb")
    (subs / "ann" / "helpers.py").write_text("def average(xs): ...\n")
    (subs / "ann" / "numpy.py").write_text("")  # would hide numpy
    (subs / "ann" / "my-notes.py").write_text("")  # not importable
    (subs / "ann" / "link.py").symlink_to(subs / "ann" / "helpers.py")
    flat = _nb(subs / "bob.ipynb")
    (subs / "shared.py").write_text("")  # beside every flat notebook: nobody's
    modules, notes = helpers(nb, subs)
    assert modules == {"helpers.py": "def average(xs): ...\n"}
    assert sorted(n.split(":")[0] for n in notes) == [
        "link.py",
        "my-notes.py",
        "numpy.py",
    ]
    assert helpers(flat, subs) == ({}, [])


@pytest.mark.slow
def test_a_helper_module_is_graded_with_its_notebook(tmp_path):
    """``from helpers import average`` works in the sandbox (6 -> 4 before),
    and a helper reaching the library's own version is zeroed like a cell."""
    need_sandbox()
    uses = with_cell(solution(), MEAN, "from helpers import average as mean\n")
    subs = tmp_path / "subs"
    for name, helper in (
        ("honest", "def average(xs):\n    return sum(xs) / len(xs)\n"),
        ("cheat", "import numpy\naverage = numpy.mean\n"),
    ):
        (subs / name).mkdir(parents=True)
        write_notebook(uses, subs / name / "tiny.ipynb")
        (subs / name / "helpers.py").write_text(helper)
    opts = g.Options(cell_timeout=20, timeout=120)
    records = tmp_path / "records"
    with shared("tiny", TINY, records):
        results, _ = g.grade(subs, "tiny", TINY, jobs=2, opts=opts, progress=False,
                             records=records)  # fmt: skip
    rows = {r.student: r for r in results}
    assert rows["honest"].points == {k: float(v) for k, v in FULL.items()}
    assert rows["honest"].flags == [], rows["honest"].flags
    assert rows["cheat"].points["mean"] == 0
    assert any("numpy.mean" in f for f in rows["cheat"].flags), rows["cheat"].flags


def test_a_notebook_from_an_older_release_is_noted():
    """An older release renamed ``add`` (``plus``): its check cell differs."""
    sol = solution()
    plan = lab_plan(sol, "tiny")
    older = with_cell(sol, ADD, "def plus(a, b):\n    return a + b\n")
    older = with_cell(older, ADD_CHECK, 'print("CHECK add", plus(2, 3))\n')
    for nb in (release_notebook(older, "tiny"), _bare(release_notebook(older, "tiny"))):
        notes = release_notes(plan, nb)
        assert len(notes) == 1 and "older release" in notes[0], notes
        assert "cells add differ" in notes[0]
    released = release_notebook(sol, "tiny")
    for nb in (sol, _bare(sol), released, _bare(released)):
        assert release_notes(plan, nb) == []  # the solution, as released, no ids


def test_a_check_of_no_exercise_is_refused(tmp_path):
    """A check naming no exercise of the lab would grade the solution's code."""
    sol = solution()
    check_graded_exercises(sol, "tiny")  # the tiny lab as it is passes
    for meta in (
        {"grade_id": "sum", "points": 1},
        {"grade_id": "add", "exercises": ["plus"]},
    ):
        bad = copy.deepcopy(sol)
        by_id(bad, ADD_CHECK).metadata["robotlib"] = meta  # "sum": no exercise named so
        with pytest.raises(NotebookError, match="no exercise cell defines"):
            check_graded_exercises(bad, "tiny")
    write_notebook(bad, tmp_path / "solutions" / "tiny.ipynb")
    with pytest.raises(NotebookError, match="'add' grades plus"):
        release(tmp_path / "solutions", tmp_path / "labs")  # `robotlib release` too


def _bare(nb):
    """The notebook as an old nbformat leaves it: no cell metadata or ids."""
    nb = copy.deepcopy(nb)
    for cell in nb.cells:
        cell.metadata = {}
        cell.pop("id", None)
    return nb
