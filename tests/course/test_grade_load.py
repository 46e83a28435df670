"""Grades do not depend on the machine's load or on the classmates graded alongside.

A correct answer that is slow (its ``mean`` burns about a third of the cell
limit in CPU time per call) is graded three times: alone, beside a classmate
whose notebook forks busy loops, and alone under ten busy processes this
test starts (in its own process tree, ended at the end; load about 10 on
top of the machine's). On two shared cores its calls then take several
times the cell limit in wall time, which a wall-clock limit would fail. Its
points must be the same each time; the hog is flagged, the slow answer never.
"""

from __future__ import annotations

import copy
import subprocess
import sys
import time

import nbformat
import pytest

from robotlib.course import cpu
from robotlib.course import grade as g
from robotlib.course.notebooks import write_notebook
from robotlib.course.plan import lab_plan
from tests.course.test_course_grade import (
    ADD,
    ADD_CHECK,
    FULL,
    MEAN,
    TINY,
    by_id,
    solution,
    with_cell,
)
from tests.sandboxing import need_sandbox

CELL_LIMIT = 5.0
MANY_CALLS = 3000


def _loop_count(cpu_seconds: float) -> int:
    """Iterations of the slow answer's loop that take ``cpu_seconds`` of CPU here."""
    n = 2_000_000
    t0 = time.process_time()
    t = 0
    for i in range(n):
        t += i % 7
    per = (time.process_time() - t0) / n
    return int(cpu_seconds / max(per, 1e-9))


def _slow_mean(n: int) -> str:
    return (
        "def mean(xs):\n    t = 0\n"
        f"    for i in range({n}):  # a slow but correct answer\n"
        "        t += i % 7\n"
        "    return sum(xs) / len(xs) + 0 * t\n"
    )


HOG = (
    "import os\n"
    "for _ in range(4):  # busy loops that never end\n"
    "    if os.fork() == 0:\n        while True:\n            pass\n"
    "def mean(xs):\n    return sum(xs) / len(xs)\n"
)


def _grade(folder, jobs):
    opts = g.Options(cell_timeout=CELL_LIMIT, timeout=60, backstop=20)
    results, _ = g.grade(folder, "tiny", TINY, jobs=jobs, opts=opts, progress=False)
    return {r.student: r for r in results}


@pytest.mark.slow
def test_same_grade_alone_beside_a_hog_and_under_load(tmp_path):
    need_sandbox()
    slow = with_cell(solution(), MEAN, _slow_mean(_loop_count(CELL_LIMIT / 3)))
    alone = tmp_path / "alone"
    (alone / "slow").mkdir(parents=True)
    write_notebook(slow, alone / "slow" / "tiny.ipynb")
    first = _grade(alone, jobs=1)["slow"]
    assert {k: first.points[k] for k in FULL} == {k: float(v) for k, v in FULL.items()}
    assert first.status == "ok", (first.status, first.reasons)

    crowd = tmp_path / "crowd"
    for name, nb in (("slow", slow), ("hog", with_cell(solution(), MEAN, HOG))):
        (crowd / name).mkdir(parents=True)
        write_notebook(nb, crowd / name / "tiny.ipynb")
    rows = _grade(crowd, jobs=2)
    beside = rows["slow"]
    assert any("CPU hogs" in f for f in rows["hog"].flags), rows["hog"].flags

    busy = _busy(10)
    try:
        loaded = _grade(alone, jobs=1)["slow"]
    finally:
        _end(busy)
    for again in (beside, loaded):
        assert again.points == first.points, again.reasons
        assert again.status == "ok", (again.status, again.reasons)
        assert not any("CPU hogs" in f for f in again.flags), again.flags


def test_limits_scale_with_the_solution_s_time():
    """A check may take 20 times the solution's time, never less than the floor."""
    ref = {"a": {"cpu": 0.01}, "b": {"cpu": 3.0}, "c": {}}
    opts = g.Options(cell_timeout=5, timeout=60, slower=20)
    budgets, scaled = g.limits(ref, opts)
    assert budgets == {"a": 5, "b": 60.0, "c": 5}
    assert scaled.timeout == pytest.approx(60.2) and opts.timeout == 60  # 20 x 3.01
    assert g.limits(None, opts)[0] == {}
    big = g.limits({"a": {"cpu": 100.0}}, opts)[1]  # no process killed before
    assert big.limits.cpu >= big.timeout == 2000


@pytest.mark.slow
def test_ten_times_slower_than_the_solution_passes():
    """The check's limit comes from the solution's CPU time for it, not the floor.

    The slow ``mean`` burns 0.75 s of CPU per call (two calls in its check),
    ten times what the solution is said to take: it passes with the default
    factor (20) and times out when the factor (5) brings the limit down to
    the 1 s floor.
    """
    need_sandbox()
    sol = solution()
    plan = lab_plan(sol, "tiny")
    opts = g.Options(cell_timeout=1, timeout=60, backstop=30)
    reference = g.reference_run(plan, sol, opts)
    assert all(r["cpu"] >= 0 for r in reference.values())
    reference["mean"]["cpu"] = 0.15  # the slow answer's 1.5 s: ten times that
    slow = with_cell(sol, MEAN, _slow_mean(_loop_count(0.75)))
    passed = g.grade_notebook("slow", slow, plan, reference, opts)
    assert passed.points["mean"] == 2, passed.reasons
    strict = g.Options(**{**vars(opts), "slower": 5})
    failed = g.grade_notebook("slow", slow, plan, reference, strict)
    assert failed.points["mean"] == 0
    assert "timed out after 1 s" in failed.reasons["mean"], failed.reasons


def _busy(n: int) -> list[subprocess.Popen]:
    """Start ``n`` busy processes of this test's own (end them with `_end`)."""
    return [
        subprocess.Popen([sys.executable, "-c", "while True:\n    pass"])
        for _ in range(n)
    ]


def _end(procs: list[subprocess.Popen]) -> None:
    for p in procs:
        p.kill()
        p.wait()


@pytest.mark.slow
@pytest.mark.xfail(
    strict=False,
    reason="issue 28, open: under a whole suite's own load the charge of some runs "
    "still passes the 2 s floor (3 of 4 whole suites this session)",
)
def test_many_short_calls_are_charged_their_cpu_time_under_load():
    """A check making thousands of short calls is not charged the machine's delays.

    Lab 2's potential-field check calls the student's function once per
    control step. Here a check calls a correct ``add`` 3000 times, against
    the 2 s floor, beside six busy processes of this test: each call takes
    far less CPU than a millisecond but waits for a CPU, and for the grader
    to relay it. Charged their wall time, the calls ran out of time (13 of
    15 for Lab 2's ``process_flood`` case under load); charged the CPU they
    used, the check passes, and its charged time stays below the limit.
    """
    need_sandbox()
    calls = (
        f"for i in range({MANY_CALLS}):\n    assert add(i, 1) == i + 1\n"
        "print('CHECK add', add(2, 3))\n"
    )
    sol = with_cell(solution(), ADD_CHECK, calls)
    plan = lab_plan(sol, "tiny")
    opts = g.Options(cell_timeout=2, timeout=120, backstop=200)
    reference = g.reference_run(plan, sol, opts)
    reference["add"]["cpu"] = 0.0  # its limit: the 2 s floor
    busy = _busy(6)
    try:
        graded = g.grade_notebook("many", sol, plan, reference, opts)
    finally:
        _end(busy)
    assert graded.status == "ok", (graded.status, graded.reasons)
    assert graded.points["add"] == 1, graded.reasons
    assert graded.check_lines["add"]["cpu"] < 2


def test_cpu_time_counts_the_whole_tree_and_not_sleep():
    """A busy child's CPU time is its parent's; a sleeping tree uses none."""
    code = (
        "import os, time\n"
        "if os.fork() == 0:\n    t = time.process_time()\n"
        "    while time.process_time() - t < 0.6:\n        pass\n    os._exit(0)\n"
        "time.sleep(30)\n"
    )
    proc = subprocess.Popen([sys.executable, "-c", code])
    try:
        deadline = time.monotonic() + 30
        u = cpu.usage(proc.pid, proc.pid)
        while u.cpu < 0.6 and time.monotonic() < deadline:
            time.sleep(0.1)
            u = cpu.usage(proc.pid, proc.pid)
        assert u.cpu >= 0.6  # the child's time, ended or not
        before = cpu.usage(proc.pid, proc.pid).cpu
        time.sleep(0.5)
        assert cpu.usage(proc.pid, proc.pid).cpu - before < 0.2  # asleep
        assert cpu.find_worker(proc.pid, [sys.executable, "-c"]) == proc.pid
    finally:
        proc.kill()
        proc.wait()


@pytest.mark.slow
def test_tmp_is_writable_and_the_disk_has_a_quota(tmp_path):
    """``/tmp`` in the sandbox is writable (as the guide says); filling the disk
    past the quota ends the process and is flagged, and the others' points stand."""
    from robotlib.course.sandbox import Limits

    need_sandbox()
    sol = solution()
    tmp_add = with_cell(
        sol, ADD, "open('/tmp/x', 'w').write('ok')\n" + by_id(sol, ADD).source
    )
    hog = copy.deepcopy(sol)
    hog.cells.append(nbformat.v4.new_code_cell(
        "for i in range(8):\n    with open(f'fill{i}', 'wb') as f:\n"
        "        f.write(bytes(8 << 20))\n"
        "import time\ntime.sleep(5)\n"
    ))  # fmt: skip
    subs = tmp_path / "subs"
    for name, nb in (("tmp", tmp_add), ("filler", hog)):
        (subs / name).mkdir(parents=True)
        write_notebook(nb, subs / name / "tiny.ipynb")
    opts = g.Options(cell_timeout=20, timeout=120, limits=Limits(disk=32 << 20))
    results, _ = g.grade(subs, "tiny", TINY, jobs=2, opts=opts, progress=False)
    rows = {r.student: r for r in results}
    assert rows["tmp"].points["add"] == 1, rows["tmp"].reasons
    assert any("MiB to disk" in f for f in rows["filler"].flags), rows["filler"].flags
