"""Driving JupyterLab in headless Chromium: the helpers of the browser test.

`Lab` starts JupyterLab on a copy of the notebooks (so autosave never
writes into the repository) with settings that render every cell and fetch
no news; `Browser` opens Debian's chromium through playwright (its
executable path set: no browser download) with every non-loopback request
blocked. `run_notebook` opens a notebook, runs all cells from the menu,
saves it and returns what happened; `run_notebooks` runs several, two at a
time, and loads JupyterLab in a page once: a page whose notebook was checked
opens the next one itself (``window.jupyterapp``), which takes a few
seconds where a new page took 20-40 on a loaded machine. The panels and
players are checked by `tests.browser_panels` (`check_panels`,
`check_animations`).
"""

from __future__ import annotations

import importlib.util
import json
import os
import re
import secrets
import shutil
import socket
import subprocess
import sys
import threading
import time
import urllib.request
from dataclasses import dataclass, field
from pathlib import Path

from robotlib.course.cpu import descendants
from tests.browser_panels import check_animations, check_panels
from tests.contention import Clock

CHROMIUM = "/usr/bin/chromium"


def have_browser() -> bool:
    """Can the browser test run here (playwright and Debian's chromium)?"""
    playwright = importlib.util.find_spec("playwright") is not None
    return playwright and Path(CHROMIUM).exists()


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


def notebook(sources: list[str]) -> dict:
    """A notebook (nbformat 4, as JSON data) of code cells with these sources.

    For a test or bench to write beside the labs and open in the page.
    """
    cells = [
        {
            "cell_type": "code",
            "metadata": {},
            "outputs": [],
            "execution_count": None,
            "id": f"c{i}",
            "source": source,
        }
        for i, source in enumerate(sources)
    ]
    kernel = {"name": "python3", "display_name": "Python 3", "language": "python"}
    return {
        "cells": cells,
        "metadata": {"kernelspec": kernel},
        "nbformat": 4,
        "nbformat_minor": 5,
    }


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Lab:
    """A JupyterLab server on a temporary copy of some notebook folders."""

    def __init__(
        self,
        repo: Path,
        folders=("solutions", "labs"),
        tmp: Path = None,
        env: dict | None = None,
    ):
        self.root = Path(tmp) / "root"
        for folder in folders:
            if (repo / folder).is_dir():
                shutil.copytree(repo / folder, self.root / folder)
        settings = Path(tmp) / "settings"
        for name, value in LAB_SETTINGS.items():
            path = settings / name
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(json.dumps(value))
        self.token = secrets.token_hex(16)  # another suite's server refuses it
        env = {
            **os.environ,
            "JUPYTERLAB_SETTINGS_DIR": str(settings),
            "JUPYTERLAB_WORKSPACES_DIR": str(Path(tmp) / "workspaces"),
            "JUPYTER_RUNTIME_DIR": str(Path(tmp) / "runtime"),
            "MPLBACKEND": "module://matplotlib_inline.backend_inline",
            **(env or {}),  # the kernels inherit it
        }
        self.log = open(Path(tmp) / "jupyterlab.log", "w")  # noqa: SIM115
        for attempt in range(3):  # a port taken since it was found free: another
            self.port = _free_port()
            cmd = [
                sys.executable, "-m", "jupyterlab", "--no-browser", "--allow-root",
                "--ip", "127.0.0.1", f"--port={self.port}",
                # on that port or not at all (never another suite's server's)
                "--ServerApp.port_retries=0",
                f"--ServerApp.token={self.token}", f"--ServerApp.root_dir={self.root}",
                "--LabApp.news_url=", "--ServerApp.open_browser=False",
                # window.jupyterapp: a page that has loaded JupyterLab opens the
                # next notebook itself (no second load of the whole application)
                "--LabApp.expose_app_in_browser=True",
            ]  # fmt: skip
            self.proc = subprocess.Popen(
                cmd, env=env, stdout=self.log, stderr=subprocess.STDOUT
            )
            try:
                self._wait_up()
                return
            except RuntimeError:
                if attempt == 2:
                    raise

    def _wait_up(self, timeout: float = 60.0) -> None:
        """Wait for the server to answer (``timeout``: quiet s, `tests.contention`)."""
        url = f"http://127.0.0.1:{self.port}/api/status?token={self.token}"
        clock = Clock()
        while clock.elapsed() < timeout:
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

    def kernel_list_races(self) -> set[str]:
        """Addresses of kernel lists the server failed on while a kernel started.

        jupyter_server lists a kernel that is still starting, before its
        ``last_activity`` is set, and answers that ``GET /api/kernels`` with
        a 500 (a race of the server's, in its log as a ``TraitError``). The
        page asks again a moment later; nothing a student does causes it.
        """
        lines = Path(self.log.name).read_text(errors="replace").splitlines()
        found = set()
        for i, line in enumerate(lines):
            m = _UNCAUGHT.search(line)
            if m and any(_RACE in later for later in lines[i + 1 : i + 60]):
                found.add(m.group(1))
        return found

    def close(self, keep_log: Path | None = None) -> None:
        """Stop the server (its own process only); copy its log to ``keep_log``."""
        self.shutdown_kernels()
        self.proc.terminate()
        try:
            self.proc.wait(timeout=15)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self.log.close()
        if keep_log is not None:
            Path(keep_log).parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(self.log.name, keep_log)


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
    open_s: float | None = None  # page load to an idle kernel, s
    check_s: float | None = None  # screenshots, panels, animations and save, s
    check_parts: dict = field(default_factory=dict)  # check_s by part, s
    notebook: dict = field(default_factory=dict)


def _driver(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            return b"run-driver" in f.read()
    except OSError:
        return False


class Browser:
    """Headless chromium (Debian's) driven by playwright (``driver``: its pid)."""

    def __init__(self, screenshots: Path):
        from playwright.sync_api import sync_playwright

        self.screenshots = Path(screenshots)
        self.screenshots.mkdir(parents=True, exist_ok=True)
        before = set(descendants(os.getpid()))
        self._pw = sync_playwright().start()
        self.driver = next(  # playwright's driver: chromium runs below it
            (p for p in descendants(os.getpid()) if p not in before and _driver(p)),
            None,
        )
        self.browser = self._pw.chromium.launch(
            executable_path=CHROMIUM,
            headless=True,
            args=[
                "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                "--disable-background-networking", "--disable-component-update",
                "--disable-sync", "--disable-background-timer-throttling",
                "--disable-renderer-backgrounding",
                "--disable-backgrounding-occluded-windows",
                # Every request but loopback goes to a proxy that is not there
                # (chromium never proxies loopback), so nothing leaves the
                # machine without passing every request through this process (as
                # a playwright route would, slowly, and only while it is called).
                f"--proxy-server=http://127.0.0.1:{_closed_port()}",
            ],
        )  # fmt: skip

    def page(self, run: Run):
        """A new page that records console errors and the external requests it tried.

        They go to ``run``, or to the run `attach` gave the page since.
        """
        # A context of its own: two JupyterLab pages of one context opening
        # at once fight over their window name (a page error).
        context = self.browser.new_context(viewport={"width": 1280, "height": 900})
        page = context.new_page()
        page.set_default_timeout(120_000)  # a loaded 2-core machine renders slowly
        now = self._runs = getattr(self, "_runs", {})
        now[page] = run

        def request(r):
            if not r.url.startswith(_LOCAL):
                now[page].blocked.append(r.url)  # it fails: see the proxy in __init__

        page.on("request", request)

        def console(m):
            if m.type == "error":  # with the address, so a failed request says which
                url = (m.location or {}).get("url", "")
                now[page].console.append(f"{m.text} ({url})" if url else m.text)

        page.on("console", console)
        page.on("pageerror", lambda e: now[page].console.append(f"page error: {e}"))
        return page

    def attach(self, page, run: Run) -> None:
        """Record ``page``'s console errors and requests in ``run`` from now on."""
        self._runs[page] = run

    def close(self) -> None:
        """Close the browser and playwright's driver."""
        self.browser.close()
        self._pw.stop()


_LOCAL = ("http://127.0.0.1", "ws://127.0.0.1", "data:", "blob:")
_BLOCKED = ("net::ERR_PROXY_CONNECTION_FAILED", "net::ERR_TUNNEL_CONNECTION_FAILED",
            "net::ERR_FAILED")  # fmt: skip


def _closed_port() -> int:
    """A loopback port nothing listens on (bound, then released at once)."""
    return _free_port()


_UNCAUGHT = re.compile(r"Uncaught exception GET (/api/kernels\?\S*) ")
_RACE = "'last_activity' trait of a ServerKernelManager instance expected a datetime"


def unexplained_console_errors(run: Run, races: set[str] = frozenset()) -> list[str]:
    """Console errors other than those of requests the test blocked.

    ``races``: kernel-list addresses the server failed on in its own race
    (`Lab.kernel_list_races`); a 500 for one of those is explained too.
    """
    out = []
    for text in run.console:
        blocked = any(e in text for e in _BLOCKED) or any(
            u in text for u in run.blocked
        )
        race = "status of 500" in text and any(f"{u})" in text for u in races)
        if not (blocked and run.blocked) and not race:
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


def _read_saved(page, saved: Path, limit: float = 30.0) -> dict:
    """Read a notebook the server is writing: once it is whole JSON.

    jupyter_server's "atomic" save keeps a backup copy and writes the file
    in place, so a large notebook (Lab 4's player is megabytes) can be read
    half-written on a loaded machine; read again until it parses.
    """
    t0 = time.monotonic()
    while True:
        page.wait_for_timeout(200)
        try:
            return json.loads(saved.read_text())
        except ValueError:
            if time.monotonic() - t0 > limit:
                raise


_READY = """() => !!document.querySelector('.jp-Notebook .jp-CodeCell')
  && !!document.querySelector('.jp-Notebook-ExecutionIndicator')
  && /\\|\\s*Idle/.test(
    document.querySelector('#jp-main-statusbar')?.innerText || '')"""
"""The notebook is shown and its kernel has started and answers."""


_OPEN = """(path) => {
  window.jupyterapp.commands.execute('docmanager:open', { path });
}"""
"""Open a notebook in a page that has JupyterLab loaded (not waiting for it)."""
_CLOSE = """() => {
  for (const w of [...window.jupyterapp.shell.widgets('main')]) w.dispose();
}"""
"""Close every document of the page, without asking (the notebook is saved)."""


class _Session:
    """One notebook open in its own page, from Run All to its saved file.

    Nothing here blocks for long, so several notebooks are watched at once:
    `ready` says when the page is up with an idle kernel (a page opens while
    other notebooks run), `start` runs all cells, `poll` says when they are
    done.
    """

    OPEN_LIMIT = 150.0  # quiet s (tests.contention) for JupyterLab's page and kernel

    def __init__(self, lab: Lab, browser: Browser, path: str, page=None):
        self.lab, self.browser, self.path = lab, browser, path
        self.run = Run(path)
        self.opened = time.monotonic()
        self.opening = Clock()  # OPEN_LIMIT
        self.t0: float | None = None  # when Run All was asked
        self.running: Clock | None = None  # since Run All was asked
        self._asked = 0.0  # the last time Run All was asked
        self._attempts = 0
        self._running = False
        self.shutdown: threading.Thread | None = None  # the kernel's, once checked
        if page is None:
            self.page = browser.page(self.run)
            self.page.goto(lab.url(path), wait_until="commit")
        else:  # a page whose last notebook was checked and closed
            self.page = page
            browser.attach(page, self.run)
            page.evaluate(_OPEN, path)

    def ready(self) -> bool:
        """Return True once the notebook shows and its kernel is idle."""
        if self.run.open_s is not None:
            return True
        from playwright.sync_api import Error

        try:
            shown = self.page.evaluate(_READY)
        except Error:  # still navigating
            shown = False
        if shown:
            self.run.open_s = time.monotonic() - self.opened
            return True
        if self.opening.elapsed() > self.OPEN_LIMIT:
            raise TimeoutError(
                f"{self.path}: JupyterLab did not open it with a kernel in "
                f"{self.opening}"
            )
        return False

    def start(self) -> None:
        """Run All Cells from the menu (asked again if the kernel did not hear)."""
        self.page.locator(".jp-Notebook").first.click()
        _menu(self.page, "Run", "Run All Cells")
        self._asked = time.monotonic()
        self.t0 = self.t0 or self._asked
        self.running = self.running or Clock()
        self._attempts += 1

    def poll(self) -> bool:
        """Note the first cell's time; return True once every cell has run."""
        run, page = self.run, self.page
        prompts = _prompts(page)
        if not self._running:  # until a cell is queued or done
            if any(p not in ("[ ]:", "") for p in prompts):
                self._running = True
            elif time.monotonic() - self._asked > 15 and self._attempts < 3:
                self.start()  # the kernel was not listening yet: ask again
                return False
            else:
                return False
        if run.first_cell_s is None and prompts and prompts[0] not in ("[*]:", "[ ]:"):
            run.first_cell_s = time.monotonic() - self.t0
        status = page.get_attribute(".jp-Notebook-ExecutionIndicator", "data-status")
        if status == "idle" and not any("*" in p for p in prompts):
            run.finished = True
        run.run_all_s = time.monotonic() - self.t0
        return run.finished

    def finish(
        self, panel_bound: float, feedback_bound: float = 1.0, busy_done=None
    ) -> Run:
        """Screenshot, check panels and animations, save, read the errors.

        The kernel is shut down in the background (`Lab.shutdown_kernels`).
        """
        run, page = self.run, self.page
        started = time.monotonic()
        parts, mark = run.check_parts, [started]

        def part(name):
            now = time.monotonic()
            parts[name] = round(now - mark[0], 3)
            mark[0] = now

        stem = self.path.replace("/", "_").removesuffix(".ipynb")
        page.screenshot(path=str(self.browser.screenshots / f"{stem}.png"))
        run.figures = page.eval_on_selector_all(
            ".jp-OutputArea-output img",
            "els => els.filter(e => e.naturalWidth).map("
            "e => [e.naturalWidth, e.getBoundingClientRect().width])",
        )
        part("screenshot")
        if run.finished:
            shots = self.browser.screenshots / stem
            run.panels = check_panels(
                page, shots, panel_bound, feedback_bound, busy_done
            )
            part("panels")
            run.animations = check_animations(page)
            part("animations")
        saved = self.lab.root / self.path
        before = saved.stat().st_mtime_ns
        page.keyboard.press("Control+s")
        waited = time.monotonic()
        while saved.stat().st_mtime_ns == before and time.monotonic() - waited < 15:
            page.wait_for_timeout(50)  # (playwright's calls keep the page served)
        run.notebook = _read_saved(page, saved)
        part("save")
        code = [c for c in run.notebook["cells"] if c["cell_type"] == "code"]
        run.cells_s = [_cell_seconds(c) for c in code]
        if run.cells_s and run.cells_s[0] is not None:
            run.first_cell_s = run.cells_s[0]  # as JupyterLab timed it
        for i, cell in enumerate(code):
            for out in cell.get("outputs", []):
                if out.get("output_type") == "error":
                    text = "\n".join(out.get("traceback", []))
                    run.errors.append((i, out.get("ename"), text))
        page.evaluate(_CLOSE)  # the page opens the next notebook
        self.shutdown = threading.Thread(  # the next notebooks get the cores
            target=self.lab.shutdown_kernels, args=(self.path,), daemon=True
        )
        self.shutdown.start()  # (the server waits for the kernel to exit)
        part("close")
        run.check_s = time.monotonic() - started
        return run


def run_notebooks(
    lab: Lab,
    browser: Browser,
    paths: list[str],
    timeout: float,
    panel_bound: float = 60.0,
    at_once: int = 2,
    feedback_bound: float = 1.0,
    stop: threading.Event | None = None,
) -> list[Run]:
    """Open each notebook, Run All Cells, wait (``timeout`` quiet s each), check, save.

    Up to ``at_once`` notebooks run at the same time (one kernel per core),
    in the order given, and the next one's page opens meanwhile: as soon as
    one has finished, the next one starts its Run All, and the finished one
    is checked (its panels and animations) while the others run. Returns the
    `Run` of each path, in order; its ``notebook`` is the saved file
    (outputs and all), ``errors`` the error outputs in it. Once ``stop`` is
    set, nothing more is waited for and an empty list is returned.
    """
    runs: dict[str, Run] = {}
    todo, opening, running, done = list(paths), [], [], []
    free = []  # pages whose notebook was checked and closed
    busy_done: set = set()  # panel classes whose second move was made

    def start_ready():
        for session in list(opening):
            if session.ready() and len(running) < at_once:  # (ready: times the open)
                opening.remove(session)
                session.start()
                running.append(session)

    while todo or opening or running:
        if stop is not None and stop.is_set():
            return []
        if todo and len(opening) + len(running) < at_once + 1:
            page = free.pop() if free else None  # one opens ahead
            opening.append(_Session(lab, browser, todo.pop(0), page))
        start_ready()
        for session in list(running):
            late = session.running.elapsed() > timeout  # quiet s: tests.contention
            if session.poll() or late:
                running.remove(session)
                start_ready()  # the freed kernel's successor runs during the checks
                runs[session.path] = session.finish(
                    panel_bound, feedback_bound, busy_done
                )
                done.append(session)
                free.append(session.page)
        time.sleep(0.25)
    for page in free:
        page.context.close()
    for session in done:
        session.shutdown.join(30)
    return [runs[p] for p in paths]


def run_notebook(lab, browser, path, timeout, panel_bound: float = 60.0) -> Run:
    """Run one notebook (see `run_notebooks`)."""
    return run_notebooks(lab, browser, [path], timeout, panel_bound)[0]
