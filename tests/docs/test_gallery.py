"""Each gallery example runs headless, as it is, and draws its figure.

The examples run once, in the documentation build (`tests/docs/test_docs.py`,
slow): sphinx-gallery runs each one as ``__main__`` with the Agg backend, an
example that raises fails the build (checked here), and the build's test asserts
each example's page shows its first figure.
"""

from __future__ import annotations

import runpy
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted((ROOT / "docs" / "examples").glob("plot_*.py"))


def test_the_gallery_has_ten_to_fifteen_examples():
    assert 10 <= len(EXAMPLES) <= 15


def test_an_example_that_raises_fails_the_documentation_build():
    conf = runpy.run_path(str(ROOT / "docs" / "conf.py"))["sphinx_gallery_conf"]
    assert conf["abort_on_example_error"] is True
    assert conf["plot_gallery"] == "True"  # examples run, not just shown
    assert conf["filename_pattern"] == r"/plot_"  # every plot_*.py is run
