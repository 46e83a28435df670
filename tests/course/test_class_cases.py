"""A representative part of the class cases and the adversarial set, graded.

The cases are built by `tests.class_cases` from the lab's solution and
release, each with its worth (points per check, status, flag); the whole set,
three times under different loads, is ``bench/bench_grade_cases.py``. Here:
Lab 0 (the quickest to grade), one of each kind of layout and fault; it lists
no library versions of its exercises, so the cheats' routes are built for
Lab 2 (checked for their worth, not graded here: `tests/course/
test_course_grade.py` grades each route on the tiny lab).
"""

from __future__ import annotations

import pytest

from robotlib.course import grade as g
from tests.class_cases import build, compare
from tests.sandboxing import need_sandbox, orphans_adopted

LAB = "lab0_getting_started"
SUBSET = [
    "answered", "released", "partial", "nbformat_4_4", "pasted", "duplicated_demo",
    "copy_newer", "untitled_beside", "section2/alice", "José", "helper_module",
    "older_release", "two_notebooks", "infinite_loop", "cpu_hog", "ordinary_code",
]  # fmt: skip


@pytest.mark.slow
def test_the_cases_are_built_with_their_worth(tmp_path):
    cases = build("lab2_avoidance", tmp_path)
    assert set(SUBSET) <= set(cases)
    assert {c.kind for c in cases.values()} == {"class", "adversarial"}
    assert len([c for c in cases if c.startswith("cheat_")]) == 6
    full = cases["answered"].points
    assert full and all(v > 0 for v in full.values())
    assert set(cases["released"].points.values()) == {0.0}
    # a cheat costs its exercise's checks only
    cheat = cases["cheat_importlib"].points
    assert 0 < sum(cheat.values()) < sum(full.values())
    assert cases["cpu_hog"].points is None and cases["cpu_hog"].flagged
    assert (tmp_path / "helper_module" / "helpers.py").exists()
    assert (tmp_path / "linked.ipynb").is_symlink()


@pytest.mark.slow
def test_a_representative_subset_gets_its_worth(tmp_path):
    need_sandbox()
    subs = tmp_path / "subs"
    cases = build(LAB, subs)
    graded = {name: cases[name] for name in SUBSET}
    opts = g.Options(cell_timeout=10.0)
    with orphans_adopted():
        results, _ = g.grade(subs, LAB, jobs=2, opts=opts, progress=False,
                             records=tmp_path / "records", students=SUBSET)  # fmt: skip
    assert compare(graded, results) == []
