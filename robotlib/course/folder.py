"""``robotlib course DIR``: a course folder of the student's own.

Writes the released labs (the shipped ``labs/``, never ``solutions/``), the
syllabus and a README into ``DIR``, then prints the two commands that come
next: compile the kernels once, open the folder in JupyterLab. The folder is
the student's: a notebook already there is never overwritten, so running the
command again after an upgrade only adds the labs that are new.

Usage::

    robotlib course robotics            # ./robotics/lab0_getting_started.ipynb, ...

Reads the shipped files through `robotlib._shipped`; imports nothing else of
robotlib.
"""

from __future__ import annotations

import argparse
import shutil
import sys
from dataclasses import dataclass, field
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from .._shipped import shipped_dir

__all__ = [
    "CourseFiles",
    "Written",
    "course_files",
    "next_commands",
    "write_course",
    "add_arguments",
    "run",
]

SOLUTION_MARKER = "### BEGIN SOLUTION"
"""Text a released lab never holds (`robotlib.course.release` strips it)."""


@dataclass(frozen=True)
class CourseFiles:
    """The shipped files a course folder is made from.

    Attributes
    ----------
    labs : list of pathlib.Path
        The released lab notebooks, in the syllabus' order (by name).
    syllabus : pathlib.Path
        ``syllabus.md``.
    """

    labs: list[Path]
    syllabus: Path


def course_files() -> CourseFiles:
    """Return the released labs and the syllabus this install carries.

    Raises
    ------
    FileNotFoundError
        If the install carries no labs or no syllabus (a wheel built without
        its data files).
    """
    labs = sorted(shipped_dir("labs").glob("*.ipynb"))
    syllabus = shipped_dir("course") / "syllabus.md"
    if not labs:
        raise FileNotFoundError(f"no released labs in {shipped_dir('labs')}")
    if not syllabus.is_file():
        raise FileNotFoundError(f"no syllabus at {syllabus}")
    return CourseFiles(labs=labs, syllabus=syllabus)


@dataclass
class Written:
    """What `write_course` did: files written, and files kept as they were."""

    written: list[Path] = field(default_factory=list)
    kept: list[Path] = field(default_factory=list)


def _robotlib_version() -> str:
    try:
        return version("robotlib")
    except PackageNotFoundError:  # running from a checkout that was never installed
        return "unknown"


def _command(name: str) -> str:
    """How to call the script ``name`` of this environment from any shell.

    Its bare name when it is the one on ``PATH`` (an active environment),
    else its full path.
    """
    scripts = Path(sys.executable).parent
    on_path = shutil.which(name)
    if on_path and Path(on_path).resolve().parent == scripts.resolve():
        return name
    for candidate in (scripts / name, scripts / f"{name}.exe"):
        if candidate.exists():
            return _quoted(candidate)
    return name


def _quoted(path: Path) -> str:
    """``path`` as one word for a POSIX shell, cmd.exe and PowerShell alike."""
    return f'"{path}"' if " " in str(path) else str(path)


def next_commands(folder: Path) -> list[str]:
    """Return the two commands after ``robotlib course``: warm up, open the folder."""
    return [
        f"{_command('robotlib')} warmup",
        f"{_command('jupyter')} lab {_quoted(folder)}",
    ]


def _readme(files: CourseFiles, folder: Path) -> str:
    warmup, lab = next_commands(folder)
    rows = "\n".join(f"- `{p.name}`" for p in files.labs)
    return f"""# My robotics course

Written by `robotlib course` (robotlib {_robotlib_version()}). This folder is
yours: work in these notebooks, keep them under version control if you like.

## Start

```
{warmup}
{lab}
```

The first compiles the labs' numba kernels once (a few minutes; later
notebooks then start in seconds); the second opens this folder in JupyterLab.
Start with Lab 0 and run its first cell.

## What is here

{rows}
- `syllabus.md`: what each lab teaches, what it needs, how long it takes, and
  how the checks and grading work.
- `README.md`: this file.

## Checking your work

Replace each `raise NotImplementedError()` with your code, then run the cells
marked CHECK below it: a check fails exactly when the work is wrong. Hand in
the notebook; your instructor grades the same checks plus hidden ones.

## A new version of the course

After `pip install --upgrade robotlib` (or a new wheel from your instructor),
run `robotlib course` on this folder again: it adds the labs that are new and
leaves every notebook already here untouched.
"""


def write_course(folder: str | Path, files: CourseFiles | None = None) -> Written:
    """Write the released labs, the syllabus and a README into ``folder``.

    Files already in ``folder`` are kept as they are (the student's work).

    Parameters
    ----------
    folder : str or pathlib.Path
        The course folder; made if missing.
    files : CourseFiles, optional
        Where to copy from; default: `course_files`.

    Returns
    -------
    Written
        The files written and the files kept.

    Raises
    ------
    NotADirectoryError
        If ``folder`` is an existing file.
    ValueError
        If a lab to copy holds solutions (it was not released).
    """
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise NotADirectoryError(f"{folder} is a file, not a folder")
    files = course_files() if files is None else files
    texts = {}
    for lab in files.labs:
        text = lab.read_text(encoding="utf-8")
        if SOLUTION_MARKER in text:
            raise ValueError(f"{lab} holds solutions: only released labs are copied")
        texts[lab.name] = text
    texts["syllabus.md"] = files.syllabus.read_text(encoding="utf-8")
    texts["README.md"] = _readme(files, folder.resolve())
    folder.mkdir(parents=True, exist_ok=True)
    done = Written()
    for name, text in texts.items():
        dest = folder / name
        if dest.exists():
            done.kept.append(dest)
            continue
        dest.write_text(text, encoding="utf-8", newline="\n")
        done.written.append(dest)
    return done


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``course`` options to ``parser``."""
    parser.description = (
        "Write the released labs, the syllabus and a README into a folder of "
        "your own; files already there are kept."
    )
    parser.add_argument(
        "folder",
        nargs="?",
        default="robotics-course",
        type=Path,
        help="the course folder (default: ./robotics-course)",
    )


def run(args: argparse.Namespace) -> int:
    """Run ``robotlib course``; return the exit status."""
    try:
        done = write_course(args.folder)
    except (OSError, ValueError) as exc:
        sys.stderr.write(f"robotlib course: {exc}\n")
        return 2
    folder = args.folder.resolve()
    out = sys.stdout
    out.write(f"Course folder: {folder}\n")
    out.write(f"  wrote {len(done.written)} files")
    if done.kept:
        out.write(f", kept {len(done.kept)} already there")
    out.write("\n\nNext:\n\n")
    for command in next_commands(folder):
        out.write(f"    {command}\n")
    out.write("\nThe syllabus is syllabus.md in that folder.\n")
    return 0
