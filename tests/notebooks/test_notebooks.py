"""Every solution notebook executes headless under nbval (Agg, seeded).

Each notebook runs in its own pytest process (as the grader does), so a
notebook's kernel never shares state with the test session. Where the
real-browser test can run (CI: ``ROBOTLIB_BROWSER_TEST=1``), it runs every
solution and released lab in a kernel of its own and checks the same things
(no error, nothing compiled after ``robotlib warmup``), so the nbval run is
skipped there rather than run a second time; the sandboxed grading
(tests/course/test_course_labs.py) runs each solution too.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.browser import have_browser

pytestmark = pytest.mark.slow  # every solution notebook run whole under nbval

ROOT = Path(__file__).resolve().parents[2]
SOLUTIONS = sorted((ROOT / "solutions").glob("*.ipynb"))
LIMIT = 60.0  # seconds per notebook on 2 cores (the budget)


@pytest.mark.skipif(have_browser(), reason="the real-browser test runs each solution")
@pytest.mark.parametrize("notebook", SOLUTIONS, ids=[p.stem for p in SOLUTIONS])
def test_solution_notebook_runs(notebook, tmp_path, warm):
    """It runs, and nothing compiles in it after ``robotlib warmup``."""
    compiled = tmp_path / "compiled.txt"
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTEST_DISABLE_PLUGIN_AUTOLOAD": "1",
           "ROBOTLIB_COMPILE_LOG": str(compiled)}  # fmt: skip
    (tmp_path / "pytest.ini").write_text("[pytest]\n")
    cmd = [
        sys.executable, "-m", "pytest", "-p", "nbval.plugin", "-p", "no:cacheprovider",
        "--nbval-lax", "--nbval-current-env", f"--nbval-cell-timeout={LIMIT:g}",
        "-c", str(tmp_path / "pytest.ini"), f"--rootdir={tmp_path}", "-q",
        str(notebook),
    ]  # fmt: skip
    t0 = time.monotonic()
    proc = subprocess.run(
        cmd, env=env, cwd=tmp_path, capture_output=True, text=True, timeout=3 * LIMIT
    )
    elapsed = time.monotonic() - t0
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-2000:]
    late = compiled.read_text().split() if compiled.exists() else []
    assert not late, f"compiled after robotlib warmup: {sorted(set(late))}"
    print(f"{notebook.name}: {elapsed:.1f} s")


def test_every_lab_has_a_solution():
    labs = {p.name for p in (ROOT / "labs").glob("*.ipynb")}
    assert labs == {p.name for p in SOLUTIONS}
