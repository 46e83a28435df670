"""The real labs, graded end to end: solution full, released zero, partial partial."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest

from robotlib.course import grade as g
from robotlib.course.notebooks import read_notebook, release_notebook, write_notebook

ROOT = Path(__file__).resolve().parents[1]

# lab -> the solution cells a "partial" student copied (and the checks they pass)
PARTIAL = {
    "lab0_getting_started": ({"l0-14"}, {"sonar": 2}),
    "lab3_mcl": (
        {"l3-05", "l3-10", "l3-13", "l3-37"},
        {"weights": 2, "select": 1, "resize": 2, "low_variance": 2, "global": 2},
    ),
}


@pytest.mark.parametrize("lab", sorted(PARTIAL))
def test_lab_grades_honestly(lab, tmp_path):
    sol = read_notebook(ROOT / "solutions" / f"{lab}.ipynb")
    released = read_notebook(ROOT / "labs" / f"{lab}.ipynb")
    assert released == release_notebook(sol, lab)
    copied, earned = PARTIAL[lab]
    partial = copy.deepcopy(released)
    sources = {c.id: c.source for c in sol.cells}
    for cell in partial.cells:
        if cell.id in copied:
            cell.source = sources[cell.id]
    for name, nb in {"solution": sol, "released": released, "partial": partial}.items():
        (tmp_path / name).mkdir()
        write_notebook(nb, tmp_path / name / f"{lab}.ipynb")
    opts = g.GradeOptions(cell_timeout=60, timeout=180)
    results, checks = g.grade(tmp_path, lab, jobs=2, opts=opts, progress=False)
    rows = {r.student: r for r in results}
    full = sum(c.points for c in checks)
    assert rows["solution"].total == full, rows["solution"].reasons
    assert rows["released"].total == 0
    assert all(v == 0 for v in rows["released"].points.values())
    got = {k: v for k, v in rows["partial"].points.items() if v}
    assert got == earned, rows["partial"].reasons
    assert all(r.status == "ok" and not r.flags for r in results)
