"""Marking graded check cells in lab sources: `check_header`, `mark_checks`, `main`.

Every automatically graded check cell of a lab (code cell with
``{"robotlib": {"grade_id": ..., "points": P}}`` metadata, not ``manual``)
opens with the line ``# CHECK (graded, P points): ...`` and carries the cell
tag ``graded`` (JupyterLab shows tags), so a student sees which cells grade
the work. ``python -m robotlib.course.marking solutions/*.ipynb`` adds both
where missing and corrects a header whose points disagree with the metadata;
it changes nothing else in the file (the JSON layout is kept), so it can be
re-run after a merge. ``robotlib release`` then carries both to ``labs/``.

Imports only the standard library; nothing of robotlib imports it but tests.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

__all__ = ["HEADER_RE", "check_header", "mark_checks", "unmarked", "main"]

META_KEY = "robotlib"
TAG = "graded"
HEADER_RE = re.compile(r"^# CHECK \(graded, (\d+(?:\.\d+)?) points?\)")
"""A check cell's first line; the group is its points."""


def check_header(points) -> str:
    """Return a check cell's first line for ``points`` points."""
    p = f"{points:g}" if isinstance(points, float) else str(points)
    unit = "point" if p == "1" else "points"
    return (
        f"# CHECK (graded, {p} {unit}): "
        "run this cell to test your work; do not edit it."
    )


def _graded(cell: dict) -> dict | None:
    meta = cell.get("metadata", {}).get(META_KEY)
    if cell.get("cell_type") != "code" or not isinstance(meta, dict):
        return None
    if "grade_id" not in meta or meta.get("manual"):
        return None
    return meta


def _source(cell: dict) -> str:
    src = cell.get("source", "")
    return "".join(src) if isinstance(src, list) else src


def unmarked(nb: dict) -> list[str]:
    """Return what is missing in a notebook's graded check cells (empty: none).

    Parameters
    ----------
    nb : dict
        The notebook, as JSON.

    Returns
    -------
    list of str
        One line per problem, naming the cell's ``grade_id``.
    """
    out = []
    for cell in nb.get("cells", []):
        meta = _graded(cell)
        if meta is None:
            continue
        gid, first = meta["grade_id"], _source(cell).split("\n", 1)[0]
        m = HEADER_RE.match(first)
        if m is None:
            out.append(f"{gid}: no '# CHECK (graded, N points)' first line")
        elif float(m.group(1)) != float(meta.get("points", 0)):
            out.append(
                f"{gid}: header says {m.group(1)} points, metadata {meta['points']}"
            )
        if TAG not in cell.get("metadata", {}).get("tags", []):
            out.append(f"{gid}: no '{TAG}' tag")
    return out


def mark_checks(nb: dict) -> int:
    """Give every graded check cell its header line and tag, in place.

    Returns
    -------
    int
        How many cells changed.
    """
    changed = 0
    for cell in nb.get("cells", []):
        meta = _graded(cell)
        if meta is None:
            continue
        before = json.dumps(cell, sort_keys=True)
        src = _source(cell)
        first, _, rest = src.partition("\n")
        header = check_header(meta.get("points", 0))
        if HEADER_RE.match(first):
            src = header + "\n" + rest if first != header else src
        else:
            src = header + "\n" + src
        if isinstance(cell.get("source"), list):
            cell["source"] = src.splitlines(keepends=True)
        else:
            cell["source"] = src
        tags = cell["metadata"].setdefault("tags", [])
        if TAG not in tags:
            tags.append(TAG)
        changed += json.dumps(cell, sort_keys=True) != before
    return changed


def _dump(nb: dict, like: str) -> str:
    """Serialise ``nb`` in the layout of the original text ``like``."""
    for ensure_ascii in (False, True):
        text = json.dumps(json.loads(like), indent=1, ensure_ascii=ensure_ascii) + "\n"
        if text == like:
            return json.dumps(nb, indent=1, ensure_ascii=ensure_ascii) + "\n"
    import nbformat  # the layout JupyterLab and nbformat write

    return nbformat.writes(nbformat.from_dict(nb)) + "\n"


def main(argv: list[str] | None = None) -> int:
    """Mark the check cells of the notebooks named in ``argv``; print the changes."""
    for name in sys.argv[1:] if argv is None else argv:
        path = Path(name)
        text = path.read_text(encoding="utf-8")
        nb = json.loads(text)
        n = mark_checks(nb)
        if n:
            path.write_text(_dump(nb, text), encoding="utf-8")
        sys.stdout.write(f"{path}: {n} check cell(s) marked\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
