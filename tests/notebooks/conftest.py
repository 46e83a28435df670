"""Fixtures of the notebook tests."""

from __future__ import annotations

import subprocess
import sys

import pytest


@pytest.fixture(scope="session")
def warm():
    """``robotlib warmup`` once (quick when the cache is warm, as in CI).

    The notebooks run after it must compile nothing (``ROBOTLIB_COMPILE_LOG``).
    """
    subprocess.run(
        [sys.executable, "-m", "robotlib.cli", "warmup"],
        check=True, capture_output=True, timeout=1200,
    )  # fmt: skip
