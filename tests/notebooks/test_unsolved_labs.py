"""Every released lab, unsolved, run top to bottom as a student's Run All would.

A student who has done no exercise yet should still see every
demonstration: one that needs no student code draws, one that does says in
one line what it needs (``with robotlib.notebook.demo():``), and only the
cells that fail until solved (graded checks, a stub outside a function:
tagged ``raises-exception`` by the release, so JupyterLab's Run All goes
past them) show an error, the short "not done yet" message. Labs are found
by glob, so a new lab is covered as it lands.
"""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

pytestmark = pytest.mark.slow  # each lab run whole (5-70 s)

ROOT = Path(__file__).resolve().parents[2]
LABS = sorted((ROOT / "labs").glob("*.ipynb"))
NEEDS = "This demonstration needs"
DRAWS = re.compile(r"plt\.subplots|Figure\(|Panel\(|interact\(|animate\(|plt\.show\(")
SHOWN = ("image/png", "application/vnd.jupyter.widget-view+json", "text/html")
SHORT = 4  # lines of an unsolved exercise's error: the message, no traceback


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


def _plain(text: str) -> str:
    return re.sub(r"\x1b\[[0-9;]*m", "", text)


@pytest.mark.parametrize("lab", LABS, ids=[p.stem for p in LABS])
def test_an_unsolved_lab_shows_every_demonstration(lab, tmp_path):
    book = _run(lab, tmp_path)
    found = []
    for i, cell in enumerate(book.cells):
        if cell.cell_type != "code":
            continue
        where = f"cell {i} ({cell.source.splitlines()[0][:40]!r})"
        tags = cell.metadata.get("tags", [])
        errors = [o for o in cell.outputs if o.output_type == "error"]
        for e in errors:
            text = _plain("\n".join(e.traceback))
            if "is not done yet" not in text or len(text.splitlines()) > SHORT:
                found.append(f"{where}: {e.ename} ({len(text.splitlines())} lines)")
        if errors and "raises-exception" not in tags:
            found.append(f"{where} fails: Run All in JupyterLab would stop there")
        if errors or not DRAWS.search(cell.source):
            continue
        said = "".join(o.get("text", "") for o in cell.outputs)
        shown = any(k in o.get("data", {}) for o in cell.outputs for k in SHOWN)
        if not shown and NEEDS not in said:
            found.append(f"{where} draws nothing and says nothing")
    assert not found, "\n".join(found)
