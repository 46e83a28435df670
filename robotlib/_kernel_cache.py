"""Numba's on-disk cache of robotlib's kernels, kept in step with their sources.

numba keys a cached kernel by the time stamp of its own file only, so a
kernel that calls a kernel of another file (the localization kernels call
the world's point-to-segment distance, say) keeps the old compiled callee
when only the callee's file changes: a ``git pull`` could leave a student
running yesterday's code with no sign of it (numba's documentation lists
this among the cache's limitations). `check` keeps a digest of every kernel
source (the ``_kernels*`` modules and ``_config``) beside the cache; when it
differs from the sources, robotlib's cached kernels are deleted, and numba
compiles them afresh on first use.

A cache with no digest yet (a fresh one, or a copy the grader seeded) only
gets one written: nothing is deleted.

Public means only: files on disk, ``NUMBA_CACHE_DIR`` and the sources'
hashes; numba itself is not touched. Imports nothing of robotlib's.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

__all__ = ["cache_subpath", "check", "kernel_sources"]

PACKAGE = Path(__file__).resolve().parent
DIGEST_NAME = "robotlib-kernels.sha256"
_SUFFIXES = (".nbi", ".nbc")


def cache_subpath(source_dir: Path) -> str:
    """Numba's folder name under ``NUMBA_CACHE_DIR`` for kernels of ``source_dir``.

    numba (``_CacheLocator.get_suitable_cache_subpath``) names it after the
    folder of the source file and the SHA-1 of that folder's absolute path.
    """
    path = os.path.abspath(source_dir)
    return "_".join([os.path.split(path)[-1], hashlib.sha1(path.encode()).hexdigest()])


def kernel_sources(package: Path = PACKAGE) -> list[Path]:
    """Return the files whose kernels numba caches (``_kernels*``, ``_config``)."""
    found = [package / "_config.py"]
    for top, dirs, files in os.walk(package):
        dirs[:] = [d for d in dirs if d != "__pycache__"]
        inside = os.path.basename(top) == "_kernels"
        for f in files:
            if f.endswith(".py") and (inside or f.startswith("_kernels")):
                found.append(Path(top) / f)
    return sorted(p for p in found if p.is_file())


def _digest(sources: list[Path], package: Path) -> str:
    h = hashlib.sha256()
    for p in sources:
        h.update(str(p.relative_to(package)).encode() + b"\0" + p.read_bytes() + b"\0")
    return h.hexdigest()


def _cache_dirs(sources: list[Path], root: Path | None) -> list[Path]:
    folders = sorted({p.parent for p in sources})
    if root is None:
        return [d / "__pycache__" for d in folders]
    return [root / cache_subpath(d) for d in folders]


def check(package: Path = PACKAGE, cache_root: str | None = None) -> int:
    """Delete robotlib's cached kernels if their sources changed; return how many.

    Parameters
    ----------
    package : pathlib.Path
        The package's folder (robotlib's own by default).
    cache_root : str or None
        numba's cache folder; by default ``NUMBA_CACHE_DIR``, and when that
        is not set, each source folder's ``__pycache__``.

    Returns
    -------
    int
        The number of cache files deleted (0 when the digest matched, was
        missing, or could not be written: a read-only cache is left alone).
    """
    cache_root = os.environ.get("NUMBA_CACHE_DIR") if cache_root is None else cache_root
    root = Path(cache_root) if cache_root else None
    sources = kernel_sources(package)
    try:
        now = _digest(sources, package)
    except OSError:
        return 0
    stamp = (root if root is not None else package / "__pycache__") / DIGEST_NAME
    try:
        old = stamp.read_text().strip()
    except OSError:
        old = None
    if old == now:
        return 0
    deleted = 0
    if old is not None:
        for d in _cache_dirs(sources, root):
            for f in d.glob("*"):
                if f.suffix in _SUFFIXES:
                    try:
                        f.unlink()
                        deleted += 1
                    except OSError:
                        pass
    try:
        stamp.parent.mkdir(parents=True, exist_ok=True)
        tmp = stamp.with_name(f"{DIGEST_NAME}.{os.getpid()}")
        tmp.write_text(now + "\n")
        os.replace(tmp, stamp)
    except OSError:
        pass
    return deleted
