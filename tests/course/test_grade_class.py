"""The instructor's everyday runs: one student again, a late student, a wrong lab.

``--student`` grades one student again with the options given and the
gradebook keeps everyone else; a folder holding only a late student merges
into the class's gradebook; the reference run is saved with its caches and
not repeated; an interrupted re-grade is finished by the next run; a wrong
``--lab``, an empty folder or an unknown student is a clear error. The runs
are made beside the other tests (`tests.background`); this module's tests
run last.
"""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import nbformat
import pytest

from robotlib.course import grade as g
from robotlib.course.cache import reference_key
from robotlib.course.gradebook import Again, Records
from robotlib.course.notebooks import read_notebook, release_notebook, write_notebook
from robotlib.course.submissions import check_lab, pick
from tests import background
from tests.course.test_course_grade import MEAN, TINY, with_cell
from tests.sandboxing import need_sandbox


def _cli(subs, out, *extra):
    cmd = [sys.executable, "-m", "robotlib.cli", "grade", str(subs), "--lab", "tiny",
           "--solution", str(TINY), "--out", str(out), "--cell-timeout", "20",
           "--jobs", "2", "--quiet", *extra]  # fmt: skip
    return background.run(cmd, 600)  # quiet s: tests.contention


def _rows(out):
    with open(out, newline="", encoding="utf-8") as f:
        return {r["student"]: r for r in csv.DictReader(f)}


def background_work(folder: Path) -> dict:
    """The instructor's runs, one after another, beside the other tests.

    (`tests.background`; only if their test is selected.) Returns each run's
    process, and the gradebook and the saved reference run's time after it.
    """
    names = {item.originalname for item in background.selected(__name__)}
    if "test_one_student_again_and_a_late_one_merge_into_the_class" not in names:
        return {}
    need_sandbox()
    sol = read_notebook(TINY)
    subs, late = folder / "subs", folder / "late"
    nap = "import time\ndef mean(xs):\n    time.sleep(3)\n    return sum(xs) / len(xs)"
    slow = with_cell(sol, MEAN, nap)
    released = release_notebook(sol, "tiny")
    for name, nb in (("ann", sol), ("bob", released), ("cy", slow)):
        (subs / name).mkdir(parents=True)
        write_notebook(nb, subs / name / "tiny.ipynb")
    (late / "dee").mkdir(parents=True)
    write_notebook(sol, late / "dee" / "tiny.ipynb")
    (folder / "empty").mkdir()
    out = folder / "gb.csv"
    saved = out.with_name("gb-records") / ".reference" / "reference.json"
    runs = {}
    for step, args in (
        ("first", (subs, out, "--cell-timeout", "2")),
        ("cy again", (subs, out, "--student", "cy")),  # a longer cell limit
        ("late", (late, out)),  # a late student in a folder of their own
        ("unknown", (subs, out, "--student", "cyy")),
        ("empty", (folder / "empty", folder / "e.csv")),
    ):
        proc = _cli(*args)
        rows = _rows(out) if out.exists() else {}
        runs[step] = proc, rows, saved.stat().st_mtime_ns if saved.exists() else None
    return runs


@pytest.mark.slow
def test_one_student_again_and_a_late_one_merge_into_the_class():
    runs = background.result(__name__)
    proc, first, stamp = runs["first"]
    assert proc.returncode == 0, proc.stderr
    assert first["cy"]["mean"] == "0" and first["ann"]["total"] == "4"
    assert stamp is not None  # the reference run was saved

    # cy again with a longer cell limit: only cy is graded, everyone is kept
    proc, again, stamp_again = runs["cy again"]
    assert proc.returncode == 0, proc.stderr
    assert "graded 1 submissions" in proc.stderr, proc.stderr
    assert again["cy"]["mean"] == "2", again["cy"]["notes"]
    assert again["ann"] == first["ann"] and again["bob"] == first["bob"]
    assert stamp_again == stamp  # the reference run was not repeated

    # a late student in a folder of their own, same --out: a row added
    proc, rows, _ = runs["late"]
    assert proc.returncode == 0, proc.stderr
    assert set(rows) == {"ann", "bob", "cy", "dee"}

    bad = runs["unknown"][0]
    assert bad.returncode == 2 and "'cyy' (close: cy)" in bad.stderr
    empty = runs["empty"][0]
    assert empty.returncode == 2 and "no submissions" in empty.stderr


def test_an_interrupted_regrade_is_finished_by_the_next_run(tmp_path):
    store = Records(tmp_path / "records", "tiny")
    again = Again(store, ["ann", "bob", "cy"])
    again.done("ann")  # interrupted here
    later = Again(store, None)
    assert "bob" in later and "cy" in later and "ann" not in later
    assert later.resumed
    later.done("bob")
    later.done("cy")
    assert not (tmp_path / "records" / ".again.json").exists()
    assert "bob" not in Again(store, None)
    assert Records(tmp_path / "records", "tiny").all() == []  # its list is no record


def test_wrong_lab_unknown_student_and_missing_lab_say_what_to_do(tmp_path):
    sol = nbformat.v4.new_notebook(metadata={"robotlib": {"lab": "lab4"}})
    paths = []
    for i in range(3):
        nb = nbformat.v4.new_notebook(metadata={"robotlib": {"lab": "lab2"}})
        paths.append(tmp_path / f"s{i}.ipynb")
        paths[-1].write_text(nbformat.writes(nb))
    with pytest.raises(ValueError, match="3 of 3 notebooks are lab 'lab2'"):
        check_lab(sol, "lab4_navigation", paths)
    check_lab(sol, "lab4_navigation", paths[:0])  # nothing to go by: grade
    subs = [("Ada", None, ""), ("Bob", None, "")]
    assert pick(subs, ["Bob"]) == [("Bob", None, "")]
    with pytest.raises(ValueError, match="'ada' \\(close: Ada\\)"):
        pick(subs, ["ada"])
    with pytest.raises(g.GradeError, match="labs: .*lab4_navigation"):
        g.solution_path("lab4")
    assert json.loads(paths[0].read_text())["metadata"]["robotlib"]["lab"] == "lab2"


def test_the_reference_run_is_kept_by_the_solution_s_content():
    """A saved reference run is reused while the solution is the same text."""
    text = TINY.read_text(encoding="utf-8")
    key = reference_key(text, "tiny")
    assert reference_key(text, "tiny") == key
    assert reference_key(text.replace("def add", "def add ", 1), "tiny") != key
    assert reference_key(text, "tiny2") != key
