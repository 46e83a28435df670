"""Every solution and released lab, run in JupyterLab in headless Chromium.

Starts JupyterLab on a copy of ``solutions/`` and ``labs/`` (found by glob,
so new labs are covered as they land), opens each notebook in Debian's
chromium (driven by playwright, no browser download), runs all cells from
the menu and checks what a student would see: no error output in a solution;
in a released lab, only "Exercise N is not done yet" messages of a few
lines, and Run All reaches its last cell (every demonstration runs); no
request off the machine (the test blocks them: a course must work offline)
and no browser console error; every panel's image redraws after its first
slider moves, and shows feedback first; every animation's player shows a
frame after Run All and advances; after ``robotlib warmup`` no kernel
compiles anything (``ROBOTLIB_COMPILE_LOG``). This is the run of every
solution in a plain kernel (`tests.notebooks.test_notebooks` runs them under
nbval only where there is no browser). Screenshots and
``timings.json`` go to ``artifacts/browser/`` (git-ignored; CI keeps it).
The runs start with the session, beside the other tests and at their
priority (`tests.background`); this module's tests run last and check them.

Skipped where chromium or playwright is missing, unless
``ROBOTLIB_BROWSER_TEST=1`` (set by ``.ci/run``), which makes that a failure.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import pytest

from tests import background
from tests.browser import (
    CHROMIUM,
    Browser,
    Lab,
    have_browser,
    notebook,
    run_notebook,
    run_notebooks,
    unexplained_console_errors,
)
from tests.contention import Clock
from tests.student_view import SHOWN, unsolved_problems

ROOT = Path(__file__).resolve().parents[2]
ARTIFACTS = ROOT / "artifacts" / "browser"
NOTEBOOKS = [
    str(p.relative_to(ROOT))
    for folder in ("solutions", "labs")
    for p in sorted((ROOT / folder).glob("*.ipynb"))
]
RUN_ALL_LIMIT = 600.0  # quiet s (tests.contention) per notebook: ~60 s under nbval
PANEL_REDRAW = 20.0  # quiet s (tests.contention) from a slider change to the new
# figure (0.3-0.7 s quiet, up to 7 s of wall time at a load of 15 on 2 cores)
PANEL_FEEDBACK = 1.0  # s to the first sign of a run (100 ms on an idle laptop)
# s from the key press to "running ..." in the page, for a panel with a status
# line (robotlib's answer in the browser, kernel or no kernel: a few ms)
PANEL_RUNNING_IN_PAGE = 0.3
SHRUNK = 0.7  # a figure shown below 70 % of its own width is too wide for the page

_have = have_browser()
if not _have and os.environ.get("ROBOTLIB_BROWSER_TEST") == "1":
    raise RuntimeError(f"the browser test needs playwright and {CHROMIUM}")
pytestmark = [
    pytest.mark.skipif(not _have, reason=f"needs playwright and {CHROMIUM}"),
    pytest.mark.slow,  # a real browser
]


SELECTED = {
    "every": "test_every_notebook_in_a_real_browser",
    "selftest": "test_the_browser_test_fails_when_a_panel_stops_redrawing",
}
BACKGROUND_NICER = 0  # at the tests' priority: its panels answer as a student's would


def background_work(folder: Path) -> dict:
    """Every notebook, then the self-test, beside the other tests (`tests.background`).

    ``robotlib warmup`` first (quick when the cache is warm, as in CI): after
    it no kernel may compile anything (``ROBOTLIB_COMPILE_LOG``). One
    JupyterLab and one chromium run what the selected tests check.
    """
    if not _have:
        return {}
    names = {item.originalname for item in background.selected(__name__)}
    cmd = [sys.executable, "-m", "robotlib.cli", "warmup"]
    warm = background.run(cmd, timeout=1200)
    if warm.returncode != 0:
        raise RuntimeError(f"robotlib warmup failed: {warm.stderr[-3000:]}")
    compiled = folder / "compiled.txt"  # every kernel's late compilations
    lab = Lab(ROOT, tmp=folder, env={"ROBOTLIB_COMPILE_LOG": str(compiled)})
    background.adopt(lab.proc)
    out = {}
    try:
        browser = Browser(ARTIFACTS)
        if browser.driver is not None:  # chromium's processes: not a test's
            background.adopt(browser.driver)
        try:
            if SELECTED["every"] in names:
                runs = run_notebooks(
                    lab, browser, NOTEBOOKS, RUN_ALL_LIMIT, PANEL_REDRAW,
                    feedback_bound=PANEL_FEEDBACK, stop=background.ENDED,
                )  # fmt: skip
                late = compiled.read_text().split() if compiled.exists() else []
                out["every"] = runs, lab.kernel_list_races(), sorted(set(late))
            if SELECTED["selftest"] in names and not background.ENDED.is_set():
                (lab.root / "selftest").mkdir(exist_ok=True)
                (lab.root / "selftest" / "panels.ipynb").write_text(
                    json.dumps(SELFTEST)
                )
                clock = Clock()  # quiet seconds (tests.contention)
                run = run_notebook(lab, browser, "selftest/panels.ipynb", 60, 5.0)
                out["selftest"] = run, clock.elapsed()
        finally:
            browser.close()
    finally:
        lab.close(keep_log=ARTIFACTS / "jupyterlab.log")  # a CI artefact too
    return out


@pytest.fixture(scope="module")
def ran():
    return background.result(__name__)


def problems(run, solution: bool, races: set[str] = frozenset()) -> list[str]:
    """What a student would notice in a browser run (empty: nothing).

    ``races``: the server's own failed kernel lists (`Lab.kernel_list_races`).
    """
    out = []
    if not run.finished:
        out.append(f"Run All did not finish within {run.run_all_s:.0f} s")
    out += [f"console: {text}" for text in unexplained_console_errors(run, races)]
    out += [f"asked the network for {url}" for url in sorted(set(run.blocked))]
    for cell, ename, text in run.errors if solution else ():  # a lab's: below
        lines = text.splitlines()
        out.append(f"code cell {cell}: {ename} ({len(lines)} lines): {lines[:1]}")
    for p in run.panels:
        if p.get("error"):
            said = f"shows an error after '{p['slider']}': {p['error']}"
            out.append(f"panel {p['panel']} {said}")
        elif p["redraw_s"] is None or p["redraw_quiet_s"] > PANEL_REDRAW:
            out.append(f"panel {p['panel']} did not redraw after '{p['slider']}'")
        elif p["feedback_s"] is None or p["feedback_s"] > PANEL_FEEDBACK:
            late = f"panel {p['panel']} showed no feedback within {PANEL_FEEDBACK} s"
            out.append(late)
        for when, t in (("", p.get("in_page")), (" while busy", p.get("busy"))):
            s = None if t is None else t.get("running_s")
            if p.get("status_line") and t and (s is None or s > PANEL_RUNNING_IN_PAGE):
                said = f"did not read 'running' within {PANEL_RUNNING_IN_PAGE} s"
                out.append(f"panel {p['panel']} {said}{when}")
    for natural, shown in run.figures:
        if shown < SHRUNK * natural:
            out.append(f"a {natural} px figure is shrunk to {shown / natural:.0%}")
    for a in run.animations:
        if not a.get("shown", True):
            out.append(f"animation {a['player']} showed no frame after Run All")
        if a["after"] <= a["start"]:
            out.append(f"animation {a['player']} did not advance")
    code = [c for c in run.notebook.get("cells", []) if c["cell_type"] == "code"]
    unrun = [
        i for i, c in enumerate(code)
        if c.get("execution_count") is None and "".join(c["source"]).strip()
    ]  # fmt: skip
    if run.finished and unrun:  # Run All stopped at an error
        out.append(f"code cells {unrun[:8]} never ran")
    if not solution:  # every demonstration draws, or says what it needs
        out += unsolved_problems(run.notebook.get("cells", []))
    return out


def _record(run) -> None:
    path = ARTIFACTS / "timings.json"
    try:
        timings = json.loads(path.read_text())
    except (OSError, ValueError):
        timings = {}
    timings[run.path] = {
        "first_cell_s": run.first_cell_s,
        "run_all_s": run.run_all_s,
        "panels": run.panels,
        "animations": run.animations,
        "errors": [(i, ename, text.splitlines()[-1:]) for i, ename, text in run.errors],
        "blocked": run.blocked,
        "figures": run.figures,
        "cells_s": run.cells_s,
        "open_s": run.open_s,
        "check_s": run.check_s,
        "check_parts": run.check_parts,
        "first_figure_s": _first_figure_s(run),
    }
    path.write_text(json.dumps(timings, indent=1))


def _first_figure_s(run) -> float | None:
    """Seconds of cell runs until the first figure, widget or HTML shows."""
    code = [c for c in run.notebook.get("cells", []) if c["cell_type"] == "code"]
    spent = 0.0
    for cell, seconds in zip(code, run.cells_s, strict=False):
        spent += seconds or 0.0
        if any(k in o.get("data", {}) for o in cell["outputs"] for k in SHOWN):
            return round(spent, 2)
    return None


def test_every_notebook_in_a_real_browser(ran):
    runs, races, late = ran["every"]
    found = {}
    for run in runs:
        _record(run)
        solution = run.path.startswith("solutions/")
        issues = problems(run, solution, races)
        if solution and run.first_cell_s is None:
            issues.append("the first cell never finished")
        if not solution and run.finished and not run.errors:
            issues.append("a released lab's checks should fail until it is solved")
        if issues:
            found[run.path] = issues
    if late:  # (two notebooks run at once: the kernels are named, not the notebook)
        found["compiled after robotlib warmup"] = late
    assert not found, json.dumps(found, indent=1)


SELFTEST = notebook(
    [
        "import io\n\nimport ipywidgets as w\nfrom matplotlib.figure import"
        " Figure\n\n\ndef png(v):\n    fig = Figure(figsize=(3, 2))\n"
        "    fig.add_subplot().plot([0, 1], [0, v])\n    buf = io.BytesIO()\n"
        "    fig.savefig(buf, format='png')\n    return buf.getvalue()\n\n\n"
        "def panel(live):\n    s = w.FloatSlider(value=1.0, min=0, max=5,"
        " step=0.1, continuous_update=False)\n"
        "    img = w.Image(value=png(1.0))\n"
        "    label = w.Label('ready')\n\n    def changed(c):\n"
        "        label.value = 'running'\n        if live:\n"
        "            img.value = png(c['new'])\n\n"
        "    s.observe(changed, names='value')\n"
        "    return w.VBox([s, label, img])",
        "panel(live=True)",
        "panel(live=False)  # a panel that stopped redrawing",
        "from IPython.display import Image, display\n\n\n"
        "def broken(v=1.0):  # a panel whose redraw fails\n"
        "    if v != 1.0:\n        raise ValueError('the panel broke')\n"
        "    display(Image(data=png(v)))\n\n\n"
        "w.interact(broken, v=w.FloatSlider(value=1.0, min=0, max=5, step=0.1,"
        " continuous_update=False));",
    ]
)


def test_the_browser_test_fails_when_a_panel_stops_redrawing(ran):
    """A test of the test: the same checks catch a panel whose figure stays put."""
    run, seconds = ran["selftest"]
    assert run.finished and not run.errors
    assert [p["panel"] for p in run.panels] == [0, 1, 2]
    live, stuck, broken = run.panels
    assert live["redraw_s"] is not None and live["feedback_s"] is not None
    assert stuck["redraw_s"] is None  # waited the whole bound, saw no new pixels
    assert stuck["feedback_s"] is not None  # its label still said "running"
    assert broken["redraw_s"] is None and "the panel broke" in broken["error"]
    found = problems(run, solution=True)
    assert found == [
        "panel 1 did not redraw after ''",
        "panel 2 shows an error after 'v': ValueError: the panel broke",
    ], found
    assert seconds < 90
