"""``robotlib grade --scheduler local``: the tiny lab graded on a local Dask cluster.

Each Dask worker grades whole submissions in the same sandboxes as the
threaded grader; the results must be the same (the solution full marks, the
released lab zero, a cheat zeroed, a hang timed out) and no grading process
may outlive the cluster. The class is graded beside the other tests
(`tests.background`; the test runs last). Skipped when ``dask.distributed``
is not installed (``pip install -e ".[grade-dask]"``) or the sandbox cannot
run here.
"""

from __future__ import annotations

import copy
import csv
import sys
from pathlib import Path

import pytest

from robotlib.course.notebooks import read_notebook, release_notebook, write_notebook
from tests import background
from tests.references import records_of, shared
from tests.sandboxing import left_behind, need_sandbox, run_adopting

pytestmark = pytest.mark.slow  # a class graded on a Dask cluster

TINY = Path(__file__).parents[1] / "data" / "course" / "tiny.ipynb"


def _cell(nb, cid, source):
    nb = copy.deepcopy(nb)
    next(c for c in nb.cells if c.id == cid).source = source
    return nb


def background_work(folder: Path):
    """Grade on the cluster beside the other tests (`tests.background`).

    The CLI runs in a process that adopts whatever outlives it and records
    what is left when it has ended (`tests.sandboxing.run_adopting`).
    """
    try:
        import dask.distributed  # noqa: F401
    except ImportError:
        pytest.skip("dask.distributed is not installed (extra grade-dask)")
    need_sandbox()
    sol = read_notebook(TINY)
    subs = {
        "solution_a": sol,
        "solution_b": sol,
        "released": release_notebook(sol, "tiny"),
        "alias": _cell(sol, "tiny-06", "from numpy import mean\n"),
        "hang": _cell(sol, "tiny-03", "def add(a, b):\n    while True:\n        pass"),
    }
    for name, nb in subs.items():
        (folder / "subs" / name).mkdir(parents=True)
        write_notebook(nb, folder / "subs" / name / "tiny.ipynb")
    out, report = folder / "gb.csv", folder / "left.json"
    cmd = [
        sys.executable, "-m", "robotlib.cli", "grade", str(folder / "subs"),
        "--lab", "tiny", "--solution", str(TINY), "--out", str(out),
        "--scheduler", "local", "--jobs", "2", "--cell-timeout", "4", "--quiet",
    ]  # fmt: skip
    with shared("tiny", TINY, records_of(out)):
        proc = run_adopting(cmd, report, 600)  # quiet s: tests.contention
    return proc, set(subs), out, left_behind(report) if report.exists() else None


def test_grade_on_a_local_dask_cluster():
    proc, students, out, left = background.result(__name__)
    assert proc.returncode == 0, proc.stderr[-3000:]
    rows = {r["student"]: r for r in csv.DictReader(out.open())}
    assert set(rows) == students
    full = float(rows["solution_a"]["max"]) - 1  # the written answer: by hand
    for name in ("solution_a", "solution_b"):
        assert float(rows[name]["total"]) == full, rows[name]
        assert rows[name]["status"] == "ok" and rows[name]["flags"] == ""
    assert float(rows["released"]["total"]) == 0
    assert rows["alias"]["mean"] == "0" and "numpy.mean" in rows["alias"]["notes"]
    assert rows["alias"]["add"] == "1"
    assert rows["hang"]["add"] == "0" and "timed out" in rows["hang"]["notes"]
    worker = f"{sys.executable}\0-m\0robotlib.course.worker".encode()
    assert left is not None, proc.stderr[-3000:]
    # every worker's sandboxes ended with the cluster
    assert [c for c in left if worker in c] == []
