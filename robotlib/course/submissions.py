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
import re
from pathlib import Path

__all__ = [
    "check_lab",
    "copies",
    "find_submissions",
    "helpers",
    "is_copy_of",
    "pick",
]

HELPERS = 20
"""Most helper modules taken from beside one notebook."""
HELPER_BYTES = 256 << 10
"""Largest helper module taken, bytes."""


def _name(p: Path) -> str:
    """Return the file name as text: UTF-8, else Latin-1 (old Windows zips)."""
    raw = os.fsencode(p.name)
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


_COPY = re.compile(r"(\s*\(\d+\)|\s*-\s*copy\d*|\s+copy(\s*\d+)?)+$", re.IGNORECASE)


def is_copy_of(path: Path, lab: str) -> bool:
    """Whether ``path`` is the lab's notebook or a copy (``lab (1)``, ``lab-Copy1``)."""
    stem = _COPY.sub("", path.stem.strip())
    return stem.strip().lower() == lab.lower()


def copies(path: Path, lab: str) -> list[Path]:
    """Return the other copies of the lab beside ``path`` (graded: the newest)."""
    folder = path.parent
    return sorted(
        p
        for p in folder.glob("*.ipynb")
        if p != path and is_copy_of(p, lab) and not p.is_symlink()
    )


def _newest(paths: list[Path]) -> Path:
    return max(paths, key=lambda p: (p.stat().st_mtime, p.name))


def _sections(entry: Path, lab: str) -> list[Path] | None:
    """Sub-folders that are students (``section2/alice/lab.ipynb``), or None."""
    if any(entry.glob("*.ipynb")) or (entry / lab).is_dir():
        return None
    subs = [
        d
        for d in sorted(entry.iterdir())
        if d.is_dir() and not d.name.startswith(".") and not d.is_symlink()
    ]
    with_nb = [d for d in subs if any(_notebooks(d))]
    return with_nb if len(with_nb) >= 2 else None


def _notebooks(folder: Path) -> list[Path]:
    out = []
    for root, dirs, files in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        for f in sorted(files):
            if f.endswith(".ipynb") and not f.startswith("."):
                out.append(Path(root) / f)
    return out


def find_submissions(
    folder: str | Path, lab: str, exclude: tuple[Path, ...] = ()
) -> list[tuple[str, Path | None, str]]:
    """List ``(student, notebook, status)`` of a submissions folder.

    ``status`` is "" when the notebook is clear, else why it was not graded
    ("no notebook", "several notebooks: a.ipynb, b.ipynb"); then ``notebook``
    is None. Student names are the folder or file names (UTF-8, else
    Latin-1); equal names get ``#2``, ``#3``. Of several copies of the lab's
    notebook (``lab.ipynb``, ``lab (1).ipynb``) the newest is graded; a
    folder of folders that each hold notebooks is a section, each sub-folder
    a student (``section2/alice``); ``exclude`` (the grader's own outputs)
    is skipped.
    """
    skip = {Path(p).resolve() for p in exclude}
    folder = Path(folder)
    if not folder.is_dir():
        raise FileNotFoundError(f"no submissions folder {folder}")
    out: list[tuple[str, Path | None, str]] = []
    entries = sorted(folder.iterdir(), key=lambda p: os.fsencode(p.name))
    while entries:
        entry = entries.pop(0)
        if entry.name.startswith(".") or entry.resolve() in skip:
            continue
        prefix = "" if entry.parent == folder else f"{_name(entry.parent)}/"
        if entry.is_symlink():
            name = _name(entry.with_suffix("") if entry.suffix == ".ipynb" else entry)
            out.append((prefix + name, None, "a symbolic link, not graded"))
            continue
        if entry.is_file() and entry.suffix == ".ipynb":
            out.append((prefix + _name(entry.with_suffix("")), entry, ""))
            continue
        if not entry.is_dir():
            continue
        if entry.parent == folder and (section := _sections(entry, lab)):
            entries[:0] = section  # each sub-folder a student of the section
            continue
        out.append((prefix + _name(entry), *_choose(entry, lab)))
    seen: dict[str, int] = {}
    unique = []
    for student, path, status in out:
        seen[student] = seen.get(student, 0) + 1
        name = student if seen[student] == 1 else f"{student}#{seen[student]}"
        unique.append((name, path, status))
    return unique


def helpers(notebook: Path, folder: Path) -> tuple[dict[str, str], list[str]]:
    """Return the student's modules beside ``notebook`` and notes on those left.

    ``from helpers import f`` works in a notebook beside ``helpers.py``: so
    the ``*.py`` files in the student's own folder (not the submissions
    folder itself, whose files are nobody's) are graded with it, at most
    `HELPERS` of at most `HELPER_BYTES` each. A module that would hide an
    installed one (``numpy.py``) or is not a module name is left out.

    Returns
    -------
    modules : dict
        File name to source text.
    notes : list of str
        What was left out, and why.
    """
    import importlib.util

    modules: dict[str, str] = {}
    notes: list[str] = []
    if notebook.parent.resolve() == Path(folder).resolve():
        return modules, notes
    for p in sorted(notebook.parent.glob("*.py")):
        name = _name(p)
        why = None
        if p.is_symlink() or not p.is_file() or name.startswith("."):
            why = "not a plain file"
        elif not name[:-3].isidentifier():
            why = "not a module name"
        elif importlib.util.find_spec(name[:-3]) is not None:
            why = f"would hide the installed module {name[:-3]}"
        elif p.stat().st_size > HELPER_BYTES or len(modules) >= HELPERS:
            why = "too large or too many"
        else:
            try:
                modules[name] = p.read_bytes().decode("utf-8")
            except (OSError, UnicodeDecodeError):
                why = "unreadable or not UTF-8"
        if why:
            notes.append(f"{name}: {why}, not graded")
    return modules, notes


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


def _choose(entry: Path, lab: str) -> tuple[Path | None, str]:
    """Pick a student folder's notebook: ``(path, "")`` or ``(None, why not)``."""
    found = [
        p
        for p in _notebooks(entry)
        if ".ipynb_checkpoints" not in p.parts and not p.is_symlink()
    ]
    named = [p for p in found if is_copy_of(p, lab)]
    if named:
        return _newest(named), ""
    if not found:
        return None, "no notebook"
    mine = [p for p in found if not p.stem.lower().startswith("untitled")]
    if len(mine) == 1:
        return mine[0], ""
    if len(found) == 1:
        return found[0], ""
    rel = ", ".join(str(p.relative_to(entry)) for p in (mine or found)[:4])
    return None, f"several notebooks, none chosen: {rel}"
