"""Labs 1, 5, 6 and 7: answers that do nothing fail the outcome checks.

Each case runs a check cell (hidden tests included) in-process, with the
lab's set-up cell, the instructor's definitions the check needs
(`robotlib.course.plan.lab_plan`), the other exercises' solutions (as the
grader gives them) and a do-nothing version of the exercise's functions
(plausible types, no work): the check must fail on its assertions.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest

from robotlib.course.notebooks import read_notebook
from robotlib.course.plan import lab_plan

ROOT = Path(__file__).resolve().parents[2]
ICP_STAYS = "def icp_step(reference, scan, pose, gate):\n    return np.array(pose)\n"

LAZY = {
    "lab1_models": {
        "alphas": "def fit_alphas(*a):\n    return np.zeros(4)\n",
        "umbmark": "def umbmark_estimate(*a):\n    return 1.0, 1.0\n",
        "hist_filter": (
            "def hist_predict(b, *a):\n    return np.asarray(b, float)\n"
            "def hist_update(b, lk):\n    return np.asarray(b, float)\n"
        ),
        "beam_fit": "def fit_beam(*a, **k):\n    return BeamParameters()\n",
        "ekf_update": "def ekf_landmark_update(mu, P, *a):\n    return mu, P\n",
        "ekf_run": "def ekf_landmark_update(mu, P, *a):\n    return mu, P\n",
    },
    "lab5_slam": {"icp_step": ICP_STAYS, "icp_graph": ICP_STAYS},
    "lab6_real_robot": {
        "replay": "def localize(world, odo, z, seed):\n    return np.array(odo)\n",
    },
    "lab7_exploration": {  # runs the simulator: a few seconds each
        "explore_outcome": (
            "def frontier_cells(state):\n"
            "    return np.zeros(np.shape(state), dtype=bool)\n"
            "def choose_target(costs, gains, beta):\n"
            "    return np.full(len(np.atleast_2d(costs)), -1)\n"
        ),
        "team_outcome": (
            "def discount(gain, targets, chosen, radius):\n"
            "    return np.asarray(gain, dtype=float)\n"
        ),
    },
}
SLOW = {"lab5_slam", "lab7_exploration"}  # 5-30 s each (warm-ups, drives)


def _run(lab: str, grade_id: str, lazy: str, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))  # Lab 6's mkdtemp
    sol = read_notebook(ROOT / "solutions" / f"{lab}.ipynb")
    plan = lab_plan(sol, lab)
    check = next(c for c in plan.checks if c.grade_id == grade_id)
    source = sol.cells[check.index].source
    scope: dict = {}
    exec(compile(plan.setup, "setup", "exec"), scope)
    for answer in plan.answers:  # the other exercises' solutions, as at grading
        exec(compile(answer, "solution", "exec"), scope)
    exec(compile(lazy, "lazy answer", "exec"), scope)
    for d in plan.defs:
        exec(compile(d, "definitions", "exec"), scope)
    exec(compile(lazy, "lazy answer", "exec"), scope)  # after defs that named it
    with pytest.raises(AssertionError):
        exec(compile(source, grade_id, "exec"), scope)


@pytest.mark.parametrize(
    ("lab", "grade_id"),
    [
        pytest.param(lab, g, marks=[pytest.mark.slow] if lab in SLOW else [])
        for lab, d in LAZY.items()
        for g in d
    ],
)
def test_a_do_nothing_answer_fails(lab, grade_id, tmp_path, monkeypatch):
    _run(lab, grade_id, LAZY[lab][grade_id], tmp_path, monkeypatch)
