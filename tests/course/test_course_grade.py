# ruff: noqa: E501
"""Grading end to end on a tiny lab, in the sandbox, against adversarial submissions.

One grading run (the CLI, two at a time, started with the session beside
the other tests: `tests.background`; this module's tests run last) covers
the classes of attack of issue 12: answers reached through the library (alias, string,
run-time lookup), forged or edited checks, patched builtins and modules,
secrets and other students' files, processes that outlive their kernel
(setsid, double fork, a cleaned environment), signals, memory, disk and
process exhaustion, hangs inside numba, ``os._exit``, and ordinary mess
(two notebooks, nested folders, non-UTF-8 and look-alike names). A second
run resumes (nothing re-graded) and folds in the written answers' scores.
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
from robotlib.course.notebooks import read_notebook, release_notebook, write_notebook
from tests import background, contention
from tests.references import records_of, shared
from tests.sandboxing import (
    left_behind,
    need_sandbox,
    procs_with,
    run_adopting,
)

ROOT = Path(__file__).resolve().parents[2]
DATA = Path(__file__).parents[1] / "data" / "course"
TINY = DATA / "tiny.ipynb"
CELL_TIMEOUT = 4.0
ADD, ADD_CHECK, MEAN, MEAN_CHECK, SCALE, SCALE_CHECK, WHY = (
    "tiny-03",
    "tiny-04",
    "tiny-06",
    "tiny-07",
    "tiny-09",
    "tiny-10",
    "tiny-08",
)
FULL = {"add": 1, "mean": 2, "scale": 1}


def solution():
    return read_notebook(TINY)


def by_id(nb, cid):
    return next(c for c in nb.cells if c.id == cid)


def with_cell(nb, cid, source):
    nb = copy.deepcopy(nb)
    by_id(nb, cid).source = source
    return nb


def make_submissions(folder: Path, outside: Path) -> dict[str, dict]:
    """Write the submissions; return student -> expected points per check."""
    sol = solution()
    released = release_notebook(sol, "tiny")
    subs: dict[str, dict] = {}

    def put(name, nb, points, file="tiny.ipynb"):
        d = folder / name
        d.mkdir(parents=True, exist_ok=True)
        write_notebook(nb, d / file)
        subs[name] = {**FULL, **points}

    put("solution", sol, {})
    put("released", released, {"add": 0, "mean": 0, "scale": 0})
    put(
        "partial",
        with_cell(released, ADD, by_id(sol, ADD).source),
        {"mean": 0, "scale": 0},
    )

    # answers reached through the library: alias, string, run-time lookup
    put("alias", with_cell(sol, MEAN, "from numpy import mean as m\n\ndef mean(xs):\n    return float(m(xs))"), {"mean": 0})  # fmt: skip
    put("getattr_string", with_cell(sol, MEAN, "import numpy\nf = getattr(numpy, 'me' + 'an')\n\ndef mean(xs):\n    return float(f(xs))"), {"mean": 0})  # fmt: skip
    put("runtime_lookup", with_cell(sol, MEAN, "import numpy\nf = vars(numpy)[''.join(['me', 'an'])]\n\ndef mean(xs):\n    return float(f(xs))"), {"mean": 0})  # fmt: skip
    put("exec_string", with_cell(sol, MEAN, "exec('from numpy import mean as m')\n\ndef mean(xs):\n    return float(m(xs))"), {"mean": 0})  # fmt: skip
    # a listed function named in a cell the student added: the answer that
    # calls it is zeroed (the tripwire, while a check runs it); a cell that
    # only compares with it (refused, caught) costs nothing and is not flagged
    through = with_cell(sol, MEAN, "def mean(xs):\n    return float(m(xs))")
    through.cells.insert(2, nbformat.v4.new_code_cell("from numpy import mean as m"))
    put("added_import", through, {"mean": 0})
    compares = copy.deepcopy(sol)
    compares.cells.append(nbformat.v4.new_code_cell(
        "import numpy\ntry:\n    print(numpy.mean([1.0, 2.0]), mean([1.0, 2.0]))\n"
        "except Exception as exc:\n    print(exc)\n"
    ))  # fmt: skip
    put("compares", compares, {})

    # edited and deleted checks, forged tags, outputs and an extra check
    edited = with_cell(sol, ADD, "def add(a, b):\n    return a - b")
    by_id(edited, ADD_CHECK).source = "print('CHECK add', 5)"
    by_id(edited, ADD_CHECK).metadata["tags"] = ["raises-exception", "nbval-skip"]
    by_id(edited, ADD_CHECK).outputs = [
        nbformat.v4.new_output("stream", name="stdout", text="CHECK add 5\n")
    ]
    edited.cells = [c for c in edited.cells if c.id != MEAN_CHECK]
    extra = nbformat.v4.new_code_cell("print('bonus')")
    extra.metadata["robotlib"] = {"grade_id": "bonus", "points": 10}
    edited.cells.append(extra)
    put("edited_checks", edited, {"add": 0})

    # changing what the checks see: builtins, modules, printed lines, hooks
    put("patched", with_cell(sol, ADD, (
        "import builtins, sys, numpy as np\n"
        "builtins.print = lambda *a, **k: sys.__stdout__.write('CHECK add 5\\n')\n"
        "np.allclose = lambda *a, **k: True\nnp.isclose = np.allclose\n"
        "builtins.AssertionError = type('X', (Exception,), {})\n"
        "def add(a, b):\n    return 7")), {"add": 0})  # fmt: skip
    put(
        "constant_mean",
        with_cell(sol, MEAN, "def mean(xs):\n    return 2.5"),
        {"mean": 0},
    )
    put("eq_object", with_cell(sol, MEAN, (
        "class Always(float):\n    def __eq__(self, o):\n        return True\n"
        "    def __sub__(self, o):\n        return 0.0\n    __rsub__ = __sub__\n"
        "def mean(xs):\n    return Always(0)")), {"mean": 0})  # fmt: skip

    # reading what the grader keeps from students: the solution (by path and
    # through a symlink), another submission, the grader's records, the
    # check process or the grader in /proc, the grader's paths in the
    # environment. `mean` is right only if one of them was readable (so an
    # escape earns its points and fails test_points); the attack runs in a
    # cell the student added (flagged, never zeroed by the scan)
    root = folder.parent
    secrets = with_cell(sol, MEAN, "def mean(xs):\n    return sum(xs) / len(xs) if STOLEN or not DONE else 0.0")  # fmt: skip
    secrets.cells.insert(2, nbformat.v4.new_code_cell(
        "import os\nSTOLEN, TRIED, DONE = [], 0, False\n"
        f"for p in ({str(TINY)!r}, {str(folder / 'solution' / 'tiny.ipynb')!r}, {str(root / 'gradebook-records')!r}):\n"
        "    TRIED += 1\n    try:\n        STOLEN.append(os.listdir(p) if os.path.isdir(p) else open(p).read(9))\n"
        "    except OSError:\n        pass\n"
        "try:\n"
        f"    os.symlink({str(TINY)!r}, 'sol.ipynb')\n    STOLEN.append(open('sol.ipynb').read(9))\n"
        "except OSError:\n    pass\n"
        "for pid in (d for d in os.listdir('/proc') if d.isdigit()):\n"
        "    try:\n        cmd = open(f'/proc/{pid}/cmdline', 'rb').read()\n    except OSError:\n        continue\n"
        "    if b'worker\\x00check' in cmd or b'robotlib.cli' in cmd or b'pytest' in cmd:\n        STOLEN.append(cmd)\n"
        f"if {str(root)!r} in str(os.environ):\n    STOLEN.append('environment')\n"
        "DONE = TRIED == 3  # the attack ran to its end\n"
    ))  # fmt: skip
    put("secrets", secrets, {"mean": 0})

    # hooks that would change what a check sees, if checks ran beside them:
    # an import hook, numpy patched, IPython start-up and usercustomize files
    # in HOME and in the check process's scratch (not mounted here)
    hooked = with_cell(sol, SCALE, "def scale(xs, k):\n    return [0.0] * len(xs) if HOOKED else np.asarray(xs, float) * k")  # fmt: skip
    evil = "import numpy\nnumpy.allclose = lambda *a, **k: True\n"
    hooked.cells.insert(2, nbformat.v4.new_code_cell(
        "import os, sys, numpy\n"
        "class Hook:\n    def find_spec(self, name, path, target=None):\n        return None\n"
        "sys.meta_path.insert(0, Hook())\nnumpy.allclose = lambda *a, **k: True\n"
        "home = os.path.expanduser('~')\n"
        "for d in (home, os.path.join(os.getcwd(), '..', 'check1', 'home'), '/scratch/../check1/home'):\n"
        "    for sub, name in (('.ipython/profile_default/startup', '00-evil.py'), ('.local/lib/python%d.%d/site-packages' % sys.version_info[:2], 'usercustomize.py')):\n"
        "        try:\n            os.makedirs(os.path.join(d, sub), exist_ok=True)\n"
        f"            open(os.path.join(d, sub, name), 'w').write({evil!r})\n"
        "        except OSError:\n            pass\n"
        "HOOKED = True\n"
    ))  # fmt: skip
    put("hooked", hooked, {"scale": 0})

    # harming others: files, processes, signals, resources
    target = outside / "pwned"
    harmed = (target, TINY, Path(sys.prefix) / "pwned", ROOT / "robotlib" / "pwned",
              ROOT / "robotlib" / "localization" / "__pycache__" / "pwned",
              folder / "solution" / "tiny.ipynb", root / "gradebook-records" / "pwned.json")  # fmt: skip
    escape = copy.deepcopy(sol)  # in a cell the student added: flagged, not zeroed
    escape.cells.insert(2, nbformat.v4.new_code_cell(
        f"import os, signal, subprocess, time\n"
        f"for p in {tuple(str(h) for h in harmed)!r}:\n"
        "    try:\n        open(p, 'a').write('x')\n    except OSError:\n        pass\n"
        "subprocess.Popen(['setsid', 'sh', '-c', 'sleep 987'])\n"
        "subprocess.Popen(['env', '-i', 'sleep', '988'])\n"
        "if os.fork() == 0:\n    os.setsid()\n    if os.fork() == 0:\n"
        "        time.sleep(989)\n    os._exit(0)\n"
        "if os.fork() == 0:  # a process that keeps changing its pid\n"
        "    for _ in range(3000):\n        if os.fork():\n            os._exit(0)\n"
        "        time.sleep(0.05)\n    os._exit(0)\n"
        "for pid in range(1, 50):\n    try:\n        os.kill(pid, signal.SIGTERM)"
        " if pid != os.getpid() else None\n    except OSError:\n        pass\n"
    ))  # fmt: skip
    put("escape", escape, {})
    exhaust = with_cell(sol, ADD, by_id(sol, ADD).source + (
        "\ntry:\n    big = bytearray(40 << 30)\nexcept MemoryError:\n    pass\n"
        "try:\n    with open('big', 'wb') as f:\n        for _ in range(20):\n"
        "            f.write(bytes(16 << 20))\nexcept OSError:\n    pass\n"
    ))  # fmt: skip
    at = next(i for i, c in enumerate(exhaust.cells) if c.id == ADD) + 1
    exhaust.cells.insert(at, nbformat.v4.new_code_cell(  # an added cell: flagged only
        "import os, shutil\nkids, sleep = [], shutil.which('sleep')\n"
        "for _ in range(400):  # more processes than the limit allows (spawned\n"
        "    try:  # without copying the kernel: quick even on a busy machine)\n"
        "        kids.append(os.posix_spawn(sleep, ['sleep', '991'], {}))\n"
        "    except OSError:\n        break\n"
        "if not 50 < len(kids) < 400:  # the process limit did not hold: add fails\n"
        "    def add(a, b):\n        return 0\n"
    ))  # fmt: skip
    put("exhaust", exhaust, {})
    put("infinite_loop", with_cell(sol, MEAN, "def mean(xs):\n    while True:\n        pass"), {"mean": 0})  # fmt: skip
    put("njit_hang", with_cell(sol, MEAN, by_id(sol, MEAN).source + (
        "\nfrom numba import njit\n@njit\ndef spin(n):\n    i = 0\n"
        "    while i >= 0:\n        i = (i + n) % 1000003\n    return i\nspin(1)")), {"mean": 0})  # fmt: skip
    put("os_exit", with_cell(sol, SCALE, by_id(sol, SCALE).source + "\nimport os\nos._exit(3)"), {"scale": 0})  # fmt: skip
    crash_call = with_cell(sol, SCALE, "import os\ndef scale(xs, k):\n    os._exit(1)")
    put("exit_in_call", crash_call, {"scale": 0})

    # ordinary mess
    moved = copy.deepcopy(sol)  # a check cell copied above its exercise
    moved.cells.insert(2, copy.deepcopy(by_id(sol, MEAN_CHECK)))
    put("moved_check", moved, {}, file="tiny (1).ipynb")
    put("two_notebooks", sol, {k: 0 for k in FULL}, file="a.ipynb")
    write_notebook(released, folder / "two_notebooks" / "b.ipynb")
    (folder / "nested" / "section1").mkdir(parents=True)
    write_notebook(sol, folder / "nested" / "section1" / "tiny.ipynb")
    subs["nested"] = FULL
    put("Émile Zoë", sol, {})
    put("émile zoë", released, {k: 0 for k in FULL})
    put("Émile  Zoë", released, {k: 0 for k in FULL})  # differs by a space
    put("Émile Zoë ", copy.deepcopy(released), {k: 0 for k in FULL})
    (folder / "garbage.ipynb").write_text("{ this is not json")
    subs["garbage"] = {k: 0 for k in FULL}
    (folder / "nothing").mkdir()
    subs["nothing"] = {k: 0 for k in FULL}
    return subs


def _command(folder, out, *extra) -> list:
    return [sys.executable, "-m", "robotlib.cli", "grade", str(folder), "--lab", "tiny",
            "--solution", str(TINY), "--out", str(out), "--cell-timeout",
            str(CELL_TIMEOUT), "--timeout", "90", "--jobs", "2", "--quiet", *extra]  # fmt: skip


def _cli(folder, out, *extra):
    return contention.run(_command(folder, out, *extra), 600)  # quiet s


def background_work(root: Path):
    """Grade the class with the CLI beside the other tests (`tests.background`).

    Only when a selected test uses its gradebook (`graded`). The CLI runs in a
    process that adopts whatever escapes it and records what is left when the
    CLI has ended (`tests.sandboxing.run_adopting`).
    """
    if not any("graded" in it.fixturenames for it in background.selected(__name__)):
        return None
    need_sandbox()
    folder, outside = root / "subs", root / "outside"
    folder.mkdir()
    outside.mkdir()
    expected = make_submissions(folder, outside)
    out, report = root / "gradebook.csv", root / "left.json"
    with shared("tiny", TINY, records_of(out)):
        t0 = time.monotonic()
        proc = run_adopting(_command(folder, out), report, 600)  # quiet s
        elapsed = time.monotonic() - t0
    left = left_behind(report) if report.exists() else None
    return proc, expected, out, elapsed, root, folder, left


@pytest.fixture(scope="module")
def graded():
    proc, expected, out, elapsed, root, folder, left = background.result(__name__)
    assert proc.returncode == 0, proc.stderr
    assert left is not None, proc.stderr
    with open(out, newline="") as f:
        rows = {r["student"]: r for r in csv.DictReader(f)}
    return rows, expected, out, elapsed, root, folder, left


@pytest.mark.slow
def test_gradebook_columns(graded):
    rows, expected, out, *_ = graded
    header = out.read_text().splitlines()[0].split(",")
    assert header == [
        "student", "add", "mean", "scale", "why", "total", "max",
        "status", "seconds", "flags", "notes",
    ]  # fmt: skip
    assert set(rows) == set(expected)
    assert all(r["max"] == "5" for r in rows.values())


@pytest.mark.slow
def test_points(graded):
    rows, expected, *_ = graded
    wrong = {}
    for student, points in expected.items():
        got = {k: float(rows[student][k]) for k in points}
        if got != {k: float(v) for k, v in points.items()}:
            wrong[student] = (got, rows[student]["notes"])
    assert wrong == {}


@pytest.mark.slow
def test_cheats_are_zeroed_with_a_note_and_flagged(graded):
    rows = graded[0]
    for student in ("alias", "getattr_string", "runtime_lookup", "exec_string"):
        assert (
            "numpy.mean" in rows[student]["notes"] or "exec" in rows[student]["notes"]
        )
        assert "mean: zero:" in rows[student]["notes"], rows[student]["notes"]
        assert "answer reaches" in rows[student]["flags"]
    assert "called numpy.mean" in rows["runtime_lookup"]["notes"]  # the tripwire
    assert "mean: zero: called numpy.mean" in rows["added_import"]["notes"]
    assert "answer reaches" in rows["added_import"]["flags"]
    for honest in ("solution", "partial", "compares"):
        assert rows[honest]["flags"] == "", (honest, rows[honest]["flags"])


@pytest.mark.slow
def test_statuses_and_reasons(graded):
    rows = graded[0]
    assert "NotImplementedError" in rows["released"]["notes"]
    assert "timed out" in rows["infinite_loop"]["notes"]
    assert rows["garbage"]["status"] == "unreadable notebook"
    assert rows["nothing"]["status"] == "no notebook"
    assert rows["two_notebooks"]["status"].startswith("several notebooks")
    assert "restarted" in rows["os_exit"]["status"]
    assert "wrong result: expected" in rows["constant_mean"]["notes"]
    assert "assertion failed" in rows["patched"]["notes"]
    assert "reads notebooks" in rows["escape"]["flags"]
    assert "processes at once (the limit is 256)" in rows["exhaust"]["flags"]


@pytest.mark.slow
def test_nobody_was_harmed(graded):
    root, folder = graded[4], graded[5]
    for p in (root / "outside" / "pwned", Path(sys.prefix, "pwned"),
              ROOT / "robotlib" / "pwned", ROOT / "robotlib" / "localization" / "__pycache__" / "pwned",
              root / "gradebook-records" / "pwned.json"):  # fmt: skip
        assert not p.exists(), p
    assert "x" not in TINY.read_text()[-5:]
    assert "x" not in (folder / "solution" / "tiny.ipynb").read_text()[-5:]
    needles = (b"sleep\x00987", b"sleep\x00988", b"989", b"sleep\x00991", b"robotlib.course.worker")  # fmt: skip
    for needle in needles:  # below the grading's own process when it had ended
        assert [c for c in graded[6] if needle in c] == [], needle


@pytest.mark.slow
def test_secrets_and_hooks_stay_out(graded):
    rows = graded[0]
    # the attack ran to its end and found nothing: `mean` returned 0.0 (had it
    # stopped half-way or found anything, `mean` would be right)
    assert "mean: an assertion failed" in rows["secrets"]["notes"], rows["secrets"][
        "notes"
    ]
    assert "reads notebooks" in rows["secrets"]["flags"]
    assert rows["secrets"]["add"] == "1" and rows["secrets"]["scale"] == "1"
    # numpy patched, an import hook and start-up files: the check still fails
    assert "scale: " in rows["hooked"]["notes"], rows["hooked"]["notes"]
    assert rows["hooked"]["add"] == "1" and rows["hooked"]["mean"] == "2"


@pytest.mark.slow
def test_feedback_teaches_and_never_collides(graded):
    out = graded[2]
    fb = out.with_name("gradebook-feedback")
    files = list(fb.glob("*.md"))
    assert len(files) == len(graded[1])  # the two look-alike names: two files
    partial = next(f for f in files if f.name.startswith("partial")).read_text()
    assert "1 / 5" in partial and "NotImplementedError" in partial
    assert "cell tiny-06" in partial  # the student's own frame, no library frames
    const = next(f for f in files if f.name.startswith("constant_mean")).read_text()
    assert "expected 'CHECK mean 2.333333', got 'CHECK mean 2.5'" in const


@pytest.mark.slow
def test_records_resume_and_manual_scores(graded):
    rows, expected, out, _, root, folder, _ = graded
    manual = out.with_name("gradebook-manual.csv")
    with open(manual, newline="") as f:
        answers = list(csv.DictReader(f))
    assert {a["student"] for a in answers} >= {"solution", "released"}
    sol = next(a for a in answers if a["student"] == "solution")
    assert "Vectorised" in sol["answer"] and sol["rubric"]
    for a in answers:
        a["score"] = "1" if a["student"] == "solution" else ""
    with open(manual, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(answers[0]))
        w.writeheader()
        w.writerows(answers)
    t0 = time.monotonic()
    proc = _cli(folder, out, "--manual", str(manual))
    assert proc.returncode == 0, proc.stderr
    said = proc.stderr  # nothing graded is not "graded 17"
    assert "graded 0 submissions" in said and "kept from earlier runs" in said, said
    with open(out, newline="") as f:
        again = {r["student"]: r for r in csv.DictReader(f)}
    assert again["solution"]["total"] == "5" and again["solution"]["why"] == "1"
    # nothing was graded again: same seconds, and faster than one submission
    assert again["partial"]["seconds"] == rows["partial"]["seconds"]
    records = json.loads(
        next(out.with_name("gradebook-records").glob("partial-*.json")).read_text()
    )
    assert records["points"]["add"] == 1.0
    assert time.monotonic() - t0 < graded[3]


@pytest.mark.slow
def test_gradebook_reports_each_submissions_time(graded):
    rows, _, _, elapsed, *_ = graded
    seconds = {student: float(r["seconds"]) for student, r in rows.items()}
    for student in ("garbage", "nothing", "two_notebooks"):  # nothing was run
        assert seconds[student] == 0.0, student
    graded_ones = {s: t for s, t in seconds.items() if rows[s]["status"] == "ok"}
    assert len(graded_ones) > 15 and min(graded_ones.values()) > 0.0
    for student in ("infinite_loop", "njit_hang"):  # each waited a cell's timeout
        assert seconds[student] >= CELL_TIMEOUT, (student, seconds[student])
    # wall-clock time of two at a time (--jobs 2): no more than the run took
    assert sum(seconds.values()) <= 2 * elapsed + 0.05 * len(seconds)


@pytest.mark.slow
@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
def test_interrupt_leaves_no_process(tmp_path, sig, adopting):
    """Ctrl-C (SIGINT) or SIGTERM in the middle of a class: no process is left."""
    import signal

    need_sandbox()
    folder = tmp_path / "subs"
    for i in range(3):
        d = folder / f"s{i}"
        d.mkdir(parents=True)
        write_notebook(
            with_cell(solution(), MEAN, "def mean(xs):\n    while True:\n        pass"),
            d / "tiny.ipynb",
        )
    cmd = [sys.executable, "-m", "robotlib.cli", "grade", str(folder), "--lab",
           "tiny", "--solution", str(TINY), "--out", str(tmp_path / "gb.csv"),
           "--cell-timeout", "30", "--jobs", "2", "--quiet"]  # fmt: skip
    # Ctrl-C's default action in the CLI even when this run inherited SIGINT
    # ignored (a job started in the background by a shell without job control):
    # Python keeps an ignored SIGINT ignored, and the CLI would never see it
    with shared("tiny", TINY, records_of(tmp_path / "gb.csv")):
        proc = subprocess.Popen(
            cmd,
            stderr=subprocess.PIPE,
            text=True,
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )
        deadline = time.monotonic() + 120
        while (
            time.monotonic() < deadline
            and len(procs_with(b"robotlib.course.worker", below=proc.pid)) < 3
        ):
            time.sleep(0.2)
        time.sleep(1.0)
        proc.send_signal(getattr(signal, sig))  # in the middle of the class
        proc.wait(timeout=60)
    assert proc.returncode == 130, proc.stderr.read()
    time.sleep(0.5)
    assert procs_with(b"robotlib.course.worker") == []


# -- unit tests ---------------------------------------------------------------------


def test_find_submissions_layouts(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "tiny.ipynb").write_text("{}")
    (tmp_path / "b" / "tiny").mkdir(parents=True)
    (tmp_path / "b" / "tiny" / "tiny.ipynb").write_text("{}")
    (tmp_path / "c").mkdir()
    (tmp_path / "c" / "tiny (1).ipynb").write_text("{}")
    (tmp_path / "d.ipynb").write_text("{}")
    (tmp_path / "e").mkdir()
    (tmp_path / "f").mkdir()
    (tmp_path / "f" / "x.ipynb").write_text("{}")
    (tmp_path / "f" / "y.ipynb").write_text("{}")
    (tmp_path / os.fsdecode(b"g\xff")).mkdir()
    (tmp_path / os.fsdecode(b"g\xff") / "tiny.ipynb").write_text("{}")
    # answers through symlinks: a folder linked to the solutions, a linked notebook
    (tmp_path / "h").symlink_to(DATA, target_is_directory=True)
    (tmp_path / "i").mkdir()
    (tmp_path / "i" / "tiny.ipynb").symlink_to(TINY)
    (tmp_path / "j.ipynb").symlink_to(TINY)
    found = {s: (p, st) for s, p, st in g.find_submissions(tmp_path, "tiny")}
    assert found["h"] == (None, "a symbolic link, not graded")
    assert found["j"] == (None, "a symbolic link, not graded")
    assert found["i"] == (None, "no notebook")
    assert found["a"][0].name == "tiny.ipynb" and found["b"][0].parent.name == "tiny"
    assert found["c"][0].name == "tiny (1).ipynb" and found["d"][0].name == "d.ipynb"
    assert found["e"] == (None, "no notebook")
    assert found["f"][0] is None and found["f"][1].startswith("several notebooks")
    assert any(s.startswith("g") and p is not None for s, (p, _) in found.items())


def test_safe_loads_refuses_callables():
    import pickle

    from robotlib.course.worker import safe_loads

    assert safe_loads(pickle.dumps((1, [2.0], {"a": "b"}))) == (1, [2.0], {"a": "b"})
    for evil in (os.system, print, g.grade):
        with pytest.raises(pickle.UnpicklingError):
            safe_loads(pickle.dumps(evil))


def test_notes_name_the_function_the_exercise_lists_and_the_alias():
    """Lab 5 lists one function under two names, one per exercise.

    ``sonar_map`` lists ``robotlib.mapping.inverse_sonar_model``,
    ``inverse_sonar`` lists ``robotlib.mapping.occupancy.inverse_sonar_model``
    (the same object). A note names the exercise's own listing and the alias
    the answer came through, statically and at run time.
    """
    from robotlib.course.plan import lab_plan, scan_submission

    root = Path(__file__).resolve().parents[2]
    plan = lab_plan(read_notebook(root / "solutions" / "lab5_slam.ipynb"), "lab5_slam")
    pkg, occ = "robotlib.mapping.inverse_sonar_model", "robotlib.mapping.occupancy.inverse_sonar_model"  # fmt: skip
    cells = [
        {"id": "a", "exercise": "sonar_map", "source": "from robotlib.mapping.occupancy import inverse_sonar_model as f"},
        {"id": "b", "exercise": "inverse_sonar", "source": "import robotlib.mapping as m\ng = m.inverse_sonar_model"},
        {"id": "c", "exercise": "sonar_map", "source": f"from {pkg.rsplit('.', 1)[0]} import inverse_sonar_model"},
    ]  # fmt: skip
    zero, flags = scan_submission(plan, cells)
    assert zero["sonar_map"] == [
        f"reaches {pkg} (imported as f, through {occ}), the exercise's own work",
        f"reaches {pkg} (imported), the exercise's own work",
    ]
    assert zero["inverse_sonar"] == [
        f"reaches {occ} (attribute, through {pkg}), the exercise's own work"
    ]
    assert plan.listed_as(occ, "sonar_map") == pkg
    assert plan.listed_as(pkg, "inverse_sonar") == occ
    assert plan.listed_as(pkg, None) == pkg
    # the run-time tripwire reports the listed name and the place it was reached
    code = (
        "import robotlib.mapping, robotlib.mapping.occupancy as o\n"
        "from robotlib.course import tripwires\n"
        "hits = []\n"
        f"tripwires.arm({[occ, pkg]!r}, lambda f, via: hits.append((f, via)))\n"
        "for fn in (robotlib.mapping.inverse_sonar_model, o.inverse_sonar_model):\n"
        "    try:\n        fn()\n    except tripwires.Tripwire:\n        pass\n"
        "print(hits)\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    hits = eval(proc.stdout.strip().splitlines()[-1])  # noqa: S307 - our own output
    assert hits == [(occ, pkg), (occ, occ)]
    assert {plan.listed_as(f, "sonar_map") for f, _ in hits} == {pkg}


@pytest.mark.slow
def test_slow_setup_on_a_cold_cache_does_not_zero_correct_work(tmp_path):
    """A set-up cell slower than the cell limit, compiling numba cold, costs no points.

    The set-up cell compiles an ``@njit(cache=True)`` function defined in the
    notebook (cold in every sandbox: each process has its own cache folder)
    and then takes longer than ``--cell-timeout``; the set-up is not a
    student cell, so the solution still scores full marks and the released
    lab zero.
    """
    need_sandbox()
    sol = solution()
    by_id(sol, "tiny-01").source = (
        "import time\n\nimport numpy as np\nfrom numba import njit\n\n\n"
        "@njit(cache=True)\ndef warm(x):\n    return x + 1\n\n\n"
        f"warm(1)\ntime.sleep({CELL_TIMEOUT + 2})\n"
    )
    write_notebook(sol, tmp_path / "tiny.ipynb")
    for name, nb in (("sol", sol), ("rel", release_notebook(sol, "tiny"))):
        (tmp_path / "subs" / name).mkdir(parents=True)
        write_notebook(nb, tmp_path / "subs" / name / "tiny.ipynb")
    opts = g.Options(cell_timeout=CELL_TIMEOUT, timeout=120)
    results, _ = g.grade(tmp_path / "subs", "tiny", tmp_path / "tiny.ipynb", jobs=2, opts=opts, progress=False)  # fmt: skip
    rows = {r.student: r for r in results}
    got = {k: rows["sol"].points[k] for k in FULL}  # "why" is graded by hand
    assert got == {k: float(v) for k, v in FULL.items()}, rows["sol"].reasons
    assert rows["sol"].status == "ok", rows["sol"].status
    assert all(v == 0 for v in rows["rel"].points.values()), rows["rel"].points


@pytest.mark.slow
def test_a_submission_out_of_restarts_is_graded_not_a_grader_error(tmp_path):
    """Hanging more often than ``--restarts`` allows ends in zeros with reasons.

    With no restart left, the hung cell's timer and the killed process's
    end-of-file both used to reach the grader again, which then called a
    process it had already dropped: the submission got "grader error".
    """
    need_sandbox()
    hang = with_cell(
        solution(), MEAN, "def mean(xs):\n    pass\n\n\nwhile True:\n    pass"
    )
    (tmp_path / "subs" / "hang").mkdir(parents=True)
    write_notebook(hang, tmp_path / "subs" / "hang" / "tiny.ipynb")
    opts = g.Options(cell_timeout=CELL_TIMEOUT, timeout=120, restarts=0)
    records = tmp_path / "records"
    with shared("tiny", TINY, records):
        results, _ = g.grade(tmp_path / "subs", "tiny", TINY, jobs=1, opts=opts,
                             progress=False, records=records)  # fmt: skip
    (r,) = results
    assert not r.status.startswith("grader error"), r.status
    assert r.points["mean"] == 0 and r.points["scale"] == 0, r.points
    assert "hanging or crashing" in r.reasons["scale"], r.reasons


@pytest.mark.slow
def test_a_process_that_cannot_start_is_restarted(tmp_path, monkeypatch):
    """The system refusing a process (out of pids) is a restart, not a grader error."""
    import errno

    from robotlib.course import processes

    need_sandbox()
    (tmp_path / "subs" / "sol").mkdir(parents=True)
    write_notebook(solution(), tmp_path / "subs" / "sol" / "tiny.ipynb")
    real, students = processes.subprocess.Popen, []

    def popen(cmd, *args, **kwargs):
        if "student" in cmd:
            students.append(cmd)
            if len(students) == 2:  # the submission's first (the reference ran one)
                raise OSError(errno.EAGAIN, "Resource temporarily unavailable")
        return real(cmd, *args, **kwargs)

    monkeypatch.setattr(processes.subprocess, "Popen", popen)
    opts = g.Options(cell_timeout=CELL_TIMEOUT, timeout=120)
    results, _ = g.grade(tmp_path / "subs", "tiny", TINY, jobs=1, opts=opts, progress=False)  # fmt: skip
    (r,) = results
    assert len(students) == 3, len(students)
    assert r.status.startswith("restarted"), r.status
    assert {k: r.points[k] for k in FULL} == {k: float(v) for k, v in FULL.items()}, (
        r.reasons
    )
