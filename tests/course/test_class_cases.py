"""A representative part of the class cases and the adversarial set, graded.

The cases are built by `tests.class_cases` from the lab's solution and
release, each with its worth (points per check, status, flag); the whole set,
three times under different loads, is ``bench/bench_grade_cases.py``. Here:
Lab 0 (the quickest to grade), one of each kind of layout and fault; it lists
no library versions of its exercises, so the cheats' routes are built for
Lab 2 (checked for their worth, not graded here: `tests/course/
test_course_grade.py` grades each route on the tiny lab). The subset is
graded beside the other tests (`tests.background`); its test runs last.
"""

from __future__ import annotations

import pickle
import sys
from pathlib import Path

import pytest

from robotlib.course import grade as g
from tests import background
from tests.class_cases import build, compare
from tests.references import shared
from tests.sandboxing import need_sandbox, orphans_adopted

ROOT = Path(__file__).resolve().parents[2]
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


# at the tests' priority, as when it ran among them: the hog must be seen busy
BACKGROUND_NICER = 0


def background_work(folder: Path):
    """Grade the subset beside the other tests (`tests.background`), if selected.

    In a process of its own (`_grade_subset`), so that its sandboxes stay out
    of the process trees the other grading tests search for leftovers.
    """
    names = {item.originalname for item in background.selected(__name__)}
    if "test_a_representative_subset_gets_its_worth" not in names:
        return None
    need_sandbox()
    cmd = [sys.executable, "-m", __name__, folder]
    proc = background.run(cmd, cwd=ROOT, timeout=3000)
    done = folder / "graded.pickle"
    if not done.exists():
        raise RuntimeError(f"exit {proc.returncode}: {proc.stderr[-4000:]}")
    return pickle.loads(done.read_bytes())


def _grade_subset(folder: Path) -> None:
    """Build the cases, grade `SUBSET`, write (cases, results) to ``graded.pickle``.

    SIGTERM (the session ended early) ends the grading's processes.
    """
    subs = folder / "subs"
    cases = build(LAB, subs)
    graded = {name: cases[name] for name in SUBSET}
    opts = g.Options(cell_timeout=10.0)
    records = folder / "records"  # the reference run: `tests.references`
    with orphans_adopted(), shared(LAB, ROOT / "solutions" / f"{LAB}.ipynb", records):
        results, _ = g.grade(subs, LAB, jobs=2, opts=opts, progress=False,
                             records=records, students=SUBSET)  # fmt: skip
    (folder / "graded.pickle").write_bytes(pickle.dumps((graded, results)))


@pytest.mark.slow
def test_a_representative_subset_gets_its_worth():
    graded, results = background.result(__name__)
    assert compare(graded, results) == []


if __name__ == "__main__":  # the grading's own process (`background_work`)
    _grade_subset(Path(sys.argv[1]))
