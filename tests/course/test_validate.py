"""``robotlib validate``: a student's notebook against the lab as handed out."""

from __future__ import annotations

import copy
import subprocess
import sys

import pytest

from robotlib.course.notebooks import read_notebook, release_notebook, write_notebook
from robotlib.course.validate import problems
from tests.course.test_course_grade import ADD, ADD_CHECK, TINY, WHY, by_id


def _answered(lab, sol):
    nb = copy.deepcopy(lab)
    for cid in (ADD, "tiny-06", "tiny-09", WHY):
        text = by_id(sol, cid).source.replace("### BEGIN SOLUTION\n", "")
        by_id(nb, cid).source = text.replace("### END SOLUTION", "")
    return nb


def test_unanswered_and_edited_are_named():
    sol = read_notebook(TINY)
    lab = release_notebook(sol, "tiny")
    assert problems(_answered(lab, sol), lab) == []
    found = problems(lab, lab)
    assert "exercise add: not answered (NotImplementedError)" in found
    assert "written answer 'why': not written yet" in found
    edited = _answered(lab, sol)
    by_id(edited, ADD_CHECK).source = "print('CHECK add 5')"
    (only,) = problems(edited, lab)
    assert only.startswith("check 'add': missing or edited")


@pytest.mark.slow
def test_the_command_runs_the_notebook(tmp_path):
    sol = read_notebook(TINY)
    lab = release_notebook(sol, "tiny")
    write_notebook(lab, tmp_path / "lab.ipynb")
    good, bad = _answered(lab, sol), _answered(lab, sol)
    by_id(bad, "tiny-06").source = "def mean(xs):\n    return 0.0"
    for name, nb in (("good", good), ("bad", bad)):
        write_notebook(nb, tmp_path / f"{name}.ipynb")
    cmd = [sys.executable, "-m", "robotlib.cli", "validate", "--lab-file",
           str(tmp_path / "lab.ipynb"), "--run", "--timeout", "120"]  # fmt: skip
    ok, no = (
        subprocess.run(
            [*cmd, str(tmp_path / f"{n}.ipynb")],
            capture_output=True,
            text=True,
            timeout=300,
        )
        for n in ("good", "bad")
    )
    assert ok.returncode == 0 and "ready to hand in" in ok.stdout, ok.stdout
    assert no.returncode == 1, no.stdout
    assert "check 'mean' fails: AssertionError" in no.stdout, no.stdout
