"""Lab 2: answers that do nothing, or drive at the goal regardless, fail every
outcome check (solution full, released zero and the cheats are in
test_course_labs)."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest

from robotlib.course import grade as g
from robotlib.course.notebooks import read_notebook, write_notebook

pytestmark = pytest.mark.slow  # a lab graded whole

ROOT = Path(__file__).resolve().parents[2]
LAB = "lab2_avoidance"
OUTCOME_CHECKS = {"explorer", "pf", "vfh"}

NOTHING = {
    "l2-05": "FEAR = np.zeros((2, 8))\nEXPLORER = np.zeros((2, 8))",
    "l2-11": "def potential_force(sonar, pose, goal, k_att=1.0, k_rep=0.5, d0=1.2):\n"
    "    return np.zeros(2)",
    "l2-21": "def polar_histogram(points, certainty, pose, n_sectors=72, window=1.8,"
    " enlarge=0.3):\n    return np.zeros(n_sectors)",
    "l2-24": "def choose_direction(hist, threshold, target, wide=16):\n    return 0.0",
}
"""A do-nothing answer: no wiring, no force, an empty histogram, straight ahead."""

CONSTANT = {
    "l2-05": "FEAR = np.full((2, 8), 0.1)\nEXPLORER = np.full((2, 8), -0.1)",
    "l2-11": "def potential_force(sonar, pose, goal, k_att=1.0, k_rep=0.5, d0=1.2):\n"
    "    dx, dy = goal[0] - pose[0], goal[1] - pose[1]\n"
    "    c, s = math.cos(pose[2]), math.sin(pose[2])\n"
    "    return np.array([c * dx + s * dy, -s * dx + c * dy])",
    "l2-21": "def polar_histogram(points, certainty, pose, n_sectors=72, window=1.8,"
    " enlarge=0.3):\n    return np.zeros(n_sectors)",
    "l2-24": "def choose_direction(hist, threshold, target, wide=16):\n"
    "    return float(target)",
}
"""A constant answer: symmetric wiring, pull only, and straight at the goal."""


def _with(released, sources):
    nb = copy.deepcopy(released)
    for cell in nb.cells:
        if cell.id in sources:
            cell.source = sources[cell.id]
    return nb


def test_do_nothing_and_constant_answers_fail_the_outcome_checks(tmp_path):
    released = read_notebook(ROOT / "labs" / f"{LAB}.ipynb")
    subs = {"nothing": _with(released, NOTHING), "constant": _with(released, CONSTANT)}
    for name, nb in subs.items():
        (tmp_path / name).mkdir()
        write_notebook(nb, tmp_path / name / f"{LAB}.ipynb")
    opts = g.GradeOptions(cell_timeout=120, timeout=400)
    results, checks = g.grade(tmp_path, LAB, jobs=2, opts=opts, progress=False)
    rows = {r.student: r for r in results}
    assert OUTCOME_CHECKS <= {c.grade_id for c in checks}
    for name in ("nothing", "constant"):
        earned = {k for k, v in rows[name].points.items() if v}
        assert not earned & OUTCOME_CHECKS, (name, earned, rows[name].reasons)
