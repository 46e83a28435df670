"""The one call every lab notebook starts with: ``robotlib.notebook.setup()``.

It applies the course's figure style (`robotlib.plotting.style`), seeds what
can be seeded, says unsolved exercises plainly (`explain_unsolved`, and
`demo` for a demonstration that calls a student's code), and
compiles (or loads from numba's cache) the kernels the lab will use, with a
progress bar naming what compiles, so that later cells show only teaching
code and graded cells do not pay for compilation::

    import robotlib.notebook
    robotlib.notebook.loading()  # a line that moves until setup() is done
    import matplotlib.pyplot as plt
    ...
    rng = robotlib.notebook.setup(seed=0, warm=("sim",))

`robotlib warmup` (this module's command) compiles every part of `WARMUPS`
once, into numba's cache: the README's set-up command and CI run it, so a
student's first cell only loads. Kernels compile lazily (on first call), so
a lab compiles only the parts it names. `progress` is the bar for long cells.

Sits on top (layer 7): imports any layer, inside functions, so that
importing it stays cheap; nothing imports it.
"""

from __future__ import annotations

import json
import os
import random
import re
import sys
import threading
import time
import warnings
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np

from . import _loading
from ._ipython import in_kernel, ipython_shell
from ._versions import version_mismatch
from .warmups import WARMUPS

__all__ = [
    "loading",
    "setup",
    "warm_up",
    "WARMUPS",
    "progress",
    "explain_unsolved",
    "demo",
    "warmed_parts",
    "add_arguments",
    "run",
]


def _steps(parts: Iterable[str]) -> list[tuple[str, str, Callable[[], None]]]:
    out = []
    for part in parts:
        if part not in WARMUPS:
            raise ValueError(f"unknown warm-up {part!r}; choose from {sorted(WARMUPS)}")
        entry = WARMUPS[part]
        steps = [(part, entry)] if callable(entry) else list(entry)
        out.extend((part, label, fn) for label, fn in steps)
    return out


class _CompileWatch:
    """Counts numba compilations (cache misses) and names the one running."""

    def __init__(self, on_start: Callable[[str], None] | None = None):
        self.compiled: list[str] = []
        self.on_start = on_start

    def __enter__(self):
        from numba.core import event

        watch = self

        class Listener(event.Listener):
            def on_start(self, ev):
                disp = ev.data.get("dispatcher")
                func = getattr(disp, "py_func", None)
                module = getattr(func, "__module__", "") or ""
                if not module.startswith("robotlib"):
                    return  # numba's own helpers, compiled along with a kernel
                name = f"{module.rpartition('.')[2]}.{func.__name__}"
                watch.compiled.append(name)
                if watch.on_start is not None:
                    watch.on_start(name)

            def on_end(self, ev):
                pass

        self._listener = Listener()
        event.register("numba:compile", self._listener)
        return self

    def __exit__(self, *exc):
        from numba.core import event

        event.unregister("numba:compile", self._listener)
        return False


def progress(iterable=None, desc: str = "", total: int | None = None, **kw):
    """Return a progress bar for a long cell: tqdm's notebook bar, text headless.

    In a notebook the bar's elapsed time moves every second (`_tick`), so
    a cell whose steps take long still shows that it runs; a bar still open
    when its cell ends (its loop stopped on an error, or on a student's
    unsolved function in a `demo`) is hidden then (`_hide_left_open`): the
    error or the one-line message below it says what happened.

    Parameters
    ----------
    iterable : iterable, optional
        What to iterate over (as ``tqdm``).
    desc : str
        What the bar counts.
    total : int, optional
        Number of items, if ``len(iterable)`` does not tell.
    **kw
        Passed to ``tqdm``.

    Returns
    -------
    tqdm.tqdm
    """
    kw.setdefault("leave", True)
    if not in_kernel():
        from tqdm import tqdm

        return tqdm(iterable, desc=desc, total=total, **kw)
    from tqdm.notebook import tqdm

    bar = tqdm(iterable, desc=desc, total=total, **kw)
    _tick(bar)
    _hide_left_open(bar)
    return bar


_LEFT_OPEN: dict = {"bars": [], "hooked": False}  # the running cell's bars


def _hide_left_open(bar) -> None:
    """Hide ``bar`` when its cell ends if it is short of its total then.

    A loop that stopped early leaves its bar at 0/N (open, or closed in red
    when tqdm collects the loop): under "This demonstration needs your ..."
    it looked stuck, or broken.
    """
    shell = ipython_shell()
    if shell is None:
        return
    if not _LEFT_OPEN["hooked"]:
        shell.events.register("post_run_cell", _hide_open_bars)
        _LEFT_OPEN["hooked"] = True
    _LEFT_OPEN["bars"].append(bar)


def _hide_open_bars(*_args) -> None:
    bars = _LEFT_OPEN["bars"]
    while bars:
        bar = bars.pop()
        if bar.total and bar.n < bar.total:
            bar.container.layout.display = "none"
            bar.close()  # if still open: its ticks stop


def _tick(bar, every: float = 1.0) -> None:
    """Redraw ``bar`` every ``every`` s (its elapsed time) from a thread.

    The thread ends when the bar closes, or when the cell that made it has
    finished (a bar left open by an error).
    """
    shell = ipython_shell()
    cell = getattr(shell, "execution_count", None)

    def run() -> None:
        while not bar.disable:
            time.sleep(every)
            if bar.disable or getattr(shell, "execution_count", None) != cell:
                return
            bar.refresh()

    threading.Thread(target=run, name="progress-tick", daemon=True).start()


_BAR = "{desc}: {n}/{total} steps |{bar}| {elapsed}{postfix}"


_JITTED = re.compile(rb"^\s*@(nb\.|numba\.)?njit\b", re.MULTILINE)


def _warm_key(package: Path) -> str:
    """Hash what compiled kernels depend on (names `_stamp_file`).

    numba's, NumPy's and Python's versions, the kernels' sources
    (`robotlib._kernel_cache.kernel_sources` and any other module with an
    ``@nb.njit`` function) and what each part warms (``warmups.py``), by
    content: a ``git pull`` that changes only other files (a docstring, a
    plot) keeps the parts warm, so a lab's first cell does not warm them
    again.
    """
    import hashlib

    import numba

    from ._kernel_cache import kernel_sources

    key = hashlib.sha1(f"{numba.__version__} {np.__version__} {sys.version}".encode())
    sources = set(kernel_sources(package)) | {package / "warmups.py"}
    sources |= {p for p in package.rglob("*.py") if _JITTED.search(p.read_bytes())}
    for path in sorted(p for p in sources if p.is_file()):
        key.update(f"{path.relative_to(package)}\0".encode() + path.read_bytes())
    return key.hexdigest()[:16]


def _stamp_file() -> Path:
    """Where `warm_up` notes which parts are in numba's cache for these kernels."""
    import numba

    root = Path(__file__).resolve().parent
    base = Path(numba.config.CACHE_DIR) if numba.config.CACHE_DIR else root
    return base / "__pycache__" / f"robotlib-warm-{_warm_key(root)}.json"


def warmed_parts() -> set[str]:
    """Return the parts of `WARMUPS` already compiled into numba's cache.

    A part counts once `warm_up` has run it against the installed kernels
    (a change to a kernel's source, to `robotlib.warmups`, or to numba's,
    NumPy's or Python's version starts afresh; see `_warm_key`).
    """
    try:
        return set(json.loads(_stamp_file().read_text()))
    except (OSError, ValueError):
        return set()


def _note_warmed(parts) -> None:
    try:
        path = _stamp_file()
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(sorted(warmed_parts() | set(parts))))
    except OSError:  # a read-only install: warm again next time
        pass


def warm_up(parts: Iterable[str] = ("sim",), show: bool = True) -> dict[str, float]:
    """Run the numba kernels of ``parts`` once (compiling or loading them).

    When something has to compile (numba's cache is cold or stale), a
    progress bar shows which part and kernel compiles and how many steps are
    done; when everything loads from the cache, nothing is shown.

    Parameters
    ----------
    parts : iterable of str
        Keys of `WARMUPS`.
    show : bool
        Show the progress bar when compiling.

    Returns
    -------
    dict
        Seconds spent on each part.
    """
    steps = _steps(parts)
    spent: dict[str, float] = {}
    bar = None
    t_all = time.perf_counter()

    def started(kernel: str) -> None:
        nonlocal bar
        if not show:
            return
        if bar is None:
            bar = progress(
                total=len(steps), desc="compiling kernels (once)", bar_format=_BAR
            )
            bar.update(done)
        bar.set_postfix_str(f"{current}: {kernel}", refresh=True)

    with _CompileWatch(started) as watch:
        for index, (part, label, fn) in enumerate(steps):
            done = index
            current = label if label == part else f"{part}, {label}"
            if bar is not None:
                bar.set_postfix_str(current, refresh=True)
            t0 = time.perf_counter()
            fn()
            spent[part] = spent.get(part, 0.0) + time.perf_counter() - t0
            if bar is not None:
                bar.update(1)
    if bar is not None:
        n = len(watch.compiled)
        bar.set_postfix_str(
            f"{n} kernels compiled in {time.perf_counter() - t_all:.0f} s; "
            "next time they load from the cache",
            refresh=True,
        )
        bar.close()
    _note_warmed(spent)
    return spent


def loading(every: float = 0.5) -> None:
    """Show a line that moves while a lab's first cell loads, until `setup` ends it.

    ``1.5 s: importing matplotlib ...``: the seconds since the call and the
    package importing now (or `setup`'s step), redrawn every ``every`` s
    from a thread, so that a first cell on a slow or busy machine shows
    that it works; `setup` ends it with ``Ready (2.1 s of imports and
    set-up).``, and the end of its cell with ``stopped after ...`` (an error
    before `setup`). Nothing outside a Jupyter kernel.

    Parameters
    ----------
    every : float
        Seconds between redraws.
    """
    if not in_kernel():
        return
    _loading.start(ipython_shell(), every)


def setup(
    seed: int = 0,
    warm: Iterable[str] = ("sim",),
    style: bool = True,
    requires: str | None = None,
) -> np.random.Generator:
    """Prepare a lab notebook: style, seeds, plain unsolved errors, warm kernels.

    Ends the line `loading` showed with the seconds the cell took.

    Parameters
    ----------
    seed : int
        Seeds Python's `random` and NumPy's legacy global generator (for any
        student code that uses them) and the returned generator.
    warm : iterable of str
        Kernels to compile or load now (keys of `WARMUPS`: ``"sim"``,
        ``"mcl"``, ``"mapping"``, ``"models"``, ...); empty for none.
    style : bool
        Apply the course's figure style (`robotlib.plotting.style`). The
        backend is left to Jupyter (inline) or to ``MPLBACKEND`` (``Agg``
        in CI and grading).
    requires : str, optional
        The ``"MAJOR.MINOR"`` robotlib the lab was released for: a warning
        when the installed one does not fit (`version_mismatch`).

    Returns
    -------
    numpy.random.Generator
        ``numpy.random.default_rng(seed)``, for the notebook's own draws.
    """
    if requires is not None and (message := version_mismatch(requires)):
        warnings.warn(message, RuntimeWarning, stacklevel=2)
    if style:
        import matplotlib as mpl

        from .plotting import style as course_style

        if not os.environ.get("DISPLAY") and "MPLBACKEND" not in os.environ:
            if ipython_shell() is None:
                mpl.use("Agg")
        course_style.use()
    random.seed(seed)
    np.random.seed(seed)  # noqa: NPY002 - only for students' legacy calls
    np.set_printoptions(precision=4, suppress=True)
    explain_unsolved()
    _loading.now("checking numba's cache")
    cold = [part for part in warm if part not in warmed_parts()]
    if cold and not os.environ.get("ROBOTLIB_SKIP_WARM_UP"):  # set by robotlib
        _loading.now("compiling kernels: see the bar below")
        warm_up(cold)  # a cold cache: compile now, with a progress bar (grade's
    # sandboxes set it when their copy of the numba cache holds the kernels)
    _notice_compiling()  # any later cell that compiles says so
    _loading.loaded()
    return np.random.default_rng(seed)


_NOTICE: dict = {}


def _notice_compiling() -> None:
    """Show a progress line in any cell that compiles robotlib kernels.

    With a warm cache (`robotlib warmup`) kernels load when first used and
    nothing shows; a kernel that must compile names itself in a bar below
    the running cell, with how many compiled so far and for how long. With
    ``ROBOTLIB_COMPILE_LOG`` set, each such kernel's name is also appended
    to that file (the notebook tests check that warm-up left none).
    """
    shell = ipython_shell()
    if shell is None or _NOTICE:
        return
    from numba.core import event

    state = {"bar": None, "n": 0, "t0": 0.0}

    class Listener(event.Listener):
        def on_start(self, ev):
            func = getattr(ev.data.get("dispatcher"), "py_func", None)
            module = getattr(func, "__module__", "") or ""
            if not module.startswith("robotlib"):
                return
            name = f"{module.rpartition('.')[2]}.{func.__name__}"
            log = os.environ.get("ROBOTLIB_COMPILE_LOG")
            if log:  # the notebook tests: nothing may compile after warm-up
                with open(log, "a", encoding="utf-8") as f:
                    f.write(name + "\n")
            if threading.current_thread() is not threading.main_thread():
                return  # a panel's worker: its own status line says it is busy
            if state["bar"] is None:
                state["t0"], state["n"] = time.perf_counter(), 0
                state["bar"] = progress(
                    desc="compiling kernels (once, then cached)",
                    bar_format="{desc}: {n} done{postfix}",
                )
            state["n"] += 1
            state["bar"].set_postfix_str(
                f"now {name}, {time.perf_counter() - state['t0']:.0f} s",
                refresh=False,
            )
            state["bar"].update(1)

        def on_end(self, ev):
            pass

    def close(*_args) -> None:  # the cell ended: say what compiled, not "now ..."
        bar = state["bar"]
        if bar is not None:
            seconds = time.perf_counter() - state["t0"]
            bar.set_postfix_str(
                f"{state['n']} compiled in {seconds:.0f} s; next time they load "
                "from the cache",
                refresh=False,
            )
            bar.close()
            state["bar"] = None

    _NOTICE["listener"] = Listener()
    event.register("numba:compile", _NOTICE["listener"])
    shell.events.register("post_run_cell", close)


def explain_unsolved(shell=None) -> bool:
    """Make a ``NotImplementedError`` from an unsolved exercise a short message.

    Installs an IPython handler: when the error comes from a function defined
    in a notebook cell (a released lab's ``raise NotImplementedError()``),
    the cell shows ``Exercise N is not done yet: write `name` in the cell
    above`` instead of the traceback; any other ``NotImplementedError`` gets
    its usual traceback. The cell still fails (as an error), so grading and
    Run All see it as before.

    Parameters
    ----------
    shell : IPython.core.interactiveshell.InteractiveShell, optional
        Default: the running one.

    Returns
    -------
    bool
        Whether a handler was installed (False outside IPython).
    """
    from ._unsolved import install

    shell = ipython_shell() if shell is None else shell
    return shell is not None and install(shell)


def demo():
    """Wrap a demonstration that calls a student's code: ``with demo(): ...``.

    In a released lab whose exercise is not done yet, the block stops where
    it calls the unsolved code, and the cell prints one line instead of an
    error: ``This demonstration needs your `drive_square` (Exercise 1): ...``
    (also for a name an exercise defines, or one a stopped cell above did
    not get to). The cell succeeds, so Run All goes on to the next
    demonstration. Other errors, and every error in a notebook with no
    exercise left to do (a solution), propagate as usual.

    Returns
    -------
    robotlib._unsolved.Demo
        The context manager.
    """
    from ._unsolved import Demo

    return Demo()


def add_arguments(parser) -> None:
    """Arguments of ``robotlib warmup``."""
    parser.description = (
        "Compile robotlib's numba kernels into numba's cache, so that the labs' "
        "first cells only load them."
    )
    parser.add_argument(
        "parts", nargs="*", help=f"parts to warm (default: all of {sorted(WARMUPS)})"
    )
    parser.add_argument("--list", action="store_true", help="list the parts and exit")


def run(args) -> int:
    """Run ``robotlib warmup``: warm every part (or those named), print times."""
    if args.list:
        for part, entry in WARMUPS.items():
            steps = "" if callable(entry) else ": " + ", ".join(s for s, _ in entry)
            sys.stdout.write(f"{part}{steps}\n")
        return 0
    parts = args.parts or list(WARMUPS)
    t0 = time.perf_counter()
    spent = warm_up(parts)
    for part, seconds in spent.items():
        sys.stdout.write(f"{part:12s} {seconds:6.1f} s\n")
    sys.stdout.write(f"{'all':12s} {time.perf_counter() - t0:6.1f} s\n")
    return 0
