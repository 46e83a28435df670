"""``robotlib release``: write the student labs (``labs/``) from ``solutions/``.

Usage::

    robotlib release                 # every solutions/*.ipynb -> labs/
    robotlib release lab3_mcl        # one lab
    robotlib release --check         # exit 1 if labs/ is stale (CI)
    robotlib release --bundle DIR    # the students' wheel, labs/, INSTALL.md
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .notebooks import (
    NotebookError,
    check_graded_exercises,
    notebook_text,
    read_notebook,
    release_notebook,
)

__all__ = ["project_dir", "release", "stale_labs", "add_arguments", "run"]


def _say(message: str) -> None:
    sys.stderr.write(message + "\n")


def project_dir() -> Path:
    """Return the course folder: the working directory if it has ``solutions/``.

    Otherwise the repository holding this package.
    """
    cwd = Path.cwd()
    if (cwd / "solutions").is_dir():
        return cwd
    return Path(__file__).resolve().parents[2]


def _sources(solutions: Path, names: list[str] | None) -> list[Path]:
    if names:
        paths = []
        for name in names:
            p = solutions / (name if name.endswith(".ipynb") else f"{name}.ipynb")
            if not p.exists():
                raise FileNotFoundError(f"no solution notebook {p}")
            paths.append(p)
        return paths
    return sorted(solutions.glob("*.ipynb"))


def release(
    solutions: str | Path, labs: str | Path, names: list[str] | None = None
) -> dict[str, str]:
    """Render the student version of each solution notebook.

    Parameters
    ----------
    solutions, labs : str or pathlib.Path
        Source and destination folders.
    names : list of str, optional
        Lab names (file stems) to release; all by default.

    Returns
    -------
    dict
        Lab file name to its released notebook text (nothing is written).
    """
    out = {}
    for src in _sources(Path(solutions), names):
        solution = read_notebook(src)
        check_graded_exercises(solution, src.stem)
        nb = release_notebook(solution, src.stem)
        out[src.name] = notebook_text(nb)
    return out


def stale_labs(solutions: str | Path, labs: str | Path, names=None) -> list[str]:
    """Names of the labs whose file in ``labs`` differs from a fresh release."""
    labs = Path(labs)
    stale = []
    for fname, text in release(solutions, labs, names).items():
        dest = labs / fname
        if not dest.exists() or dest.read_text(encoding="utf-8") != text:
            stale.append(fname)
    return stale


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``release`` options to ``parser``."""
    parser.add_argument("names", nargs="*", help="labs to release (default: all)")
    parser.add_argument("--solutions", type=Path, help="source folder (solutions/)")
    parser.add_argument("--labs", type=Path, help="destination folder (labs/)")
    parser.add_argument(
        "--check", action="store_true", help="write nothing; exit 1 if labs/ is stale"
    )
    parser.add_argument(
        "--bundle",
        type=Path,
        metavar="DIR",
        help="write what students get into DIR (new or empty): a wheel without "
        "solutions, the labs, INSTALL.md; labs/ must be released first",
    )
    parser.add_argument(
        "--warmup-seconds",
        type=float,
        metavar="S",
        help="with --bundle: the time `robotlib warmup` takes, for INSTALL.md "
        "(default: measured, on an empty kernel cache)",
    )


def run(args: argparse.Namespace) -> int:
    """Run ``robotlib release``; return the exit status."""
    root = project_dir()
    if args.bundle is not None:
        return _bundle(root, args)
    if args.warmup_seconds is not None:
        _say("robotlib release: --warmup-seconds goes with --bundle")
        return 2
    solutions = args.solutions or root / "solutions"
    labs = args.labs or root / "labs"
    try:
        rendered = release(solutions, labs, args.names or None)
    except (NotebookError, FileNotFoundError) as exc:
        _say(f"robotlib release: {exc}")
        return 2
    if args.check:
        stale = stale_labs(solutions, labs, args.names or None)
        for fname in stale:
            _say(f"stale: {Path(labs) / fname} (run `robotlib release`)")
        return 1 if stale else 0
    labs.mkdir(parents=True, exist_ok=True)
    for fname, text in rendered.items():
        dest = labs / fname
        if dest.exists() and dest.read_text(encoding="utf-8") == text:
            _say(f"unchanged {dest}")
            continue
        tmp = dest.with_name(dest.name + ".tmp")
        tmp.write_text(text, encoding="utf-8")
        tmp.replace(dest)
        _say(f"wrote {dest}")
    orphans = {p.name for p in labs.glob("*.ipynb")} - {
        p.name for p in solutions.glob("*.ipynb")
    }
    for fname in sorted(orphans):
        _say(f"warning: {labs / fname} has no source in {solutions}")
    return 0


def _bundle(root: Path, args: argparse.Namespace) -> int:
    from .bundle import make_bundle

    if args.names or args.solutions or args.labs or args.check:
        _say("robotlib release: --bundle takes every lab of the repository, alone")
        return 2
    solutions, labs = root / "solutions", root / "labs"
    try:
        stale = stale_labs(solutions, labs)
        if stale:
            _say(f"stale: {', '.join(stale)} (run `robotlib release` first)")
            return 1
        released = release(solutions, labs)
        make_bundle(root, args.bundle, released, args.warmup_seconds, say=_say)
    except (ValueError, RuntimeError, NotebookError) as exc:
        _say(f"robotlib release --bundle: {exc}")
        return 1
    return 0
