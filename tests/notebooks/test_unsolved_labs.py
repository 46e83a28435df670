"""Every released lab, unsolved, run top to bottom as a student's Run All would.

A student who has done no exercise yet should still see every
demonstration: one that needs no student code draws, one that does says in
one line what it needs (``with robotlib.notebook.demo():``), and only the
cells that fail until solved show an error, the short "not done yet"
message (`tests.student_view`). Labs are found by glob, so a new lab is
covered as it lands. Where the real-browser test can run, it checks the
same on the notebooks JupyterLab ran, and this headless run is skipped.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

from tests.browser import have_browser
from tests.student_view import unsolved_problems

pytestmark = pytest.mark.slow  # each lab run whole (5-70 s)

ROOT = Path(__file__).resolve().parents[2]
LABS = sorted((ROOT / "labs").glob("*.ipynb"))


def _run(lab: Path, tmp_path: Path) -> nbformat.NotebookNode:
    shutil.copy(lab, tmp_path)  # the message reads its exercise from the file
    book = nbformat.read(tmp_path / lab.name, as_version=4)
    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}  # inline
    client = NotebookClient(
        book, timeout=300, allow_errors=True, kernel_name="python3",
        resources={"metadata": {"path": str(tmp_path)}},
    )  # fmt: skip
    client.km = client.create_kernel_manager()
    client.start_new_kernel(env=env)
    client.execute(reset_kc=False, cleanup_kc=True)
    return book


@pytest.mark.skipif(have_browser(), reason="the real-browser test runs each lab")
@pytest.mark.parametrize("lab", LABS, ids=[p.stem for p in LABS])
def test_an_unsolved_lab_shows_every_demonstration(lab, tmp_path, warm):
    found = unsolved_problems(_run(lab, tmp_path).cells)
    assert not found, "\n".join(found)
