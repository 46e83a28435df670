"""What a student waits for in each lab, in JupyterLab in headless Chromium.

Runs ``robotlib warmup`` (as the README's set-up does), starts JupyterLab
on a copy of ``solutions/`` and ``labs/``, loads it once in Debian's
chromium (`tests.browser`) and runs a small warm-up notebook (a kernel
start and robotlib's imports, so the first lab does not pay for a cold disk).
Then, one notebook at a time (nothing else of ours runs meanwhile), it opens
each lab, solution and released version, in that page, presses Run All as
soon as the kernel is idle, waits for the last cell and saves the notebook.
Per notebook it writes:

- **first figure**: seconds from opening the notebook (the kernel's start
  included) to the first image in an output (a figure, a panel's image, an
  animation's frame), as the page saw it;
- **Run All**: seconds from Run All to the last cell's reply, and the
  kernel's CPU time over them;
- **longest silent**: the longest time a running cell showed nothing new
  (no output, no moving bar or counter: no change at all in the cell's
  output area, watched by a ``MutationObserver`` in the page), and which
  cell; also over every cell, the same for the first cell;
- **CPU s**: the kernel's CPU time (its process tree, from ``/proc``) over
  the same stretch, from the kernel's start for the first figure: on a
  loaded machine, a floor for the quiet wall time;
- the load average when the notebook started and ended, what compiled
  after the warm-up (``ROBOTLIB_COMPILE_LOG``: should be nothing) and, for a
  released lab, what a student would notice in its outputs
  (`tests.student_view.unsolved_problems`: a ``NameError``, a traceback
  over a few lines, a demonstration that draws nothing and says nothing).

The machine is shared: the wall times depend on its load, given beside
them. About 10 minutes on a quiet 2-core machine::

    .venv/bin/python bench/browser_timings.py --out bench/results/browser_timings.md
    .venv/bin/python bench/browser_timings.py --only lab3 --shots /tmp/shots

``--out`` also writes the rows as JSON beside the table (``.json``);
``--only`` keeps the notebooks whose path contains one of the words;
``--shots DIR`` also saves a Chromium screenshot of every output holding an
image (to look at the figures as a student sees them).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from robotlib.course.cpu import descendants, usage  # noqa: E402
from tests.browser import (  # noqa: E402
    _CLOSE,
    _OPEN,
    _READY,
    Browser,
    Lab,
    Run,
    _menu,
    _prompts,
    _read_saved,
    notebook,
)
from tests.student_view import unsolved_problems  # noqa: E402

NOTEBOOKS = [
    f"{folder}/{p.name}"
    for p in sorted((ROOT / "solutions").glob("*.ipynb"))
    for folder in ("solutions", "labs")
]

WATCH = """() => {
  if (!window.__rl) {
    const rl = window.__rl = { marks: [], fig: null };
    new MutationObserver((records) => {
      const now = Date.now();
      for (const r of records) {
        const el = r.target.nodeType === 1 ? r.target : r.target.parentElement;
        const out = el && el.closest('.jp-Cell-outputWrapper');
        const cell = out && out.closest('.jp-CodeCell');
        if (!cell) continue;
        const last = rl.marks[rl.marks.length - 1];
        if (last && last[0] === cell && now - last[1] < 100) continue;
        rl.marks.push([cell, now]);
      }
      if (rl.fig === null
          && document.querySelector('.jp-Notebook .jp-OutputArea-output img')) {
        rl.fig = now;
      }
    }).observe(document.body,
      { subtree: true, childList: true, characterData: true, attributes: true });
  }
  window.__rl.marks = [];
  window.__rl.fig = null;
  return Date.now();
}"""
"""Watch every change in a code cell's output area (page time, ms); reset."""

MARKS = """() => {
  const cells = [...document.querySelectorAll('.jp-Notebook .jp-CodeCell')];
  return { fig: window.__rl.fig,
           marks: window.__rl.marks.map(([c, t]) => [cells.indexOf(c), t]) };
}"""

SHOWING = """(path) => {
  const w = window.jupyterapp.shell.currentWidget;
  if (!w || !w.context || w.context.path !== path || !w.sessionContext) return false;
  const k = w.sessionContext.session && w.sessionContext.session.kernel;
  return !!k && k.status === 'idle' && k.connectionStatus === 'connected';
}"""
"""``path`` is the notebook shown, and its kernel has started and is idle."""

WARM_UP = notebook(
    [
        "import matplotlib.pyplot as plt\nimport robotlib.notebook\n"
        "robotlib.notebook.setup(warm=())\nplt.plot([0, 1]);"
    ]
)
"""A kernel start and robotlib's imports, before the first lab is timed."""


@dataclass
class Timing:
    """What one notebook's run in the page gave (seconds; None: not seen)."""

    path: str
    open_s: float | None = None  # open to an idle kernel
    first_figure_s: float | None = None  # open to the first image
    first_figure_cpu_s: float | None = None  # the kernel's, from its start
    run_all_s: float | None = None
    run_all_cpu_s: float | None = None
    finished: bool = False
    silent_s: float = 0.0
    silent_cpu_s: float = 0.0
    silent_cell: int | None = None  # code cell index
    silent_source: str = ""
    first_cell_s: float | None = None
    first_cell_silent_s: float | None = None
    load: tuple = ()
    compiled: list = field(default_factory=list)
    errors: list = field(default_factory=list)  # (code cell, ename, lines)
    problems: list = field(default_factory=list)
    cells: list = field(default_factory=list)  # per code cell: see `time_notebook`


class Kernel:
    """The CPU time of a kernel's process tree over time, sampled on a thread.

    A thread of its own samples every 0.2 s whatever the page is doing (a
    call into a page on a loaded machine can take seconds).
    """

    def __init__(self, pid: int):
        self.pid, self.samples = pid, [(time.time(), usage(pid).cpu)]
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(0.2):
            u = usage(self.pid)
            if u.processes:
                self.samples.append((time.time(), u.cpu))

    def stop(self) -> None:
        """Take a last sample and stop sampling."""
        self._stop.set()
        self._thread.join()
        u = usage(self.pid)
        if u.processes:
            self.samples.append((time.time(), u.cpu))

    def cpu(self, t: float) -> float:
        """CPU s at epoch ``t``, interpolated between samples."""
        when, cpu = zip(*self.samples, strict=True)
        return float(np.interp(t, when, cpu))


def _kernel_pid(lab: Lab, path: str) -> int | None:
    ids = [s["kernel"]["id"] for s in lab._api("sessions") if s.get("path") == path]
    if not ids:
        return None
    for pid in descendants(lab.proc.pid):
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                if ids[0].encode() in f.read():
                    return pid
        except OSError:
            continue
    return None


def _epoch(iso: str | None) -> float | None:
    if not iso:
        return None
    return datetime.fromisoformat(iso.replace("Z", "+00:00")).timestamp()


def _span(cell: dict) -> tuple[float | None, float | None]:
    t = cell.get("metadata", {}).get("execution", {})
    start = t.get("iopub.execute_input") or t.get("iopub.status.busy")
    return _epoch(start), _epoch(t.get("shell.execute_reply"))


def _longest_gap(start: float, end: float, marks: list[float]) -> tuple[float, float]:
    """The longest stretch of [start, end] with no mark in it: (from, to)."""
    points = [start, *sorted(m for m in marks if start < m < end), end]
    gaps = [(b - a, a, b) for a, b in zip(points, points[1:], strict=False)]
    _, a, b = max(gaps)
    return a, b


def _cpu(kernel: Kernel | None, a: float, b: float) -> float | None:
    return None if kernel is None else kernel.cpu(b) - kernel.cpu(a)


def _shots(page, stem: str, folder: Path) -> None:
    """Screenshot each code cell's output area that holds an image."""
    cells = page.locator(".jp-Notebook .jp-CodeCell")
    for i in range(cells.count()):
        out = cells.nth(i).locator(".jp-Cell-outputWrapper")
        if out.count() and out.first.locator("img").count():
            out.first.screenshot(path=str(folder / f"{stem}_cell{i:02d}.png"))


def time_notebook(lab, browser, page, path, timeout, compiled, shots=None) -> Timing:
    """Open ``path`` in ``page``, Run All, wait, save: its `Timing`."""
    tm = Timing(path, load=(os.getloadavg()[0],))
    seen = compiled.read_text().split() if compiled.exists() else []
    opened = page.evaluate(WATCH) / 1000
    page.evaluate(_OPEN, path)  # (not waiting for JupyterLab's answer)
    while not (page.evaluate(SHOWING, path) and page.evaluate(_READY)):
        if time.time() - opened > 300:
            raise TimeoutError(f"{path}: JupyterLab did not open it with a kernel")
        page.wait_for_timeout(100)
    tm.open_s = time.time() - opened
    pid = _kernel_pid(lab, path)
    kernel = Kernel(pid) if pid else None
    page.locator(".jp-Notebook").first.click()
    asked = time.time()
    _menu(page, "Run", "Run All Cells")
    started = again = time.monotonic()
    while time.monotonic() - started < timeout:
        prompts = _prompts(page)
        status = page.get_attribute(".jp-Notebook-ExecutionIndicator", "data-status")
        ran = any(p not in ("[ ]:", "") for p in prompts)
        if not ran and time.monotonic() - again > 15:  # the kernel did not hear it
            _menu(page, "Run", "Run All Cells")
            again = time.monotonic()
        if ran and status == "idle" and not any("*" in p for p in prompts):
            tm.finished = True
            break
        page.wait_for_timeout(200)
    if kernel:
        kernel.stop()
    seen_by_page = page.evaluate(MARKS)
    stem = path.replace("/", "_").removesuffix(".ipynb")
    if shots is not None:
        _shots(page, stem, shots)
    saved = lab.root / path
    before = saved.stat().st_mtime_ns
    page.keyboard.press("Control+s")
    waited = time.monotonic()
    while saved.stat().st_mtime_ns == before and time.monotonic() - waited < 30:
        page.wait_for_timeout(100)
    nb = _read_saved(page, saved)
    page.evaluate(_CLOSE)
    lab.shutdown_kernels(path)
    tm.load += (os.getloadavg()[0],)
    late = compiled.read_text().split() if compiled.exists() else []
    tm.compiled = sorted(set(late[len(seen) :]))

    code = [c for c in nb["cells"] if c["cell_type"] == "code"]
    marks: dict[int, list[float]] = {}
    for i, t in seen_by_page["marks"]:
        marks.setdefault(i, []).append(t / 1000)
    fig = seen_by_page["fig"]
    if fig is not None:
        fig /= 1000
        tm.first_figure_s = fig - opened
        tm.first_figure_cpu_s = kernel.cpu(fig) if kernel else None
    ends = []
    for i, cell in enumerate(code):
        start, end = _span(cell)
        for out in cell.get("outputs", []):
            if out.get("output_type") == "error":
                lines = len("\n".join(out.get("traceback", [])).splitlines())
                tm.errors.append((i, out.get("ename"), lines))
        if start is None or end is None:
            continue
        ends.append(end)
        a, b = _longest_gap(start, end, marks.get(i, []))
        cpu = [_cpu(kernel, start, end), _cpu(kernel, a, b)]
        tm.cells.append(  # s from opening: start, end, silent from, to; CPU s of both
            [round(x - opened, 2) for x in (start, end, a, b)]
            + [None if c is None else round(c, 2) for c in cpu]
        )
        if i == 0:
            tm.first_cell_s, tm.first_cell_silent_s = end - start, b - a
        if b - a > tm.silent_s:
            tm.silent_s, tm.silent_cell = b - a, i
            tm.silent_cpu_s = _cpu(kernel, a, b)
            source = "".join(cell["source"]).strip().splitlines()
            tm.silent_source = source[0][:48] if source else ""
    if ends:
        tm.run_all_s = max(ends) - asked
        if kernel:
            tm.run_all_cpu_s = _cpu(kernel, asked, max(ends))
    if path.startswith("labs/"):
        tm.problems = unsolved_problems(nb["cells"])
    return tm


def _s(x: float | None, fmt: str = ".1f") -> str:
    return "-" if x is None else format(x, fmt)


def table(timings: list[Timing], silent: float = 5.0) -> str:
    """The Markdown table of the timings, then every cell silent over ``silent`` s."""
    head = (
        "| notebook | open s | first figure s (CPU s) | Run All s (CPU s) "
        "| longest silent s (CPU s) | in code cell | first cell s (silent s) "
        "| load start-end | compiled | errors (lines) |\n"
        "|---|---|---|---|---|---|---|---|---|---|\n"
    )
    rows = []
    for t in timings:
        errors = ", ".join(f"{i}:{e}({n})" for i, e, n in t.errors) or "none"
        cell = "-" if t.silent_cell is None else f"{t.silent_cell} `{t.silent_source}`"
        cell = cell.replace("|", "\\|")
        run_all = f"{_s(t.run_all_s)} ({_s(t.run_all_cpu_s)})"
        if not t.finished:
            run_all += " not finished"
        rows.append(
            f"| {t.path} | {_s(t.open_s)} "
            f"| {_s(t.first_figure_s)} ({_s(t.first_figure_cpu_s)}) | {run_all} "
            f"| {_s(t.silent_s)} ({_s(t.silent_cpu_s)}) | {cell} "
            f"| {_s(t.first_cell_s)} ({_s(t.first_cell_silent_s)}) "
            f"| {' - '.join(f'{x:.1f}' for x in t.load)} "
            f"| {', '.join(t.compiled) or 'none'} | {errors} |"
        )
    out = head + "\n".join(rows) + "\n"
    long = [
        (t.path, i, c) for t in timings for i, c in enumerate(t.cells)
        if c[3] - c[2] > silent
    ]  # fmt: skip
    if long:
        out += f"\nCells silent over {silent:g} s:\n\n"
        for path, i, (start, end, a, b, cpu, quiet) in long:
            out += (
                f"- {path}, code cell {i}: silent {b - a:.1f} s ({_s(quiet)} s CPU)"
                f" of its {end - start:.1f} s ({_s(cpu)} s CPU)\n"
            )
    problems = [(t.path, p) for t in timings for p in t.problems]
    if problems:
        out += "\nWhat a student would notice in the released labs:\n\n"
        out += "".join(f"- {path}: {p}\n" for path, p in problems)
    return out


def report(timings, args, run: str, warm_s, warm_load, t_all) -> str:
    """The whole report (written to ``--out``, with its JSON, if given)."""
    text = (
        f"# What a student waits for, in JupyterLab in headless Chromium\n\n"
        f"`bench/browser_timings.py`, commit {run}, "
        f"{time.monotonic() - t_all:.0f} s in all; `robotlib warmup` first: "
        f"{warm_s:.1f} s (load {warm_load:.1f}). One notebook at a time; times from "
        "opening the notebook (first figure: kernel start included) or from Run All; "
        "silent: the longest a running cell's output area did not change; CPU s: "
        "the kernel's CPU time over the same stretch; load: 1-minute average.\n\n"
        + table(timings, args.silent)
    )
    if args.out:
        args.out.write_text(text)
        rows = [vars(t) for t in timings]
        args.out.with_suffix(".json").write_text(json.dumps(rows, indent=1))
    return text


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, help="write the Markdown table here too")
    parser.add_argument("--only", nargs="*", default=[], help="words of the paths")
    parser.add_argument("--timeout", type=float, default=900.0, help="s per notebook")
    parser.add_argument("--shots", type=Path, help="folder for output screenshots")
    parser.add_argument(
        "--silent", type=float, default=5.0, help="list cells silent over this, s"
    )
    args = parser.parse_args(argv)
    paths = [p for p in NOTEBOOKS if not args.only or any(w in p for w in args.only)]
    t_all = time.monotonic()
    git = ["git", "rev-parse", "--short", "HEAD"]
    commit = subprocess.run(git, cwd=ROOT, capture_output=True, text=True).stdout
    commit = commit.strip()
    began = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    t0 = time.monotonic()
    warm = subprocess.run(
        [sys.executable, "-m", "robotlib.cli", "warmup"], capture_output=True, text=True
    )
    if warm.returncode:
        sys.exit(f"robotlib warmup failed:\n{warm.stderr[-3000:]}")
    warm_s, warm_load = time.monotonic() - t0, os.getloadavg()[0]
    if args.shots:
        args.shots.mkdir(parents=True, exist_ok=True)
    timings = []
    with tempfile.TemporaryDirectory(prefix="browser-timings-") as tmp:
        compiled = Path(tmp) / "compiled.txt"
        lab = Lab(ROOT, tmp=Path(tmp), env={"ROBOTLIB_COMPILE_LOG": str(compiled)})
        try:
            browser = Browser(Path(tmp) / "screens")
            try:
                (lab.root / "warm_up.ipynb").write_text(json.dumps(WARM_UP))
                page = browser.page(Run("warm_up.ipynb"))
                page.goto(lab.url("warm_up.ipynb"), wait_until="commit")
                page.wait_for_function(_READY, timeout=300_000)
                page.evaluate(WATCH)
                page.evaluate(_CLOSE)
                lab.shutdown_kernels()
                time_notebook(lab, browser, page, "warm_up.ipynb", 300, compiled)
                for path in paths:
                    tm = time_notebook(
                        lab, browser, page, path, args.timeout, compiled, args.shots
                    )
                    timings.append(tm)
                    print(table([tm]).splitlines()[2], flush=True)
                    report(timings, args, commit, warm_s, warm_load, t_all)  # so far
            finally:
                browser.close()
        finally:
            lab.close()
    print(report(timings, args, f"{commit}, started {began}", warm_s, warm_load, t_all))
    return 0


if __name__ == "__main__":
    sys.exit(main())
