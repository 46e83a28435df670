"""The documentation site builds with warnings as errors and has its key pages.

The build runs in a temporary copy of the files it reads (``docs/``,
``course/``, ``CONTRIBUTING.md``, ``CHANGELOG.md``), so that the gallery's
generated pages land there and not in the repository; it starts with the
session, beside the other tests (`tests.background`), which run first. The
site must open from disk: no page loads a script or a style sheet from the
network.
"""

from __future__ import annotations

import os
import re
import shutil
import sys
from pathlib import Path

import pytest

from tests import background

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted(p.stem for p in (ROOT / "docs" / "examples").glob("plot_*.py"))

pytestmark = pytest.mark.slow


def background_work(folder: Path):
    """Build the site in ``folder`` (`tests.background`: beside the other tests)."""
    src, html = folder / "src", folder / "html"
    ignore = shutil.ignore_patterns("_build", "gallery", "sg_execution_times.rst")
    shutil.copytree(ROOT / "docs", src / "docs", ignore=ignore)
    shutil.copytree(ROOT / "course", src / "course")
    for name in ("CONTRIBUTING.md", "CHANGELOG.md"):
        shutil.copy2(ROOT / name, src / name)
    env = {**os.environ, "MPLBACKEND": "Agg", "ROBOTLIB_TABLE_CACHE": "off"}
    cmd = [
        sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
        "-d", src / "doctrees", src / "docs", html,
    ]  # fmt: skip
    return background.run(cmd, cwd=src, env=env, timeout=1200), html


@pytest.fixture(scope="module")
def site():
    proc, html = background.result(__name__)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-6000:]
    return html


def test_key_pages_exist(site):
    pages = [
        "index", "getting-started", "robot-api", "syllabus", "instructor-guide",
        "contributing", "changelog", "course/index", "gallery/index", "api/index",
    ]  # fmt: skip
    pages += [f"course/lab{k}" for k in range(7)]
    for page in pages:
        assert (site / f"{page}.html").is_file(), page


def test_robot_api_page_has_the_papers_table(site):
    text = (site / "robot-api.html").read_text()
    for name in ("robot", "move", "setheading", "setdeltaheading", "ismovedone",
                 "isheadingdone", "readsonar", "disconnect"):  # fmt: skip
        assert f'href="api/robot.html#robotlib.robot.{name}"' in text, name


def test_api_reference_comes_from_the_docstrings(site):
    expected = {
        "world": ["robotlib.world.World", "robotlib.world.load_world"],
        "localization": ["robotlib.localization.MCL"],
        "planning": ["robotlib.planning.astar"],
        "mapping": ["robotlib.mapping.GridFastSLAM"],
        "course": ["robotlib.course.folder.write_course"],
    }
    for page, ids in expected.items():
        text = (site / "api" / f"{page}.html").read_text()
        for ident in ids:
            assert f'id="{ident}"' in text, (page, ident)
        assert "Parameters" in text  # numpydoc's sections


def test_every_gallery_example_runs_and_draws_its_figure(site):
    """The build ran every example (one that raises aborts it: test_gallery.py)."""
    index = (site / "gallery" / "index.html").read_text()
    for stem in EXAMPLES:
        assert f"{stem}.html" in index, stem
        page = (site / "gallery" / f"{stem}.html").read_text()
        assert f"sphx_glr_{stem}_001.png" in page, stem
        assert (site / "_images" / f"sphx_glr_{stem}_001.png").is_file(), stem


def test_the_site_opens_from_disk(site):
    remote = re.compile(r'<(?:script|link|img)[^>]+(?:src|href)="(?:https?:)?//')
    for page in site.rglob("*.html"):
        assert not remote.search(page.read_text()), page
