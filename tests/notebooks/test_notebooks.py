"""Every solution notebook executes headless under nbval (Agg, seeded) in CI.

Each notebook runs in its own pytest process (as the grader does), so a
notebook's kernel never shares state with the test session.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow  # every solution notebook run whole under nbval

ROOT = Path(__file__).resolve().parents[2]
SOLUTIONS = sorted((ROOT / "solutions").glob("*.ipynb"))
LIMIT = 60.0  # seconds per notebook on 2 cores (the budget)


@pytest.mark.parametrize("notebook", SOLUTIONS, ids=[p.stem for p in SOLUTIONS])
def test_solution_notebook_runs(notebook, tmp_path):
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTEST_DISABLE_PLUGIN_AUTOLOAD": "1"}
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
    print(f"{notebook.name}: {elapsed:.1f} s")


def test_every_lab_has_a_solution():
    labs = {p.name for p in (ROOT / "labs").glob("*.ipynb")}
    assert labs == {p.name for p in SOLUTIONS}
