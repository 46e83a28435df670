"""Grading with nbval, end to end, on a tiny lab and adversarial submissions.

One module-scoped grading run covers every case (about 25-35 s on 2 cores):
the solution, the released lab, a partial solution, an edited or deleted
check, a forged tag, an infinite loop, a hang inside an @njit function,
``os._exit``, swallowed exceptions, cells blanked by an input transformer,
``np.isclose`` patched, an unreadable file and a missing notebook.
"""

from __future__ import annotations

import copy
import csv
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import nbformat
import pytest

from robotlib.course import grade as g
from robotlib.course._nbval_plugin import check_token
from robotlib.course.notebooks import read_notebook, release_notebook, write_notebook

DATA = Path(__file__).parent / "data" / "course"
TINY = DATA / "tiny.ipynb"
CELL_TIMEOUT = 3.0


def solution():
    return read_notebook(TINY)


def by_id(nb, cid):
    return next(c for c in nb.cells if c.id == cid)


def set_source(nb, cid, source):
    by_id(nb, cid).source = source
    return nb


ADD, ADD_CHECK, MEAN, MEAN_CHECK, SCALE, SCALE_CHECK = (
    "tiny-03",
    "tiny-04",
    "tiny-06",
    "tiny-07",
    "tiny-09",
    "tiny-10",
)


def make_submissions(folder: Path) -> dict[str, tuple[float, dict]]:
    """Write the submissions; return student -> (expected total, expected points)."""
    sol = solution()
    released = release_notebook(sol, "tiny")
    subs = {}

    def put(name, nb, total, points):
        d = folder / name
        d.mkdir(parents=True)
        write_notebook(nb, d / "tiny.ipynb")
        subs[name] = (total, points)

    put("solution", sol, 4, {"add": 1, "mean": 2, "scale": 1})
    put("released", released, 0, {"add": 0, "mean": 0, "scale": 0})

    partial = copy.deepcopy(released)
    set_source(partial, ADD, by_id(sol, ADD).source)
    put("partial", partial, 1, {"add": 1, "mean": 0, "scale": 0})

    # wrong add with its check edited to pass, wrong mean with its check deleted
    edited = copy.deepcopy(sol)
    set_source(edited, ADD, "def add(a, b):\n    return a - b")
    set_source(edited, ADD_CHECK, "print('CHECK add', 5)")
    set_source(edited, MEAN, "def mean(xs):\n    return 0")
    edited.cells = [c for c in edited.cells if c.id != MEAN_CHECK]
    put("edited_check", edited, 1, {"add": 0, "mean": 0, "scale": 1})

    # forged tags and outputs on a check, and a forged extra check cell
    forged = copy.deepcopy(sol)
    set_source(forged, ADD, "def add(a, b):\n    return 0")
    chk = by_id(forged, ADD_CHECK)
    chk.metadata["tags"] = ["raises-exception", "nbval-skip"]
    chk.outputs = [
        nbformat.v4.new_output("stream", name="stdout", text="CHECK add 5\n")
    ]
    chk.execution_count = 3
    extra = nbformat.v4.new_code_cell("print('bonus')")
    extra.metadata["robotlib"] = {"grade_id": "bonus", "points": 10}
    forged.cells.append(extra)
    put("forged_tags", forged, 3, {"add": 0, "mean": 2, "scale": 1})

    loop = copy.deepcopy(sol)
    set_source(loop, MEAN, "def mean(xs):\n    while True:\n        pass")
    put("infinite_loop", loop, 2, {"add": 1, "mean": 0, "scale": 1})

    njit_hang = copy.deepcopy(sol)
    set_source(
        njit_hang,
        MEAN,
        by_id(sol, MEAN).source
        + "\n\nfrom numba import njit\n\n@njit\ndef spin(n):\n    i = 0\n"
        "    while i >= 0:\n        i = (i + n) % 1000003\n    return i\n\nspin(1)",
    )
    put("njit_hang", njit_hang, 2, {"add": 1, "mean": 0, "scale": 1})

    exits = copy.deepcopy(sol)
    set_source(exits, SCALE, by_id(sol, SCALE).source + "\nimport os\nos._exit(3)")
    put("os_exit", exits, 3, {"add": 1, "mean": 2, "scale": 0})

    swallow = copy.deepcopy(sol)
    set_source(
        swallow,
        ADD,
        "get_ipython().set_custom_exc((BaseException,), lambda *a, **k: None)\n"
        "def add(a, b):\n    return 7",
    )
    put("swallowed", swallow, 3, {"add": 0, "mean": 2, "scale": 1})

    blank = copy.deepcopy(sol)
    set_source(
        blank,
        ADD,
        "def _blank(lines):\n"
        "    return [] if any('assert' in x for x in lines) else lines\n"
        "get_ipython().input_transformers_post.append(_blank)\n"
        "def add(a, b):\n    return 7",
    )
    set_source(blank, MEAN, "def mean(xs):\n    return 1")
    put("blanked", blank, 0, {"add": 0, "mean": 0, "scale": 0})

    patched = copy.deepcopy(sol)
    set_source(
        patched,
        SCALE,
        "np.isclose = lambda *a, **k: True\nnp.allclose = lambda *a, **k: True\n"
        "def scale(xs, k):\n    return np.asarray(xs, float) * (k + 1)",
    )
    put("isclose_patched", patched, 3, {"add": 1, "mean": 2, "scale": 0})

    (folder / "garbage.ipynb").write_text("{ this is not json")
    subs["garbage"] = (0, {"add": 0, "mean": 0, "scale": 0})
    (folder / "nothing").mkdir()
    subs["nothing"] = (0, {"add": 0, "mean": 0, "scale": 0})
    return subs


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    folder = tmp_path_factory.mktemp("subs")
    expected = make_submissions(folder)
    out = folder.parent / "gradebook.csv"
    t0 = time.monotonic()
    cmd = [
        sys.executable,
        "-m",
        "robotlib.cli",
        "grade",
        str(folder),
        "--lab",
        "tiny",
        "--solution",
        str(TINY),
        "--out",
        str(out),
        "--cell-timeout",
        str(CELL_TIMEOUT),
        "--timeout",
        "60",
        "--jobs",
        "2",
        "--quiet",
    ]
    work = folder.parent / "work"  # the grader's temporary folders go here
    work.mkdir()
    env = {**os.environ, "TMPDIR": str(work)}
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=env)
    elapsed = time.monotonic() - t0
    assert proc.returncode == 0, proc.stderr
    with open(out, newline="") as f:
        rows = {r["student"]: r for r in csv.DictReader(f)}
    return rows, expected, out, elapsed, work


def test_gradebook_columns(graded):
    rows, expected, out, *_ = graded
    header = out.read_text().splitlines()[0].split(",")
    assert header == [
        "student", "add", "mean", "scale", "total", "max",
        "status", "seconds", "flags", "notes",
    ]  # fmt: skip
    assert set(rows) == set(expected)
    assert all(r["max"] == "4" for r in rows.values())


@pytest.mark.parametrize(
    "student",
    [
        "solution",
        "released",
        "partial",
        "edited_check",
        "forged_tags",
        "infinite_loop",
        "njit_hang",
        "os_exit",
        "swallowed",
        "blanked",
        "isclose_patched",
        "garbage",
        "nothing",
    ],
)
def test_points(graded, student):
    rows, expected, *_ = graded
    total, points = expected[student]
    row = rows[student]
    got = {k: float(row[k]) for k in points}
    assert got == {k: float(v) for k, v in points.items()}, row["notes"]
    assert float(row["total"]) == total
    for gid, p in points.items():  # a reason for each failure, none for a pass
        assert (f"{gid}:" in row["notes"]) == (p == 0), row["notes"]


def test_reasons_and_status(graded):
    rows = graded[0]
    assert "timed out" in rows["infinite_loop"]["notes"]
    assert rows["os_exit"]["status"] == "kernel died"
    assert "NotImplementedError" in rows["released"]["notes"]
    assert "did not run to its end" in rows["swallowed"]["notes"]
    assert "did not run to its end" in rows["blanked"]["notes"]
    assert "wrong result" in rows["isclose_patched"]["notes"]
    assert rows["garbage"]["status"] == "unreadable notebook"
    assert rows["nothing"]["status"] == "no notebook"


def test_flags(graded):
    rows = graded[0]
    assert "hidden errors" in rows["swallowed"]["flags"]
    assert "input transformer" in rows["blanked"]["flags"]
    assert "patched library function" in rows["isclose_patched"]["flags"]
    assert rows["solution"]["flags"] == ""


def test_feedback_files(graded):
    out = graded[2]
    fb = out.with_name("gradebook-feedback")
    text = (fb / "partial.md").read_text()
    assert "1 / 4" in text and "NotImplementedError" in text
    assert len(list(fb.glob("*.md"))) == len(graded[1])


def test_no_process_left_behind(graded):
    """No process of this run's grading jobs survives it."""
    work = str(graded[4]).encode()
    left = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/environ", "rb") as f:
                environ = f.read()
        except OSError:
            continue
        if g.JOB_ENV.encode() in environ and work in environ:
            left.append(int(entry))
    assert left == []
    assert list(graded[4].iterdir()) == []  # working folders removed


def test_report_time(graded, capsys):
    with capsys.disabled():
        print(f"\n[grading {len(graded[1])} tiny submissions took {graded[3]:.1f} s]")


# -- unit tests of the notebook rebuilding ----------------------------------------


def test_build_restores_edited_and_deleted_checks():
    sol = solution()
    student = release_notebook(sol, "tiny")
    set_source(student, ADD_CHECK, "pass")
    by_id(student, ADD_CHECK).metadata["robotlib"]["points"] = 100
    student.cells = [c for c in student.cells if c.id != MEAN_CHECK]
    key = b"k" * 32
    nb = g.build_graded_notebook(student, sol, key, "tiny")
    ids = [c.id for c in nb.cells]
    # the deleted check comes back right after the cell it followed
    assert ids.index(MEAN_CHECK) == ids.index(MEAN) + 1
    add_check = by_id(nb, ADD_CHECK)
    assert "assert add(-1, 1) == 0" in add_check.source  # hidden test back
    assert add_check.source.endswith(f"print({check_token(key, 'add')!r})")
    assert add_check.metadata["robotlib"] == {"grade_id": "add", "points": 1}
    assert all(c.get("outputs", []) == [] for c in nb.cells)


def test_build_drops_unknown_checks_and_nbval_tags():
    sol = solution()
    student = copy.deepcopy(sol)
    by_id(student, ADD).metadata["tags"] = ["raises-exception", "mine"]
    fake = nbformat.v4.new_code_cell("print(1)")
    fake.metadata["robotlib"] = {"grade_id": "extra", "points": 5}
    student.cells.append(fake)
    nb = g.build_graded_notebook(student, sol, b"k" * 32, "tiny")
    assert by_id(nb, ADD).metadata["tags"] == ["mine"]
    assert not any("print(1)" == c.source for c in nb.cells)
    assert len({c.id for c in nb.cells}) == len(nb.cells)


def test_build_skips_cells_and_survives_garbage_cells():
    sol = solution()
    student = json.loads(json.dumps(sol))
    student["cells"].insert(0, "not a cell")
    student["cells"][1]["id"] = "bad id with spaces"
    nb = g.build_graded_notebook(student, sol, b"k" * 32, "tiny", skip={MEAN})
    assert by_id(nb, MEAN).metadata["tags"] == ["nbval-skip"]
    nbformat.validate(nb)


def test_results_with_a_bad_signature_are_ignored(tmp_path):
    from robotlib.course._nbval_plugin import sign

    key = b"s" * 32
    good = {"event": "cell", "id": "a", "status": "failed"}
    forged = {"event": "cell", "id": "b", "status": "passed"}
    lines = [
        json.dumps({**good, "mac": sign(key, good)}),
        json.dumps({**forged, "mac": sign(b"x" * 32, forged)}),
        "not json",
    ]
    path = tmp_path / "r.jsonl"
    path.write_text("\n".join(lines))
    records, tampered = g._read_results(path, key)
    assert records == [good] and tampered


def test_find_submissions_layouts(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "tiny.ipynb").write_text("{}")
    (tmp_path / "b" / "tiny").mkdir(parents=True)
    (tmp_path / "b" / "tiny" / "tiny.ipynb").write_text("{}")
    (tmp_path / "c").mkdir()
    (tmp_path / "c" / "whatever.ipynb").write_text("{}")
    (tmp_path / "d.ipynb").write_text("{}")
    (tmp_path / "e").mkdir()
    found = dict(g.find_submissions(tmp_path, "tiny"))
    assert found["a"].name == "tiny.ipynb" and found["b"].parent.name == "tiny"
    assert found["c"].name == "whatever.ipynb" and found["d"].name == "d.ipynb"
    assert found["e"] is None


def test_solution_that_fails_its_checks_is_refused(tmp_path):
    sol = solution()
    set_source(sol, ADD, "def add(a, b):\n    return a * b")
    path = tmp_path / "tiny.ipynb"
    write_notebook(sol, path)
    (tmp_path / "subs").mkdir()
    with pytest.raises(g.GradeError, match="add"):
        g.grade(tmp_path / "subs", "tiny", path, jobs=1, progress=False,
                opts=g.GradeOptions(cell_timeout=CELL_TIMEOUT, timeout=60))  # fmt: skip
