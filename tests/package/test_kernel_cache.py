"""Cached kernels follow their sources, across files (`robotlib._kernel_cache`)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest

from robotlib._kernel_cache import DIGEST_NAME, cache_subpath, check, kernel_sources

BASE = "import numba as nb\n\n@nb.njit(cache=True)\ndef base():\n    return {}\n"
CALLER = """
import numba as nb
from ..low._kernels import base

@nb.njit(cache=True)
def twice():
    return 2 * base()
"""


def _package(tmp, base_value: int):
    pkg = tmp / "pkg"
    for sub in ("", "low", "high", "plain"):
        (pkg / sub).mkdir(parents=True, exist_ok=True)
        (pkg / sub / "__init__.py").write_text("")
    (pkg / "_config.py").write_text("JIT = {}\n")
    (pkg / "low" / "_kernels.py").write_text(BASE.format(base_value))
    (pkg / "high" / "_kernels.py").write_text(CALLER)
    (pkg / "plain" / "model.py").write_text("X = 1\n")
    return pkg


def _run_twice(tmp, pkg, cache_root: str) -> int:
    script = textwrap.dedent(f"""
        from pathlib import Path
        from robotlib._kernel_cache import check
        check(Path({str(pkg)!r}), {cache_root!r})
        from pkg.high._kernels import twice
        print(twice())
    """)
    env = {**os.environ, "PYTHONPATH": str(tmp)}
    env.pop("NUMBA_CACHE_DIR", None)
    if cache_root:
        env["NUMBA_CACHE_DIR"] = cache_root
    out = subprocess.run(
        [sys.executable, "-c", script], env=env, capture_output=True, text=True,
        timeout=120, check=True,
    )  # fmt: skip
    return int(out.stdout.split()[-1])


@pytest.mark.slow
def test_a_changed_callee_in_another_file_is_compiled_afresh(tmp_path):
    """numba alone keeps the caller's old compiled callee; the check deletes it."""
    pkg = _package(tmp_path, 1)
    assert _run_twice(tmp_path, pkg, "") == 2
    assert list((pkg / "high" / "__pycache__").glob("*.nbi"))  # cached
    (pkg / "low" / "_kernels.py").write_text(BASE.format(5))
    assert _run_twice(tmp_path, pkg, "") == 10


def test_only_a_changed_digest_deletes_and_only_kernel_caches(tmp_path):
    pkg = _package(tmp_path, 1)
    root = tmp_path / "numba-cache"
    assert {p.relative_to(pkg).as_posix() for p in kernel_sources(pkg)} == {
        "_config.py",
        "low/_kernels.py",
        "high/_kernels.py",
    }
    kernel_files = []
    for where in (pkg / "low" / "__pycache__", root / cache_subpath(pkg / "high")):
        where.mkdir(parents=True)
        for suffix in (".nbi", ".nbc", ".pyc"):
            (where / f"_kernels.f-1.py311{suffix}").write_bytes(b"x")
        kernel_files += [
            where / "_kernels.f-1.py311.nbi",
            where / "_kernels.f-1.py311.nbc",
        ]
    other = pkg / "plain" / "__pycache__" / "model.g-1.py311.nbi"
    other.parent.mkdir()
    other.write_bytes(b"x")

    # no digest yet (a fresh or seeded cache): one is written, nothing deleted
    assert check(pkg, "") == 0 and check(pkg, str(root)) == 0
    assert (pkg / "__pycache__" / DIGEST_NAME).is_file()
    assert (root / DIGEST_NAME).is_file()
    assert check(pkg, "") == 0 and check(pkg, str(root)) == 0
    assert all(f.exists() for f in kernel_files)

    (pkg / "_config.py").write_text("JIT = {'cache': True}\n")
    assert check(pkg, "") == 2  # the folder-local caches
    assert check(pkg, str(root)) == 2  # and those under NUMBA_CACHE_DIR
    assert not any(f.exists() for f in kernel_files)
    assert other.exists()  # not a kernel folder
    assert (pkg / "low" / "__pycache__" / "_kernels.f-1.py311.pyc").exists()
    assert check(pkg, "") == 0
