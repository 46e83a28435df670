"""Driving JupyterLab in headless Chromium: what tests/test_browser.py checks with.

`Lab` starts JupyterLab on a copy of the notebooks (so autosave never
writes into the repository) with settings that render every cell and fetch
no news; `Browser` opens Debian's chromium through playwright (its
executable path set: no browser download) with every non-loopback request
blocked. `run_notebook` opens a notebook, runs all cells from the menu,
saves it and returns what happened; `check_panels` moves the first slider
of each panel and times its first feedback and its redraw (a change of the
pixels of its image, read through a canvas, so a greyed-out old figure does
not count); `check_animations` presses each player's play button and reads
its frame slider.
"""

from __future__ import annotations

import json
import os
import shutil
import socket
import subprocess
import sys
import time
import urllib.request
from dataclasses import dataclass, field
from pathlib import Path

CHROMIUM = "/usr/bin/chromium"
LAB_SETTINGS = {
    "@jupyterlab/notebook-extension/tracker.jupyterlab-settings": {
        "windowingMode": "none",
        "recordTiming": True,  # each cell's start and end in the saved file
    },
    "@jupyterlab/apputils-extension/notification.jupyterlab-settings": {
        "fetchNews": "false",
        "checkForUpdates": False,
    },
    "@jupyterlab/docmanager-extension/plugin.jupyterlab-settings": {"autosave": False},
}

_HASH_IMAGES = """(root) => {
  const out = [];
  for (const img of root.querySelectorAll('img')) {
    if (!img.complete || !img.naturalWidth) { out.push('loading'); continue; }
    const c = document.createElement('canvas');
    c.width = img.naturalWidth; c.height = img.naturalHeight;
    const g = c.getContext('2d'); g.drawImage(img, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    let h = 2166136261 >>> 0;
    for (let i = 0; i < d.length; i += 7) { h = Math.imul(h ^ d[i], 16777619) >>> 0; }
    out.push(c.width + 'x' + c.height + ':' + h);
  }
  return out.join('|');
}"""


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Lab:
    """A JupyterLab server on a temporary copy of some notebook folders."""

    def __init__(self, repo: Path, folders=("solutions", "labs"), tmp: Path = None):
        self.root = Path(tmp) / "root"
        for folder in folders:
            if (repo / folder).is_dir():
                shutil.copytree(repo / folder, self.root / folder)
        settings = Path(tmp) / "settings"
        for name, value in LAB_SETTINGS.items():
            path = settings / name
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(json.dumps(value))
        self.port, self.token = _free_port(), "robotlib-browser-test"
        env = {
            **os.environ,
            "JUPYTERLAB_SETTINGS_DIR": str(settings),
            "JUPYTERLAB_WORKSPACES_DIR": str(Path(tmp) / "workspaces"),
            "JUPYTER_RUNTIME_DIR": str(Path(tmp) / "runtime"),
            "MPLBACKEND": "module://matplotlib_inline.backend_inline",
        }
        cmd = [
            sys.executable, "-m", "jupyterlab", "--no-browser", "--allow-root",
            "--ip", "127.0.0.1", f"--port={self.port}",
            f"--ServerApp.token={self.token}", f"--ServerApp.root_dir={self.root}",
            "--LabApp.news_url=", "--ServerApp.open_browser=False",
        ]  # fmt: skip
        self.log = open(Path(tmp) / "jupyterlab.log", "w")  # noqa: SIM115
        self.proc = subprocess.Popen(
            cmd, env=env, stdout=self.log, stderr=subprocess.STDOUT
        )
        self._wait_up()

    def _wait_up(self, timeout: float = 60.0) -> None:
        url = f"http://127.0.0.1:{self.port}/api/status?token={self.token}"
        t0 = time.monotonic()
        while time.monotonic() - t0 < timeout:
            if self.proc.poll() is not None:
                raise RuntimeError("JupyterLab exited; see jupyterlab.log")
            try:
                urllib.request.urlopen(url, timeout=2).read()
                return
            except OSError:
                time.sleep(0.3)
        raise TimeoutError("JupyterLab did not start")

    def url(self, path: str) -> str:
        """The address that opens ``path`` alone, in a workspace of its own."""
        self._workspaces = getattr(self, "_workspaces", 0) + 1
        space = f"w{self._workspaces}"
        return (
            f"http://127.0.0.1:{self.port}/lab/workspaces/{space}/tree/{path}"
            f"?reset&token={self.token}"
        )

    def _api(self, path: str, method: str = "GET"):
        url = f"http://127.0.0.1:{self.port}/api/{path}"
        auth = {"Authorization": f"token {self.token}"}
        req = urllib.request.Request(url, headers=auth, method=method)
        with urllib.request.urlopen(req, timeout=10) as r:
            body = r.read()
        return json.loads(body) if body else None

    def shutdown_kernels(self, notebook: str | None = None) -> None:
        """End the kernel of ``notebook`` (a path in the copy), or every kernel."""
        try:
            if notebook is None:
                for k in self._api("kernels"):
                    self._api(f"kernels/{k['id']}", "DELETE")
                return
            for session in self._api("sessions"):
                if session.get("path") == notebook:
                    self._api(f"sessions/{session['id']}", "DELETE")
        except OSError:
            pass

    def close(self) -> None:
        """Stop the server (its own process only)."""
        self.shutdown_kernels()
        self.proc.terminate()
        try:
            self.proc.wait(timeout=15)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self.log.close()


@dataclass
class Run:
    """What running one notebook in the browser gave."""

    path: str
    first_cell_s: float | None = None
    run_all_s: float | None = None
    finished: bool = False
    errors: list = field(default_factory=list)  # (cell index, ename, text)
    console: list = field(default_factory=list)
    blocked: list = field(default_factory=list)
    panels: list = field(default_factory=list)
    animations: list = field(default_factory=list)
    figures: list = field(default_factory=list)  # (natural, shown) widths, px
    cells_s: list = field(default_factory=list)  # each code cell's run time, s
    notebook: dict = field(default_factory=dict)


class Browser:
    """Headless chromium (Debian's) driven by playwright."""

    def __init__(self, screenshots: Path):
        from playwright.sync_api import sync_playwright

        self.screenshots = Path(screenshots)
        self.screenshots.mkdir(parents=True, exist_ok=True)
        self._pw = sync_playwright().start()
        self.browser = self._pw.chromium.launch(
            executable_path=CHROMIUM,
            headless=True,
            args=[
                "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                "--disable-background-networking", "--disable-component-update",
                "--disable-sync", "--disable-background-timer-throttling",
                "--disable-renderer-backgrounding",
                "--disable-backgrounding-occluded-windows",
            ],
        )  # fmt: skip

    def page(self, run: Run):
        """A new page that records console errors and blocks external requests."""
        context = self.browser.new_context(viewport={"width": 1280, "height": 900})
        page = context.new_page()
        page.set_default_timeout(120_000)  # a loaded 2-core machine renders slowly

        def route(r):
            url = r.request.url
            if url.startswith(("http://127.0.0.1", "ws://127.0.0.1", "data:", "blob:")):
                r.continue_()
            else:
                run.blocked.append(url)
                r.abort()

        page.route("**/*", route)
        page.on(
            "console",
            lambda m: run.console.append(m.text) if m.type == "error" else None,
        )
        page.on("pageerror", lambda e: run.console.append(f"page error: {e}"))
        return page

    def close(self) -> None:
        """Close the browser and playwright's driver."""
        self.browser.close()
        self._pw.stop()


def unexplained_console_errors(run: Run) -> list[str]:
    """Console errors other than those of requests the test blocked."""
    out = []
    for text in run.console:
        blocked = "net::ERR_FAILED" in text or any(u in text for u in run.blocked)
        if not (blocked and run.blocked):
            out.append(text)
    return out


def _menu(page, top: str, item: str) -> None:
    page.locator(".lm-MenuBar-itemLabel", has_text=top).first.click()
    page.locator(".lm-Menu-itemLabel", has_text=item).first.click()


def _prompts(page) -> list[str]:
    return page.eval_on_selector_all(
        ".jp-Notebook .jp-CodeCell .jp-InputPrompt",
        "els => els.map(e => e.textContent.trim())",
    )


def _cell_seconds(cell) -> float | None:
    """A code cell's run time from JupyterLab's timing metadata (None: not run)."""
    from datetime import datetime

    t = cell.get("metadata", {}).get("execution", {})
    start = t.get("iopub.execute_input") or t.get("iopub.status.busy")
    end = t.get("shell.execute_reply")
    if not (start and end):
        return None
    parse = datetime.fromisoformat
    return (
        parse(end.replace("Z", "+00:00")) - parse(start.replace("Z", "+00:00"))
    ).total_seconds()


class _Session:
    """One notebook open in its own page, from Run All to its saved file."""

    def __init__(self, lab: Lab, browser: Browser, path: str):
        self.lab, self.browser, self.path = lab, browser, path
        self.run = Run(path)
        self.page = page = browser.page(self.run)
        page.goto(lab.url(path))
        page.wait_for_selector(".jp-Notebook .jp-CodeCell", timeout=60_000)
        page.wait_for_selector(".jp-Notebook-ExecutionIndicator", timeout=60_000)
        page.wait_for_function(  # the kernel has started and answers
            "() => /\\|\\s*Idle/.test("
            "document.querySelector('#jp-main-statusbar')?.innerText || '')",
            timeout=90_000,
        )
        self.t0 = time.monotonic()
        for _attempt in range(3):
            page.locator(".jp-Notebook").first.click()
            _menu(page, "Run", "Run All Cells")
            started = time.monotonic() + 15
            while time.monotonic() < started:  # until a cell is queued or done
                if any(p not in ("[ ]:", "") for p in _prompts(page)):
                    break
                time.sleep(0.05)
            else:
                continue  # the kernel was not listening yet: ask again
            break

    def poll(self) -> bool:
        """Note the first cell's time; return True once every cell has run."""
        run, page = self.run, self.page
        prompts = _prompts(page)
        if run.first_cell_s is None and prompts and prompts[0] not in ("[*]:", "[ ]:"):
            run.first_cell_s = time.monotonic() - self.t0
        status = page.get_attribute(".jp-Notebook-ExecutionIndicator", "data-status")
        if status == "idle" and not any("*" in p for p in prompts):
            run.finished = True
        run.run_all_s = time.monotonic() - self.t0
        return run.finished

    def finish(self, panel_bound: float) -> Run:
        """Screenshot, check panels and animations, save, read the errors."""
        run, page = self.run, self.page
        stem = self.path.replace("/", "_").removesuffix(".ipynb")
        page.screenshot(path=str(self.browser.screenshots / f"{stem}.png"))
        run.figures = page.eval_on_selector_all(
            ".jp-OutputArea-output img",
            "els => els.filter(e => e.naturalWidth).map("
            "e => [e.naturalWidth, e.getBoundingClientRect().width])",
        )
        if run.finished:
            shots = self.browser.screenshots / stem
            run.panels = check_panels(page, shots, panel_bound)
            run.animations = check_animations(page)
        page.keyboard.press("Control+s")
        page.wait_for_timeout(1500)
        run.notebook = json.loads((self.lab.root / self.path).read_text())
        code = [c for c in run.notebook["cells"] if c["cell_type"] == "code"]
        run.cells_s = [_cell_seconds(c) for c in code]
        if run.cells_s and run.cells_s[0] is not None:
            run.first_cell_s = run.cells_s[0]  # as JupyterLab timed it
        for i, cell in enumerate(code):
            for out in cell.get("outputs", []):
                if out.get("output_type") == "error":
                    text = "\n".join(out.get("traceback", []))
                    run.errors.append((i, out.get("ename"), text))
        page.context.close()
        self.lab.shutdown_kernels(self.path)  # the next notebooks get the cores
        return run


def run_notebooks(
    lab: Lab,
    browser: Browser,
    paths: list[str],
    timeout: float,
    panel_bound: float = 60.0,
    at_once: int = 2,
) -> list[Run]:
    """Open each notebook, Run All Cells, wait (``timeout`` s each), check, save.

    Up to ``at_once`` notebooks run at the same time (one kernel per core);
    panels are checked once a notebook is done, while no other notebook of
    the batch is running. Returns the `Run` of each path, in order; its
    ``notebook`` is the saved file (outputs and all), ``errors`` the error
    outputs in it.
    """
    runs: dict[str, Run] = {}
    todo = list(paths)
    while todo:
        batch = [_Session(lab, browser, p) for p in todo[:at_once]]
        todo = todo[at_once:]
        waiting = list(batch)
        while waiting:
            for session in list(waiting):
                late = time.monotonic() - session.t0 > timeout
                if session.poll() or late:
                    waiting.remove(session)
            time.sleep(0.25)
        for session in batch:
            runs[session.path] = session.finish(panel_bound)
    return [runs[p] for p in paths]


def run_notebook(lab, browser, path, timeout, panel_bound: float = 60.0) -> Run:
    """Run one notebook (see `run_notebooks`)."""
    return run_notebooks(lab, browser, [path], timeout, panel_bound)[0]


_PANEL_ERROR = """(root) => {
  const e = root.querySelector(
    '[data-mime-type="application/vnd.jupyter.stderr"], .jp-RenderedText.jp-mod-error');
  if (!e) return null;
  const lines = e.innerText.trim().split('\\n').filter(l => l.trim());
  return lines.slice(-1)[0] || 'error';
}"""

_OUTSIDE = """(root, moved) => {
  const parts = [];
  for (const el of root.querySelectorAll('*')) {
    if (moved.contains(el)) continue;
    parts.push(el.tagName + '.' + el.className + (el.style.opacity || ''));
  }
  const walk = document.createTreeWalker(root, NodeFilter.SHOW_TEXT);
  for (let n = walk.nextNode(); n; n = walk.nextNode()) {
    if (!moved.contains(n)) parts.push(n.textContent);
  }
  return parts.join('|');
}"""
"""The panel's text and classes outside the slider that moved (whose own
readout changes at once, which is no sign that the panel is running)."""

_AT_TOP = """(h) => parseFloat(h.getAttribute('aria-valuenow'))
  >= parseFloat(h.getAttribute('aria-valuemax'))"""


def check_panels(page, stem: Path, bound: float = 60.0) -> list[dict]:
    """Move the first enabled slider of each panel; time feedback and redraw.

    A panel is an output holding both a slider and an image, found once
    before any slider moves (so a panel whose image is replaced while it
    redraws, or by an error, is still the same panel). Its first enabled
    slider moves one step right (left when it sits at its maximum). Returns,
    per panel, ``feedback_s`` (until the panel's text or classes change: a
    status line, a greyed figure, or the new figure itself; the moved
    slider's own readout does not count), ``redraw_s`` (until its image's pixels
    change; None if they did not within ``bound`` s), ``error`` (the last
    line of an error the panel shows instead, else None) and the slider's
    label.
    """
    results = []
    outputs = page.locator(".jp-OutputArea-output:has(.widget-slider):has(img)")
    for k, panel in enumerate(outputs.element_handles()):
        panel.scroll_into_view_if_needed()
        handles = panel.query_selector_all(
            ".widget-slider:not(.mod-disabled) .noUi-handle"
        )
        if not handles:
            continue
        handle = handles[0]
        slider = handle.evaluate_handle("h => h.closest('.widget-slider')")
        label = slider.evaluate(
            "s => s.querySelector('.widget-label')?.textContent || ''"
        )
        key = "ArrowLeft" if handle.evaluate(_AT_TOP) else "ArrowRight"
        before_pixels = panel.evaluate(_HASH_IMAGES)
        before_text = panel.evaluate(_OUTSIDE, slider)
        panel.screenshot(path=f"{stem}-panel{k}-before.png")
        handle.focus()
        t0 = time.monotonic()
        page.keyboard.press(key)
        feedback = redraw = error = None
        while time.monotonic() - t0 < bound:
            now = time.monotonic() - t0
            if feedback is None:
                if panel.evaluate(_OUTSIDE, slider) != before_text:
                    feedback = now
            error = panel.evaluate(_PANEL_ERROR)
            if error is not None:
                break
            pixels = panel.evaluate(_HASH_IMAGES)
            if pixels not in (before_pixels, "") and "loading" not in pixels:
                redraw = now
                feedback = now if feedback is None else feedback  # the answer itself
                break
            time.sleep(0.02)
        if redraw is not None or error is not None:
            page.wait_for_timeout(300)
            panel.screenshot(path=f"{stem}-panel{k}-after.png")
        results.append(
            {"panel": k, "slider": label.strip(), "key": key, "feedback_s": feedback,
             "redraw_s": redraw, "error": error}
        )  # fmt: skip
    return results


def check_animations(page, wait: float = 2.0) -> list[dict]:
    """Press play on each jshtml player; return its frame before and after."""
    results = []
    players = page.locator(".jp-OutputArea-output .animation")
    for k, player in enumerate(players.element_handles()):
        player.scroll_into_view_if_needed()
        frame = player.query_selector("input[type=range]")
        start = int(frame.input_value())
        player.query_selector("button[title='Play']").click()
        page.wait_for_timeout(int(wait * 1000))
        results.append({"player": k, "start": start, "after": int(frame.input_value())})
    return results
