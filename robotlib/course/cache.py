"""The numba cache every grading process starts from: warmed by the instructor, seeded.

Compiling the library's kernels takes minutes; loading them from numba's
cache takes seconds. A class is graded from one cache folder (``opts.
numba_cache``), made here before the reference run:

1. `prewarm` runs the lab's set-up cell once, in the instructor's own
   environment (it is the instructor's code, from ``solutions/``), so the
   kernels it warms are compiled into the instructor's numba cache (the
   library's ``__pycache__`` folders, or ``NUMBA_CACHE_DIR``) and stay there
   for the next grading run, the tests and the notebooks; matplotlib's font
   list, built on the way, is kept for the sandboxed processes too;
2. `seed` copies the library's cached kernels from there into the class's
   cache folder, laid out as numba looks for them under ``NUMBA_CACHE_DIR``
   (each source folder under ``<name>_<sha1 of its path>``; the library is
   mounted at the same path inside the sandbox, so the entries stay valid).

The reference run then writes what its checks compile into that folder, and
each submission gets its own copy (`session`): no sandboxed student process
ever writes a cache another process reads. `save_reference` keeps the
reference run's lines with that cache and the font list (in the records
folder), and `load_reference` gives them back while `reference_key` (the
solution, the library, the tools) is unchanged: adding a late student or
folding in hand grades does not repeat the reference run. Imports nothing
of robotlib's but numba's cache folder naming (`robotlib._kernel_cache`).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

from .._kernel_cache import cache_subpath

__all__ = [
    "cache_subpath",
    "instructor_cache_dirs",
    "load_reference",
    "prewarm",
    "reference_key",
    "save_reference",
    "seed",
]

_SUFFIXES = (".nbi", ".nbc")

_RUN_SETUP = (
    "import sys\n"
    "from IPython.core.interactiveshell import InteractiveShell\n"
    "shell = InteractiveShell.instance()\n"
    "source = shell.transform_cell(sys.stdin.read())\n"
    "exec(compile(source, '<set-up>', 'exec'), shell.user_ns)\n"
)


def _package_dirs() -> list[Path]:
    pkg = Path(__file__).resolve().parents[1]  # the installed robotlib package
    subs = (p for p in pkg.rglob("*") if p.is_dir() and "__pycache__" not in p.parts)
    return [pkg, *sorted(subs)]


def instructor_cache_dirs() -> list[tuple[Path, str]]:
    """Where the instructor's numba cache of the library is: ``(folder, subpath)``.

    For each folder of the installed package: its ``__pycache__`` (numba's
    default) and, if ``NUMBA_CACHE_DIR`` is set, the folder numba uses there.
    """
    out = []
    user = os.environ.get("NUMBA_CACHE_DIR")
    for d in _package_dirs():
        sub = cache_subpath(d)
        out.append((d / "__pycache__", sub))
        if user:
            out.append((Path(user) / sub, sub))
    return out


def seed(cache: Path) -> int:
    """Copy the instructor's cached kernels of the library into ``cache``.

    Returns the number of files copied. Newer files win where several
    caches hold the same entry.
    """
    n = 0
    for src, sub in instructor_cache_dirs():
        if not src.is_dir():
            continue
        dst = cache / sub
        for f in src.iterdir():
            if f.suffix not in _SUFFIXES or not f.is_file():
                continue
            dst.mkdir(parents=True, exist_ok=True)
            target = dst / f.name
            try:
                if target.exists() and target.stat().st_mtime >= f.stat().st_mtime:
                    continue
                shutil.copy2(f, target)
                n += 1
            except OSError:
                continue
    return n


def prewarm(setup: str, mplconfig: Path | None = None, timeout: float = 1800.0) -> str:
    """Run a lab's set-up cell in the instructor's environment; return "" or why not.

    The cell is the instructor's own code (from ``solutions/``); it compiles
    (or loads) the kernels it warms into the instructor's numba cache. A
    failure is reported, not raised: the reference run then compiles in the
    sandbox (slower, same result). ``mplconfig``: where matplotlib writes its
    font list (each sandboxed process gets a copy instead of rebuilding it,
    seconds per process).
    """
    if not setup.strip():
        return ""
    import tempfile

    env = {**os.environ, "MPLBACKEND": "Agg"}
    if mplconfig is not None:
        env["MPLCONFIGDIR"] = str(mplconfig)
    try:
        with tempfile.TemporaryDirectory(prefix="rg-warm-") as tmp:
            proc = subprocess.run(
                [sys.executable, "-c", _RUN_SETUP],
                input=setup,
                env=env,
                capture_output=True,
                text=True,
                timeout=timeout,
                cwd=tmp,
            )
    except (OSError, subprocess.TimeoutExpired) as exc:
        return f"the set-up cell did not run: {exc}"
    if proc.returncode != 0:
        return f"the set-up cell failed: {proc.stderr.strip()[-300:]}"
    return ""


def reference_key(solution_text: str, lab: str) -> str:
    """Return a hash of what the reference run's results depend on.

    The solution, the lab's name, the library's sources and worlds (names,
    sizes, times), Python's, numpy's and numba's versions: a saved reference
    run is reused only while none of them changed.
    """
    import hashlib

    import numba
    import numpy

    h = hashlib.sha256(f"{lab}\0{sys.version}\0{numpy.__version__}\0".encode())
    h.update(f"{numba.__version__}\0".encode())
    h.update(solution_text.encode("utf-8", "surrogateescape"))
    pkg = Path(__file__).resolve().parents[1]
    for p in sorted(pkg.rglob("*.py")):
        h.update(str(p.relative_to(pkg)).encode())
        h.update(p.read_bytes())
    worlds = pkg.parent / "worlds"
    for p in sorted(worlds.rglob("*")) if worlds.is_dir() else ():
        st = p.stat()
        h.update(f"{p.relative_to(worlds)}\0{st.st_size}\0{st.st_mtime_ns}".encode())
    return h.hexdigest()[:32]


def load_reference(folder: Path, key: str, opts) -> dict | None:
    """Return a saved reference run's ``CHECK`` lines, its caches copied; or None.

    ``opts.numba_cache`` and ``opts.mpl_cache`` receive the warmed class
    cache and font list saved with it.
    """
    import json

    try:
        data = json.loads((folder / "reference.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("key") != key:
        return None
    for name, dst in (("numba", opts.numba_cache), ("matplotlib", opts.mpl_cache)):
        if (folder / name).is_dir():
            shutil.copytree(folder / name, dst, dirs_exist_ok=True)
    return data.get("lines")


def save_reference(folder: Path, key: str, lines: dict, opts) -> None:
    """Save a reference run (lines, warmed class cache, font list) under ``folder``.

    Written beside it and renamed into place: a run interrupted while saving
    leaves the previous one or none, never half of one.
    """
    import json

    tmp = folder.with_name(f"{folder.name}.{os.getpid()}.tmp")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir(parents=True)
    for name, src in (("numba", opts.numba_cache), ("matplotlib", opts.mpl_cache)):
        if src is not None and src.is_dir():
            shutil.copytree(src, tmp / name, symlinks=False)
    (tmp / "reference.json").write_text(json.dumps({"key": key, "lines": lines}))
    shutil.rmtree(folder, ignore_errors=True)
    tmp.rename(folder)
