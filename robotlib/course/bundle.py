"""``robotlib release --bundle DIR``: what an instructor hands to students.

The bundle is a folder of three things:

- ``robotlib-VERSION-py3-none-any.whl``: the library, the worlds, the
  released labs and the syllabus, built from a copy of the files the build
  reads (never ``solutions/``), so nothing is written into the repository;
- ``labs/``: the released lab notebooks, for a course page or an LMS;
- ``INSTALL.md``: the student's commands (install the wheel, write a course
  folder, compile the kernels once with ``robotlib warmup``, open JupyterLab)
  and how long the warmup took when the bundle was made.

Before anything is written the wheel is checked (`leaks`): no file named
after solutions, no solution or hidden-test marker, every lab identical to a
fresh release of ``solutions/``, and no solution region of any lab anywhere
in the wheel's text. A wheel that fails is not kept.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
import time
import zipfile
from pathlib import Path

from .notebooks import HIDDEN, SOLUTION, exercises, read_notebook

__all__ = [
    "BUILD_INPUTS",
    "build_wheel",
    "solution_regions",
    "leaks",
    "warmup_seconds",
    "install_text",
    "make_bundle",
]

BUILD_INPUTS = ("pyproject.toml", "README.md", "robotlib", "worlds", "labs", "course")
"""The repository's files and folders the wheel is built from (not ``solutions/``)."""

_IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc", "*.nbi", "*.nbc", "*.egg-info")
_MIN_REGION_CHARS = 40
"""Shorter solution regions (``return x``) are too common to be evidence of a leak."""


def build_wheel(root: str | Path, out: str | Path, timeout: float = 900) -> Path:
    """Build robotlib's wheel from a copy of ``BUILD_INPUTS`` of ``root``.

    Parameters
    ----------
    root : str or pathlib.Path
        The repository (a released checkout).
    out : str or pathlib.Path
        Folder the wheel is written into (created).
    timeout : float, optional
        Seconds the build may take.

    Returns
    -------
    pathlib.Path
        The wheel.

    Raises
    ------
    RuntimeError
        When the build fails (pip's last output lines attached).
    """
    root, out = Path(root), Path(out)
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="robotlib-bundle-") as tmp:
        src = Path(tmp) / "src"
        src.mkdir()
        for name in BUILD_INPUTS:
            path = root / name
            if path.is_dir():
                shutil.copytree(path, src / name, ignore=_IGNORE)
            elif path.is_file():
                shutil.copy2(path, src / name)
        build = Path(tmp) / "wheel"
        env = {**os.environ, "PIP_DISABLE_PIP_VERSION_CHECK": "1"}
        cmd = [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q"]
        proc = subprocess.run(
            [*cmd, "-w", str(build), str(src)],
            cwd=tmp,
            env=env,
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        wheels = sorted(build.glob("robotlib-*.whl"))
        if proc.returncode != 0 or len(wheels) != 1:
            tail = (proc.stdout + proc.stderr)[-2000:]
            raise RuntimeError(f"building the wheel failed:\n{tail}")
        dest = out / wheels[0].name
        shutil.copy2(wheels[0], dest)
    return dest


def solution_regions(notebook: str | Path) -> list[tuple[int, str]]:
    """Return each solution and hidden-test region of a notebook.

    Only regions of at least 40 characters (dedented) are returned: a
    one-line ``return x`` is no evidence.

    Returns
    -------
    list of (int, str)
        The cell's index and the region's text.
    """
    regions = []
    for index, cell in enumerate(read_notebook(notebook).cells):
        lines, inside = [], False
        for line in cell.source.splitlines():
            stripped = line.strip()
            if stripped in (SOLUTION[0], HIDDEN[0]):
                lines, inside = [], True
            elif stripped in (SOLUTION[1], HIDDEN[1]):
                inside = False
                text = textwrap.dedent("\n".join(lines)).strip()
                if len(text) >= _MIN_REGION_CHARS:
                    regions.append((index, text))
            elif inside:
                lines.append(line)
    return regions


def _declared_files(notebook: Path) -> dict[int, set[str]]:
    """Cell index of each exercise to the wheel files of its listed versions.

    An exercise lists the library's own versions of its answer (``writes``,
    e.g. ``robotlib.localization.paper.resize``): the library ships them, by
    design, so a solution region found in their module is no leak.
    """
    out = {}
    for ex in exercises(read_notebook(notebook), notebook.stem):
        files = set()
        for dotted in ex.writes:
            parts = dotted.split(".")
            for n in range(1, len(parts)):
                files.add("/".join(parts[:n]) + ".py")
        out[ex.index] = files
    return out


def _flat(text: str) -> str:
    """``text`` with runs of blanks removed (a notebook's JSON escapes and indents)."""
    return "".join(text.split())


def leaks(
    wheel: str | Path, solutions: str | Path, released: dict[str, str]
) -> list[str]:
    """List what in ``wheel`` gives away an answer of ``solutions/*.ipynb``.

    Parameters
    ----------
    wheel : str or pathlib.Path
        A built wheel (any zip file).
    solutions : str or pathlib.Path
        The solution notebooks' folder.
    released : dict
        Lab file name to the text of its fresh release
        (`robotlib.course.release.release`).

    Returns
    -------
    list of str
        One line per problem: a file named after solutions, a solution or
        hidden-test marker outside the library's code (whose release module
        names them), a shipped lab that differs from a fresh release of its
        solution (or a lab missing), a solution region found in a file other
        than the modules its exercise lists as the library's own versions.
        Empty when the wheel is clean.
    """
    solutions = Path(solutions)
    regions = {}  # (lab, number): the region flattened, the files allowed it
    for path in sorted(solutions.glob("*.ipynb")):
        declared = _declared_files(path)
        for i, (cell, text) in enumerate(solution_regions(path), 1):
            regions[path.stem, i] = (_flat(text), declared.get(cell, set()))
    found, shipped = [], set()
    with zipfile.ZipFile(wheel) as zf:
        for name in zf.namelist():
            if "solution" in name.lower():
                found.append(f"{name}: a file named after solutions")
            try:
                text = zf.read(name).decode("utf-8")
            except UnicodeDecodeError:
                continue
            for marker in (SOLUTION[0], HIDDEN[0]):
                if marker in text and not name.endswith(".py"):  # release's own
                    found.append(f"{name}: holds {marker!r}")
            if name.endswith(".ipynb") and "/share/robotlib/labs/" in name:
                lab = name.rsplit("/", 1)[1]
                shipped.add(lab)
                if released.get(lab) != text:
                    found.append(f"{name}: differs from a fresh release of {lab}")
            flat = _flat(_cells_text(text) if name.endswith(".ipynb") else text)
            for (lab, i), (region, allowed) in regions.items():
                if name not in allowed and region in flat:
                    found.append(f"{name}: holds solution region {i} of {lab}")
    for lab in sorted(set(released) - shipped):
        found.append(f"{lab}: not in the wheel")
    return sorted(set(found))


def _cells_text(text: str) -> str:
    """Return a notebook's cells' sources, one after the other (else ``text``)."""
    try:
        cells = json.loads(text).get("cells", [])
        return "\n".join("".join(c.get("source", "")) for c in cells)
    except (ValueError, AttributeError, TypeError):
        return text


def warmup_seconds(timeout: float = 1800) -> float:
    """Time ``robotlib warmup`` with an empty kernel cache, in seconds.

    Runs in a subprocess whose ``NUMBA_CACHE_DIR`` is a new temporary folder,
    so every kernel compiles, as on a student's first run.
    """
    with tempfile.TemporaryDirectory(prefix="robotlib-warmup-") as tmp:
        env = {**os.environ, "NUMBA_CACHE_DIR": tmp, "MPLBACKEND": "Agg"}
        t0 = time.perf_counter()
        proc = subprocess.run(
            [sys.executable, "-m", "robotlib.cli", "warmup"],
            cwd=tmp,
            env=env,
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        seconds = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"robotlib warmup failed:\n{proc.stderr[-2000:]}")
    return seconds


def _minutes(seconds: float) -> str:
    if seconds < 90:
        return f"about {max(5, round(seconds / 5) * 5):.0f} seconds"
    return f"about {round(seconds / 60):.0f} minutes"


def install_text(wheel_name: str, seconds: float, where: str) -> str:
    """Return ``INSTALL.md``: a student's commands and the warmup's duration.

    Parameters
    ----------
    wheel_name : str
        The wheel's file name.
    seconds : float
        How long ``robotlib warmup`` took on an empty cache, in seconds.
    where : str
        Where it was measured (the machine's cores and load), said in the text.
    """
    return f"""# Installing the course

You need Python 3.11 or newer. In a terminal, in the folder holding
`{wheel_name}`:

```bash
python3 -m venv .venv
.venv/bin/pip install {wheel_name}
.venv/bin/robotlib course my-course
.venv/bin/robotlib warmup
.venv/bin/jupyter lab my-course
```

On Windows (PowerShell or cmd):

```bat
py -3 -m venv .venv
.venv\\Scripts\\pip install {wheel_name}
.venv\\Scripts\\robotlib course my-course
.venv\\Scripts\\robotlib warmup
.venv\\Scripts\\jupyter lab my-course
```

- `pip install` installs robotlib and the packages it needs (numpy, numba,
  matplotlib, JupyterLab, ...): a few hundred megabytes the first time.
- `robotlib course my-course` writes the labs and the syllabus into the
  folder `my-course`. Running it again later (after installing a newer
  wheel) adds new labs and never overwrites a notebook you have worked on.
- `robotlib warmup` compiles the simulator's kernels once, so that the
  labs start in seconds. **It takes {_minutes(seconds)}**
  ({seconds:.0f} s {where}); a slower laptop may take two or three times as
  long. Run it once, and again after installing a new wheel; a progress bar
  shows where it is.
- `jupyter lab my-course` opens the labs in your browser.

The `labs/` folder beside this file holds the same notebooks, to read
before installing.
"""


def _where() -> str:
    cores = os.cpu_count() or 1
    try:
        load = f", load average {os.getloadavg()[0]:.1f}"
    except OSError:
        load = ""
    return f"on {cores} cores{load}"


def make_bundle(
    root: str | Path,
    dest: str | Path,
    released: dict[str, str],
    warmup: float | None = None,
    say=print,
) -> Path:
    """Write the student bundle of the repository ``root`` into ``dest``.

    Parameters
    ----------
    root : str or pathlib.Path
        The repository; its ``labs/`` must be a fresh release of
        ``solutions/`` (the wheel is built from them).
    dest : str or pathlib.Path
        Bundle folder (created; must be empty or absent).
    released : dict
        Lab file name to the text of its fresh release
        (`robotlib.course.release.release`).
    warmup : float, optional
        Seconds ``robotlib warmup`` takes, for ``INSTALL.md``; measured here
        (`warmup_seconds`) when None.
    say : callable, optional
        Progress lines go there.

    Returns
    -------
    pathlib.Path
        The wheel inside ``dest``.

    Raises
    ------
    ValueError
        When ``dest`` holds files, or the wheel leaks or its labs are not
        ``released`` (the problems listed; the wheel is deleted).
    """
    root, dest = Path(root), Path(dest)
    if dest.exists() and any(dest.iterdir()):
        raise ValueError(f"{dest} is not empty")
    say("building the wheel (from a copy without solutions/) ...")
    wheel = build_wheel(root, dest)
    problems = leaks(wheel, root / "solutions", released)
    if problems:
        wheel.unlink()
        raise ValueError("the wheel gives answers away:\n  " + "\n  ".join(problems))
    say(f"checked {wheel.name}: no solution, every lab as released")
    (dest / "labs").mkdir()
    for name, text in sorted(released.items()):
        (dest / "labs" / name).write_text(text, encoding="utf-8")
    if warmup is None:
        say("timing `robotlib warmup` on an empty kernel cache ...")
        where = f"when this bundle was made, {_where()} before the run"
        warmup = warmup_seconds()
    else:
        where = "as measured by your instructor"
    (dest / "INSTALL.md").write_text(install_text(wheel.name, warmup, where))
    say(f"wrote {dest}: {wheel.name}, labs/, INSTALL.md (warmup {warmup:.0f} s)")
    return wheel
