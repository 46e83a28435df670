"""Find the submissions in a folder, with a clear status for what is ambiguous.

Accepted layouts: ``<student>/<lab>.ipynb``, ``<student>/<lab>/<lab>.ipynb``
(nbgrader), ``<student>/<the only notebook>.ipynb`` (``lab3 (1).ipynb``
included), ``<student>.ipynb``. A folder without a notebook, with several
notebooks and none named after the lab, or with notebooks only in nested
folders of several sections gets a status instead of a silent zero.
Checkpoints (``.ipynb_checkpoints``) and hidden files are ignored; file names
need not be UTF-8 or ASCII. Imports nothing of robotlib's.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

__all__ = ["check_lab", "find_submissions", "pick"]


def _name(p: Path) -> str:
    return os.fsdecode(p.name).encode("utf-8", "backslashreplace").decode("utf-8")


def _notebooks(folder: Path) -> list[Path]:
    out = []
    for root, dirs, files in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        for f in sorted(files):
            if f.endswith(".ipynb") and not f.startswith("."):
                out.append(Path(root) / f)
    return out


def find_submissions(
    folder: str | Path, lab: str
) -> list[tuple[str, Path | None, str]]:
    """List ``(student, notebook, status)`` of a submissions folder.

    ``status`` is "" when the notebook is clear, else why it was not graded
    ("no notebook", "several notebooks: a.ipynb, b.ipynb"); then ``notebook``
    is None. Student names are the folder or file names (undecodable bytes
    escaped); equal names get ``#2``, ``#3``.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise FileNotFoundError(f"no submissions folder {folder}")
    out: list[tuple[str, Path | None, str]] = []
    for entry in sorted(folder.iterdir(), key=lambda p: os.fsencode(p.name)):
        if entry.name.startswith("."):
            continue
        if entry.is_symlink():
            out.append((_name(entry), None, "a symbolic link, not graded"))
            continue
        if entry.is_file() and entry.suffix == ".ipynb":
            out.append((_name(entry.with_suffix("")), entry, ""))
            continue
        if not entry.is_dir():
            continue
        student = _name(entry)
        found = [
            p
            for p in _notebooks(entry)
            if ".ipynb_checkpoints" not in p.parts and not p.is_symlink()
        ]
        named = [p for p in found if p.stem.strip().lower() == lab.lower()]
        if len(named) == 1:
            out.append((student, named[0], ""))
        elif len(found) == 1:
            out.append((student, found[0], ""))
        elif not found:
            out.append((student, None, "no notebook"))
        else:
            rel = ", ".join(str(p.relative_to(entry)) for p in (named or found)[:4])
            out.append((student, None, f"several notebooks, none chosen: {rel}"))
    seen: dict[str, int] = {}
    unique = []
    for student, path, status in out:
        seen[student] = seen.get(student, 0) + 1
        name = student if seen[student] == 1 else f"{student}#{seen[student]}"
        unique.append((name, path, status))
    return unique


def pick(subs: list[tuple], students: list[str]) -> list[tuple]:
    """Keep the submissions of ``students`` (exact names); ValueError if absent."""
    names = {s[0] for s in subs}
    missing = [n for n in students if n not in names]
    if missing:
        import difflib

        near = {n: difflib.get_close_matches(n, names, 3, 0.5) for n in missing}
        hint = "; ".join(
            f"{n!r} (close: {', '.join(c) or 'none'})" for n, c in near.items()
        )
        raise ValueError(f"no submission of {hint}")
    return [s for s in subs if s[0] in students]


def _lab_of(path: Path) -> str | None:
    try:
        meta = json.loads(path.read_bytes()).get("metadata", {}).get("robotlib", {})
    except (OSError, ValueError, AttributeError):
        return None
    return meta.get("lab") if isinstance(meta, dict) else None


def check_lab(solution: dict, lab: str, notebooks: list[Path]) -> None:
    """Refuse to grade notebooks of another lab (``metadata.robotlib.lab``).

    Raises
    ------
    ValueError
        When most submissions that name their lab name one other than the
        solution's: grading them would give everyone zero.
    """
    meta = (solution.get("metadata") or {}).get("robotlib") or {}
    want = meta.get("lab") if isinstance(meta, dict) else None
    if want is None:
        return
    named = [x for x in map(_lab_of, notebooks) if x is not None]
    other = [x for x in named if x != want]
    if named and len(other) * 2 > len(named):
        common = max(set(other), key=other.count)
        raise ValueError(
            f"{len(other)} of {len(named)} notebooks are lab {common!r} "
            f"(their metadata), the solution of --lab {lab} is lab {want!r}: "
            "pick the lab they were handed out as"
        )
