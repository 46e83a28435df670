"""SIGTERM to pytest (a CI runner's stop) ends the whole run and leaves nothing behind.

A session runs in a child pytest with this suite's hooks (`tests.conftest`)
and two test files of its own: one with background work (a long process
started by `tests.background.run`), one whose first test waits in the
foreground (asleep, or in a grading of the tiny lab) and whose second test
must never run. SIGTERM comes while the first one waits. The child must exit
as after Ctrl-C (status 2), its background process and its grading's
sandboxes must be gone (the test adopts whatever escapes: `orphans_adopted`)
and so must its ``robotlib-bg-*`` folder.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.sandboxing import need_sandbox, orphans_adopted, procs_with

ROOT = Path(__file__).resolve().parents[2]

BACKGROUND = """
import sys
from pathlib import Path

from tests import background


def background_work(folder):
    Path({out!r}, "background-folder").write_text(str(folder))
    cmd = [sys.executable, "-c", "import time; time.sleep(600)", {mark!r}]
    return background.run(cmd, timeout=900)


def test_background_ran():
    pass
"""

SLEEPING = """
import time
from pathlib import Path


def test_waits():
    Path({out!r}, "started").write_text("")
    time.sleep(600)


def test_after():
    Path({out!r}, "after").write_text("")
"""

GRADING = """
from pathlib import Path

from robotlib.course import grade as g
from robotlib.course.notebooks import write_notebook
from tests.course.test_course_grade import MEAN, TINY, solution, with_cell


def test_waits(tmp_path):
    loop = "def mean(xs):\\n    while True:\\n        pass"
    for name in ("a", "b"):
        (tmp_path / name).mkdir()
        nb = with_cell(solution(), MEAN, loop)
        write_notebook(nb, tmp_path / name / "tiny.ipynb")
    Path({out!r}, "started").write_text("")
    opts = g.Options(cell_timeout=300, timeout=600)
    g.grade(tmp_path, "tiny", TINY, jobs=2, opts=opts, progress=False)


def test_after():
    Path({out!r}, "after").write_text("")
"""


def _wait_for(condition, limit: float = 300.0) -> None:
    t0 = time.monotonic()
    while not condition():
        assert time.monotonic() - t0 < limit, "the child session never got there"
        time.sleep(0.2)


@pytest.mark.slow
@pytest.mark.parametrize("waiting", ["sleeping", "grading"])
def test_sigterm_ends_the_run_and_leaves_nothing(tmp_path, waiting):
    if waiting == "grading":
        need_sandbox()
    mark = f"robotlib-sigterm-test-{os.getpid()}-{waiting}"
    out, tmp = tmp_path / "out", tmp_path / "tmp"
    out.mkdir()
    tmp.mkdir()
    code = {"sleeping": SLEEPING, "grading": GRADING}[waiting]
    (tmp_path / "test_a_background.py").write_text(
        BACKGROUND.format(out=str(out), mark=mark)
    )
    (tmp_path / "test_b_foreground.py").write_text(code.format(out=str(out)))
    (tmp_path / "pytest.ini").write_text("[pytest]\n")
    cmd = [
        sys.executable, "-m", "pytest", "-q", "-p", "tests.conftest",
        "-p", "no:cacheprovider", "-c", tmp_path / "pytest.ini",
        f"--rootdir={tmp_path}", "--basetemp", tmp_path / "base",
        tmp_path / "test_a_background.py", tmp_path / "test_b_foreground.py",
    ]  # fmt: skip
    with orphans_adopted():
        _stop(tmp_path, cmd, mark, out, tmp, waiting)


def _stop(tmp_path, cmd, mark, out, tmp, waiting):
    """Run the child session, SIGTERM it while it waits, check what is left."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "TMPDIR": str(tmp)}
    child = subprocess.Popen(
        [str(c) for c in cmd], cwd=tmp_path, env=env, stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT, text=True,
    )  # fmt: skip
    try:
        _wait_for(lambda: (out / "started").exists() and procs_with(mark.encode()))
        if waiting == "grading":  # both submissions are running
            worker = b"robotlib.course.worker"
            _wait_for(lambda: len(procs_with(worker, below=child.pid)) >= 2)
        folder = Path((out / "background-folder").read_text())
        assert folder.is_dir() and folder.is_relative_to(tmp)
        child.send_signal(signal.SIGTERM)
        report, _ = child.communicate(timeout=120)
    finally:
        if child.poll() is None:
            child.kill()
            child.communicate()
    assert child.returncode == 2, report  # pytest's "interrupted"
    assert not (out / "after").exists(), report
    assert not folder.exists()
    assert list(tmp.glob("robotlib-bg-*")) == []
    time.sleep(0.5)
    assert procs_with(mark.encode()) == []
    assert procs_with(b"robotlib.course.worker") == []
