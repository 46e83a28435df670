"""What a student sees in an unsolved lab after Run All, read from its outputs.

Shared by `tests.notebooks.test_unsolved_labs` (headless) and the
real-browser test (the notebook JupyterLab saved): only cells that fail
until solved (tagged ``raises-exception`` by the release, so Run All goes
past them) show an error, and that error is the short "not done yet"
message, never a ``NameError``; a cell that draws (by its source) shows a
figure, a widget or HTML, or says in one line which of the student's code it
needs (``with robotlib.notebook.demo():``).
"""

from __future__ import annotations

import re

NEEDS = "This demonstration needs"
DRAWS = re.compile(r"plt\.subplots|Figure\(|Panel\(|interact\(|animate\(|plt\.show\(")
SHOWN = ("image/png", "application/vnd.jupyter.widget-view+json", "text/html")
SHORT = 4  # lines of an unsolved exercise's error: the message, no traceback


def _text(value) -> str:
    return "".join(value) if isinstance(value, list) else str(value or "")


def _plain(text: str) -> str:
    return re.sub(r"\x1b\[[0-9;]*m", "", text)


def unsolved_problems(cells: list) -> list[str]:
    """Return what is wrong in an unsolved lab's executed code cells (empty: nothing).

    Parameters
    ----------
    cells : list of dict
        The notebook's cells, with their outputs.
    """
    found = []
    for i, cell in enumerate(cells):
        if cell.get("cell_type") != "code":
            continue
        source = _text(cell.get("source"))
        where = f"cell {i} ({source.splitlines()[0][:40] if source else ''!r})"
        outputs = cell.get("outputs", [])
        errors = [o for o in outputs if o.get("output_type") == "error"]
        for e in errors:
            lines = _plain("\n".join(e.get("traceback", []))).splitlines()
            plain = "is not done yet" in "\n".join(lines) and len(lines) <= SHORT
            if not plain or e.get("ename") == "NameError":  # reads as a typo
                found.append(f"{where}: {e.get('ename')} ({len(lines)} lines)")
        tags = cell.get("metadata", {}).get("tags", [])
        if errors and "raises-exception" not in tags:
            found.append(f"{where} fails: Run All in JupyterLab stops there")
        if errors or not DRAWS.search(source):
            continue
        said = "".join(_text(o.get("text")) for o in outputs)
        shown = any(k in o.get("data", {}) for o in outputs for k in SHOWN)
        if not shown and NEEDS not in said:
            found.append(f"{where} draws nothing and says nothing")
    return found
