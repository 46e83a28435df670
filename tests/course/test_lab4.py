"""Lab 4 graded end to end: solution full, released zero, a do-nothing answer
fails every check (the outcome checks included)."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest

from robotlib.course import grade as g
from robotlib.course.notebooks import read_notebook, release_notebook, write_notebook

pytestmark = pytest.mark.slow  # a lab graded whole

ROOT = Path(__file__).resolve().parents[2]
LAB = "lab4_navigation"

DO_NOTHING = {
    "inflate": "def inflate_grid(occupied, radius, resolution):\n"
    "    return np.zeros_like(np.asarray(occupied, dtype=bool))\n",
    "wavefront": "def wavefront(blocked, goal):\n"
    "    return np.full(np.shape(blocked), -1)\n",
    "astar": "import heapq\n\n\ndef astar_grid(blocked, start, goal, weight=1.0):\n"
    "    return [], math.inf, 0\n",
    "extend": "def extend(nodes, q, step):\n"
    "    return 0, np.asarray(nodes, float)[0]\n",
    "steer": "def steer(pose, target, v, w_max):\n    return 0.0, 0.0\n",
}


def test_lab4_grades_honestly(tmp_path):
    sol = read_notebook(ROOT / "solutions" / f"{LAB}.ipynb")
    released = read_notebook(ROOT / "labs" / f"{LAB}.ipynb")
    assert released == release_notebook(sol, LAB)
    lazy = copy.deepcopy(released)
    exercises = {
        c.id: c.metadata.get("robotlib", {}).get("exercise") for c in sol.cells
    }
    found = set()
    for cell in lazy.cells:
        ex = exercises.get(cell.id)
        if ex:
            cell.source = DO_NOTHING[ex]
            found.add(ex)
    assert found == set(DO_NOTHING)
    # a sign error in steer costs steer's own checks, not navigate's (which
    # grades A* and drives with the solution's steering law)
    sign = copy.deepcopy(sol)
    cell = next(c for c in sign.cells if "def steer" in c.source)
    wrong = "pose[2], 2 * math.pi)\n    alpha = -alpha"
    cell.source = cell.source.replace("pose[2], 2 * math.pi)", wrong)
    subs = {"solution": sol, "released": released, "lazy": lazy, "sign": sign}
    for name, nb in subs.items():
        (tmp_path / name).mkdir()
        write_notebook(nb, tmp_path / name / f"{LAB}.ipynb")
    opts = g.GradeOptions(cell_timeout=120, timeout=600)
    results, checks = g.grade(tmp_path, LAB, jobs=2, opts=opts, progress=False)
    rows = {r.student: r for r in results}
    assert {c.grade_id for c in checks} >= {"astar", "tracking", "navigate"}
    assert rows["solution"].total == sum(c.points for c in checks), rows[
        "solution"
    ].reasons
    for student in ("released", "lazy"):
        assert rows[student].total == 0, (student, rows[student].points)
    assert all(r.status == "ok" for r in results), [r.status for r in results]
    lost = {k for k, v in rows["sign"].points.items() if v == 0}
    assert lost == {"steer", "tracking"}, rows["sign"].reasons
