"""One mistake costs its own exercise's checks, not every later check that uses it.

A check is given the student's versions of the exercises it grades (its
``exercises`` metadata) and the solution's versions of the others, as
nbgrader's and otter's users expect: in this lab the ``scale`` check also
calls ``add``; a student whose ``add`` is wrong loses ``add`` only.
"""

from __future__ import annotations

import pytest

from robotlib.course import grade as g
from robotlib.course.notebooks import read_notebook, write_notebook
from tests.course.test_course_grade import ADD, SCALE_CHECK, TINY, by_id, with_cell
from tests.sandboxing import need_sandbox


@pytest.mark.slow
def test_a_wrong_earlier_exercise_costs_only_its_own_check(tmp_path):
    need_sandbox()
    sol = read_notebook(TINY)
    check = by_id(sol, SCALE_CHECK)
    check.source = "assert add(2, 2) == 4, 'scale uses add'\n" + check.source
    write_notebook(sol, tmp_path / "tiny.ipynb")
    wrong_add = with_cell(sol, ADD, "def add(a, b):\n    return a - b")
    (tmp_path / "subs" / "ann").mkdir(parents=True)
    write_notebook(wrong_add, tmp_path / "subs" / "ann" / "tiny.ipynb")
    opts = g.Options(cell_timeout=20, timeout=120)
    lab = tmp_path / "tiny.ipynb"
    results, _ = g.grade(tmp_path / "subs", "tiny", lab, 1, opts, progress=False)
    (r,) = results
    assert r.points["add"] == 0 and r.points["scale"] == 1, r.reasons
    assert r.points["mean"] == 2
