"""What a student sees, headless: warm-up, progress, unsolved errors, panels."""

from __future__ import annotations

import json
import os
import re
import threading
import time

import nbformat
import numba
import pytest
from nbclient import NotebookClient

import robotlib.notebook as nb
from robotlib.cli import main
from robotlib.experiments import drive_route
from robotlib.widgets import mcl as widgets
from robotlib.widgets._live import Cancelled, LiveRunner
from robotlib.world import load_world


def test_compile_watch_names_a_kernel_that_compiles_and_progress_shows_it(capsys):
    @numba.njit  # new each run: never in the cache
    def _ux_fresh_kernel(x):
        return x + 1

    _ux_fresh_kernel.py_func.__module__ = "robotlib.tests_ux"
    nb.WARMUPS["_ux"] = [("a fresh kernel", lambda: _ux_fresh_kernel(1))]
    try:
        spent = nb.warm_up(["_ux"])
    finally:
        del nb.WARMUPS["_ux"]
    assert set(spent) == {"_ux"}
    err = capsys.readouterr().err
    assert "compiling kernels (once)" in err and "tests_ux._ux_fresh_kernel" in err
    assert "1 kernels compiled" in err
    # a second warm-up loads (nothing compiles): no bar at all
    nb.WARMUPS["_ux"] = lambda: _ux_fresh_kernel(2)
    try:
        nb.warm_up(["_ux"])
    finally:
        del nb.WARMUPS["_ux"]
    assert "compiling" not in capsys.readouterr().err


def test_a_notebook_bar_redraws_every_tick_until_it_closes():
    """A long step still moves the bar (its elapsed time); a closed bar stops."""

    class Bar:
        disable, drawn = False, 0

        def refresh(self):
            self.drawn += 1

    bar = Bar()
    before = {t.name for t in threading.enumerate()}
    nb._tick(bar, every=0.01)
    (ticker,) = [t for t in threading.enumerate() if t.name not in before]
    waited = time.monotonic()
    while bar.drawn < 3 and time.monotonic() - waited < 30:
        time.sleep(0.01)
    assert bar.drawn >= 3
    bar.disable = True  # what tqdm's close() sets
    ticker.join(30)
    assert not ticker.is_alive()


def test_warm_up_rejects_unknown_parts():
    with pytest.raises(ValueError, match="unknown warm-up"):
        nb.warm_up(["nope"])


def test_warmup_command_lists_and_warms(capsys):
    assert main(["warmup", "--list"]) == 0
    listed = capsys.readouterr().out
    assert "sim" in listed and "MCL.best" in listed
    assert main(["warmup", "sim"]) == 0
    assert "sim" in capsys.readouterr().out
    assert "sim" in nb.warmed_parts()  # setup(warm=("sim",)) now only loads


def test_warmup_builds_a_cone_table_even_when_tables_are_on_disk(tmp_path, monkeypatch):
    """A table on disk (another clone's) must not stand in for its builder's kernels."""
    from robotlib.localization import cones
    from robotlib.localization._kernels import cone_table as kernels
    from robotlib.warmups import _warm_cone_table

    built = []
    real = kernels.build_cone_table
    monkeypatch.setattr(
        kernels, "build_cone_table", lambda *a: built.append(1) or real(*a)
    )
    monkeypatch.setenv("ROBOTLIB_TABLE_CACHE", str(tmp_path))
    monkeypatch.setattr(cones, "DISK_MIN_SECONDS", 0.0)  # any table would be kept
    for _ in range(2):
        _warm_cone_table()
    assert len(built) == 2  # built both times, nothing read from the disk
    assert not list(tmp_path.iterdir())  # nor kept there
    assert os.environ["ROBOTLIB_TABLE_CACHE"] == str(tmp_path)  # as it was


def _run(cells, tmp_path):
    """Execute ``cells`` as a notebook in ``tmp_path``; return its error outputs."""
    book = _execute(cells, tmp_path)
    return [
        out for cell in book.cells if cell.cell_type == "code" for out in cell.outputs
        if out.output_type == "error"
    ]  # fmt: skip


def _execute(cells, tmp_path):
    (tmp_path / "lib.py").write_text("def later():\n    raise NotImplementedError\n")
    book = nbformat.v4.new_notebook()
    for kind, src in cells:
        v4 = nbformat.v4
        make = v4.new_code_cell if kind == "code" else v4.new_markdown_cell
        book.cells.append(make(src))
    (tmp_path / "lab.ipynb").write_text(nbformat.writes(book))
    client = NotebookClient(
        book, timeout=120, allow_errors=True, kernel_name="python3",
        resources={"metadata": {"path": str(tmp_path)}},
    )  # fmt: skip
    client.execute()
    return book


def test_an_unsolved_exercise_is_said_plainly_and_still_fails(tmp_path):
    errors = _run(
        [
            ("code", "import robotlib.notebook\nrobotlib.notebook.explain_unsolved()"),
            ("markdown", "### Exercise 3\nWrite `resize`."),
            ("code", "def resize(n):\n    raise NotImplementedError()"),
            ("code", "resize(3)"),
            ("code", "import lib\nlib.later()"),
            ("markdown", "### Exercise 4\nWrite the matrix `GAINS`."),
            ("code", "# YOUR CODE HERE\nraise NotImplementedError()"),
        ],
        tmp_path,
    )
    assert len(errors) == 3  # the cells fail: the grader and Run All see them
    unsolved, library, stub = errors
    said = "Exercise 4 is not done yet: write your code in this cell."
    assert stub.ename == "NotImplementedError" and said in stub.traceback[0]
    text = "\n".join(unsolved.traceback)
    assert unsolved.ename == "NotImplementedError"
    assert "Exercise 3 is not done yet: write `resize` in the cell above" in text
    assert len(text.splitlines()) <= 4
    # a NotImplementedError from the library keeps its traceback
    assert "is not done yet" not in "\n".join(library.traceback)


def test_an_unsolved_exercise_shows_no_empty_figure(tmp_path):
    book = _execute(
        [
            ("code", "%matplotlib inline\nimport matplotlib.pyplot as plt"),
            ("code", "import robotlib.notebook\nrobotlib.notebook.explain_unsolved()"),
            ("markdown", "### Exercise 2\nWrite `curve`."),
            ("code", "def curve():\n    raise NotImplementedError()"),
            ("code", "fig, ax = plt.subplots()\nax.plot(curve())"),
            ("code", "fig, ax = plt.subplots()\nax.plot([0, 1])"),
        ],
        tmp_path,
    )
    unsolved, drawn = book.cells[-2].outputs, book.cells[-1].outputs
    assert [o.output_type for o in unsolved] == ["error"]
    assert any("image/png" in o.get("data", {}) for o in drawn)


def test_live_runner_coalesces_and_cancels():
    started, release = threading.Event(), threading.Event()
    done = []

    def job(request):
        started.set()
        while not release.is_set():
            runner.check()  # a newer request stops this one here
            time.sleep(0.005)
        return request * 10

    runner = LiveRunner(job, lambda req, res: done.append(res), background=True)
    runner.submit(1)
    assert started.wait(5)
    for k in (2, 3, 4):  # arrive while 1 runs: 1 is cancelled, 2 and 3 never run
        runner.submit(k)
    release.set()
    assert runner.wait(10)
    assert done == [40]
    assert runner.cancelled == 1 and runner.runs == 2
    with pytest.raises(Cancelled):
        runner.check(generation=0)


@pytest.fixture(scope="module")
def route():
    return drive_route(load_world("corridor"), seed=0, n_steps=8)


@pytest.mark.slow
def test_mcl_panel_controls(route):
    panel = widgets.MCLPanel(route, n_steps=4, n=300, lam=0.5)
    values = [v for _, v in panel.n.options]
    assert {50, 300, 1000, 50_000} <= set(values)
    assert all(b / a <= 2.0 for a, b in zip(values, values[1:], strict=False))  # log
    assert not panel.lam.disabled
    panel.resampler.value = "KLD"  # lambda does nothing for KLD
    assert panel.lam.disabled
    panel.resampler.value = widgets.RESAMPLERS[0]
    assert not panel.lam.disabled
    panel.n_typed.value = 420  # a typed count that is not a stop of the slider
    assert panel.n.value == 420 and panel.history.n_particles[0] == 420
    panel.n.value = 1000
    assert panel.n_typed.value == 1000
    assert "1,000 particles" in panel.figure.texts[0].get_text()


def test_mcl_panel_answers_at_once_and_runs_the_newest_in_the_background(route):
    panel = widgets.MCLPanel(route, n_steps=8, n=300, background=True)
    first = panel.image.value
    t0 = time.perf_counter()
    panel.n.value = 500
    assert time.perf_counter() - t0 < 0.1  # the change returns at once...
    assert panel.status.value.startswith("running")  # ...saying it runs
    assert "robotlib-stale" in panel.image._dom_classes
    panel.n.value = 750  # supersedes the run of 500
    panel.n.value = 1000
    assert panel.runner.wait(120)
    assert panel.history.n_particles[0] == 1000  # the newest settings won
    assert panel.runner.runs <= 3 and panel.image.value != first
    assert "robotlib-stale" not in panel.image._dom_classes
    assert panel.timings["feedback_s"] < 0.1
    assert json.dumps(panel.timings)


def test_run_mcl_keeps_snapshots_and_times_and_they_plot(route):
    from matplotlib.figure import Figure

    from robotlib.plotting.mcl import plot_particle_snapshots

    seen = []
    h = widgets.run_mcl(
        route, n=200, seed=0, snapshot_steps=(1, 5), on_step=lambda k, n: seen.append(k)
    )
    assert seen == list(range(1, len(route) + 1))
    assert sorted(h.snapshots) == [1, 5]
    first = h.snapshots[1]  # after step 1's resampling
    assert first["particles"].shape == (len(first["weights"]), 3)
    assert abs(h.snapshots[5]["weights"].sum() - 1) < 1e-9
    assert all(t > 0 for t in h.time_ms)
    again = widgets.run_mcl(route, n=200, seed=0)  # snapshots change nothing
    assert again.estimate[-1].tolist() == h.estimate[-1].tolist()
    fig = Figure()
    axes = plot_particle_snapshots(fig, route.world, h.snapshots)
    assert [a.get_title(loc="left") for a in axes[:2]] == [
        f"step 1: {len(first['particles'])} particles",
        f"step 5: {len(h.snapshots[5]['particles'])} particles",
    ]
    assert all(a.get_aspect() == 1.0 for a in axes[:2])


def test_legends_go_outside_the_map():
    from matplotlib.figure import Figure

    from robotlib.plotting import plot_world
    from robotlib.plotting.style import PALETTE, legend_outside, map_figsize

    fig = Figure(figsize=map_figsize(load_world("corridor").bounds))
    ax = fig.add_subplot()
    plot_world(ax, load_world("corridor"))
    ax.plot([1, 2], [4, 4], label="path")
    legend = legend_outside(ax)  # a wide map: the legend goes above it
    fig.canvas.draw()
    box, axbox = legend.get_window_extent(), ax.get_window_extent()
    assert box.y0 >= axbox.y1 - 1
    assert len(set(PALETTE)) == 8
    w, h = map_figsize((0, 0, 29, 8))
    assert w == 9.0 and 1.8 <= h <= 6.0


def test_interact_panel_says_it_runs_then_redraws_and_shows_errors():
    import ipywidgets as w
    import matplotlib.pyplot as plt

    from robotlib.widgets.interact import InteractPanel

    seen = []

    def show(k=1.0):
        if k > 2.5:
            raise ValueError("too big")
        seen.append((k, panel_status()))
        fig, ax = plt.subplots()
        ax.plot([0, 1], [0, k])
        plt.show()

    def panel_status():
        return panel.status.value if "panel" in names else None

    names = {}
    slider = w.FloatSlider(value=1.0, min=0.0, max=3.0, step=0.5)
    panel = InteractPanel(show, k=slider)
    names["panel"] = panel
    assert panel.runs == 1 and seen == [(1.0, None)]
    assert slider.description == "k"
    assert panel.status.value.startswith("k = 1 (drawn in")
    slider.value = 2.0
    assert seen[-1] == (2.0, "running: k = 2 ...")  # said before drawing
    assert panel.runs == 2 and "robotlib-stale" not in panel.output._dom_classes
    with pytest.raises(ValueError, match="too big"):  # outside a kernel it raises
        slider.value = 3.0
    assert panel.status.value == "running: k = 3 ..."
    assert "robotlib-stale" in panel.output._dom_classes  # the old figure stays grey


def test_a_demonstration_of_unsolved_code_says_what_it_needs_and_goes_on(tmp_path):
    book = _execute(
        [
            ("code", "%matplotlib inline\nimport matplotlib.pyplot as plt\n"
                     "import robotlib.notebook\nrobotlib.notebook.explain_unsolved()"),
            ("markdown", "### Exercise 2\nWrite `curve`, and the matrix `GAINS`."),
            ("code", "def curve():\n    raise NotImplementedError()"),
            ("code", "with robotlib.notebook.demo():\n    fig, ax = plt.subplots()\n"
                     "    points = curve()\n    ax.plot(points)"),
            ("code", "with robotlib.notebook.demo():\n    print(GAINS)"),
            ("code", "with robotlib.notebook.demo():\n    print(len(points))"),
            ("code", "GAINS * 2"),
            ("code", "with robotlib.notebook.demo():\n    1 / 0"),
        ],
        tmp_path,
    )  # fmt: skip
    out = [c.outputs for c in book.cells if c.cell_type == "code"]
    said = [[o.get("text", "") for o in cell] for cell in out[2:5]]
    assert said[0] == [
        "This demonstration needs your `curve` (Exercise 2): write it, run its"
        " cell, then run this one again.\n"
    ]  # one line, no error, and not the empty axes it opened
    assert said[1] == [
        "This demonstration needs your `GAINS` (Exercise 2): define it, run its"
        " cell, then run this one again.\n"
    ]
    assert "`points`, which a cell above makes" in said[2][0]
    (check,) = out[5]  # the exercise's error, as a check calling unsolved code gets
    assert check.output_type == "error" and check.ename == "NotImplementedError"
    assert check.traceback[0].startswith("\x1b[31m\x1b[1mNotImplementedError")
    assert "Exercise 2 is not done yet: define `GAINS`" in check.traceback[0]
    assert len(check.traceback) <= 4
    (other,) = out[6]
    assert other.ename == "ZeroDivisionError"  # not an unsolved exercise: it shows


def test_a_demonstration_in_a_solved_notebook_shows_its_errors(tmp_path):
    """With no exercise left to do (a solution), a demonstration's fault shows."""
    book = _execute(
        [
            ("code", "import robotlib.notebook"),
            ("markdown", "### Exercise 1\nWrite `GAINS`."),
            ("code", "def helper():\n    raise NotImplementedError"),
            ("code", "with robotlib.notebook.demo():\n    print(GAINS)"),
            ("code", "with robotlib.notebook.demo():\n    helper()"),
        ],
        tmp_path,
    )
    errors = [o.ename for c in book.cells[-2:] for o in c.outputs]
    assert errors == ["NameError", "NotImplementedError"]


def test_a_bar_left_short_by_unsolved_code_is_hidden_when_its_cell_ends(tmp_path):
    """A bar at 0/4 under "needs your `curve`" looked stuck; a finished one stays."""
    book = _execute(
        [
            ("code", "import robotlib.notebook\nrobotlib.notebook.explain_unsolved()"),
            ("markdown", "### Exercise 2\nWrite `curve`."),
            ("code", "def curve(k):\n    raise NotImplementedError()"),
            ("code", "with robotlib.notebook.demo():\n"
                     "    for k in robotlib.notebook.progress(range(4), desc='runs'):\n"
                     "        curve(k)"),
            ("code", "for k in robotlib.notebook.progress(range(3), desc='done'):\n"
                     "    pass"),
            ("code", "bar = robotlib.notebook.progress(total=5, desc='by hand')\n"
                     "bar.update(2)\n1 / 0"),
        ],
        tmp_path,
    )  # fmt: skip
    models = book.metadata.widgets["application/vnd.jupyter.widget-state+json"]["state"]

    def shown(cell):
        """Each bar's (text, display) in a cell's outputs."""
        bars = []
        for out in cell.outputs:
            view = out.get("data", {}).get("application/vnd.jupyter.widget-view+json")
            if view is None:
                continue
            box = models[view["model_id"]]["state"]
            layout = models[box["layout"].removeprefix("IPY_MODEL_")]["state"]
            text = models[box["children"][2].removeprefix("IPY_MODEL_")]["state"]
            bars.append((text["value"], layout.get("display")))
        return bars

    stopped, finished, failed = (shown(c) for c in book.cells[-3:])
    assert "needs your `curve`" in book.cells[-3].outputs[-1]["text"]
    assert [d for _, d in stopped] == ["none"] and "0/4" in stopped[0][0]
    assert [d for _, d in finished] == [None] and "3/3" in finished[0][0]
    assert [d for _, d in failed] == ["none"]  # the ZeroDivisionError says why


def test_warm_stamp_follows_only_the_kernels_and_what_is_warmed(tmp_path):
    """A docstring edited outside the kernels leaves a warm cache warm."""
    pkg = tmp_path / "pkg"
    (pkg / "avoidance").mkdir(parents=True)
    (pkg / "_config.py").write_text("JIT = {}\n")
    (pkg / "_kernels.py").write_text("@nb.njit\ndef f():\n    return 1\n")
    (pkg / "avoidance" / "grid.py").write_text("@nb.njit(cache=True)\ndef g():\n")
    (pkg / "warmups.py").write_text("WARMUPS = {}\n")
    (pkg / "plot.py").write_text('"""Plots."""\n')
    key = nb._warm_key(pkg)
    (pkg / "plot.py").write_text('"""Plots, edited."""\nX = 1\n')
    assert nb._warm_key(pkg) == key  # a plot or docstring: still warm
    for changed in ("_kernels.py", "avoidance/grid.py", "warmups.py", "_config.py"):
        (pkg / changed).write_text((pkg / changed).read_text() + "# changed\n")
        assert nb._warm_key(pkg) != key, changed  # a kernel, or what is warmed
        key = nb._warm_key(pkg)


def test_a_first_cell_shows_a_line_that_moves_until_setup_ends_it(tmp_path):
    """Seconds and the package importing now, redrawn while the cell loads."""
    (tmp_path / "slowpackage.py").write_text("import time\ntime.sleep(0.6)\n")
    book = _execute(
        [
            ("code", "import robotlib.notebook as nb\nfrom robotlib import _loading\n"
                     "nb.loading(every=0.05)\n"
                     "shown, update = [], _loading.LINES[0].handle.update\n"
                     "_loading.LINES[0].handle.update = lambda data, **kw: ("
                     "shown.append(data['text/plain']), update(data, **kw))\n"
                     "import slowpackage\n_loading.now('a step')\n"
                     "import time\ntime.sleep(0.3)\nnb.setup(warm=(), style=False)\n"
                     "time.sleep(0.2)"),
            ("code", "print('\\n'.join(shown))"),
            ("code", "nb.loading(every=0.05)\n1 / 0"),
        ],
        tmp_path,
    )  # fmt: skip
    (line,) = book.cells[0].outputs  # one line, redrawn in place
    ready = r"Ready \(\d+\.\d s of imports and set-up\)\."
    assert re.fullmatch(ready, line.data["text/plain"])
    shown = book.cells[1].outputs[0].text.splitlines()
    importing = [s for s in shown if s.endswith(": importing slowpackage ...")]
    assert len(set(importing)) >= 3  # it moved: 0.6 s of it, every 0.05 s
    assert any(s.endswith(": a step ...") for s in shown)
    assert re.fullmatch(ready, shown[-1])  # and nothing after it
    stopped = book.cells[2].outputs[0].data["text/plain"]
    assert re.fullmatch(r"stopped after \d+\.\d s\.", stopped)


def test_a_cell_that_compiles_says_so_and_its_bar_ends_with_what_compiled(tmp_path):
    book = _execute(
        [
            ("code", "import numba\nimport robotlib.notebook as nb\n"
                     "nb.setup(warm=(), style=False)"),
            ("code", "@numba.njit\ndef fresh(x):\n    return x + 1\n\n\n"
                     "fresh.py_func.__module__ = 'robotlib.tests_ux'\nfresh(1)"),
        ],
        tmp_path,
    )  # fmt: skip
    models = book.metadata.widgets["application/vnd.jupyter.widget-state+json"]["state"]
    (view,) = [
        o.data["application/vnd.jupyter.widget-view+json"]["model_id"]
        for o in book.cells[1].outputs if o.output_type == "display_data"
    ]  # fmt: skip
    text = models[models[view]["state"]["children"][2].removeprefix("IPY_MODEL_")]
    said = text["state"]["value"].replace("\u2007", " ")  # tqdm: figure spaces
    assert "compiling kernels (once, then cached): 1 done" in said
    assert "1 compiled in" in said and "now " not in said  # finished, not "now ..."
