# ruff: noqa: E501
"""A class of submissions built from a lab's solution and release, with their worth.

`build(lab, folder)` writes, into ``folder``, the layouts students really
hand in and the faults and attacks a grader must take (issue 28), each with
the points it is worth per automatic check, the status and whether it must
be flagged (`Case`). Nothing is checked in: every notebook is made from
``solutions/LAB.ipynb`` and its release, so the set follows the lab.

The honest class (``kind == "class"``): the answered lab, the released one,
partial and wrong work, cell ids lost (nbformat 4.4), cells pasted into a new
notebook (metadata and ids gone), a demo cell duplicated, ``LAB (1).ipynb``
newer than ``LAB.ipynb``, ``Untitled.ipynb`` beside, section folders, the
nbgrader layout, a notebook at the top, a Latin-1 folder name, an exercise
in a helper module, a check cell from an older release, another lab's
notebook, a slow but correct answer, code that looks like a route to the
library and is not (``__import__('time')``, ...), the library's own version
tried in a cell of one's own, and what is not a submission (an unreadable
file, an empty folder, two notebooks, a link).
Lab 4 adds its own (a slow A*, a sign error in ``steer``).

The adversarial set (``kind == "adversarial"``): the library's own version of
an exercise reached through every route (alias, ``getattr`` on a built
string, ``importlib``, ``exec``, ``__import__``, a helper module), constant
answers, patched checks and builtins, hangs (a loop, a sleep, inside numba),
``os._exit`` at the top and inside a call, memory and disk filled, a flood
of processes, a fork bomb, CPU hogs, reading the solution and other
students' files, signals to every process. A hog's own points are not
compared (`Case.points` is None: its busy loops are charged to its own
calls, so they depend on the load); it must be flagged.

``expected`` points follow what the grader promises: a check scores what
its own exercises are worth (the others are the solution's), an answer that
reaches the library's listed version scores zero.
"""

from __future__ import annotations

import ast
import copy
import importlib
import inspect
import os
import time
from dataclasses import dataclass
from pathlib import Path

import nbformat

from robotlib.course.notebooks import (
    SOLUTION,
    exercises,
    read_notebook,
    release_notebook,
    setup_cell,
    write_notebook,
)
from robotlib.course.plan import lab_plan

ROOT = Path(__file__).resolve().parents[1]

__all__ = ["Case", "build", "compare"]


@dataclass
class Case:
    """One submission and what grading it must give.

    Attributes
    ----------
    student : str
        Its gradebook row.
    kind : str
        ``"class"`` (an honest layout or mistake) or ``"adversarial"``.
    what : str
        What it is, in a few words.
    points : dict or None
        Automatic check id to its points; None: not compared.
    status : str or None
        The start of the expected status (``"ok"``, ``"no notebook"``,
        ``"restarted"`` after a hang or a crash, ...); None: any.
    flagged : bool or None
        Whether it must be flagged; None: either.
    """

    student: str
    kind: str
    what: str
    points: dict[str, float] | None
    status: str | None = "ok"
    flagged: bool | None = False


class _Lab:
    """The lab's solution, its release, and the answered lab a student hands in."""

    def __init__(self, lab: str):
        self.name = lab
        self.solution = read_notebook(ROOT / "solutions" / f"{lab}.ipynb")
        self.released = release_notebook(self.solution, lab)
        self.plan = lab_plan(self.solution, lab)
        self.exercises = exercises(self.solution, lab)
        self.answered = copy.deepcopy(self.released)
        for ex in self.exercises:
            self.answered.cells[ex.index].source = self.answer(ex)
        self.full = {c.grade_id: float(c.points) for c in self.plan.checks}
        self.setup = setup_cell(self.solution)

    def answer(self, ex) -> str:
        """The solution's code of an exercise, as a student writes it."""
        lines = self.solution.cells[ex.index].source.splitlines()
        return "\n".join(ln for ln in lines if ln.strip() not in SOLUTION)

    def without(self, *broken: str) -> dict[str, float]:
        """Points when the exercises ``broken`` are worth nothing."""
        return {
            c.grade_id: 0.0 if set(c.exercises) & set(broken) else float(c.points)
            for c in self.plan.checks
        }

    def functions(self, ex) -> list[str]:
        """The functions an exercise's cell defines (not its tables)."""
        tree = ast.parse(self.answer(ex))
        return [n.name for n in tree.body if isinstance(n, ast.FunctionDef)]

    def first_function(self):
        """The first exercise that defines a function, and that function."""
        return next(
            (e, self.functions(e)[0]) for e in self.exercises if self.functions(e)
        )

    def with_answer(self, ex, source: str, base=None):
        nb = copy.deepcopy(base or self.answered)
        nb.cells[ex.index].source = source
        return nb

    def demo(self) -> int:
        """Index of the first code cell that is the lab's own (not exercise, check)."""
        own = {e.index for e in self.exercises} | {c.index for c in self.plan.checks}
        return next(
            i
            for i, c in enumerate(self.solution.cells)
            if c.cell_type == "code" and i not in own and i != self.setup
        )

    def listed(self) -> list[tuple]:
        """(exercise, module, function) of each exercise with a module-level listed one."""
        out = []
        for ex in self.exercises:
            for dotted in ex.writes:
                module, _, attr = dotted.rpartition(".")
                try:
                    obj = getattr(importlib.import_module(module), attr)
                except (ImportError, AttributeError):
                    continue
                if inspect.isfunction(obj) or hasattr(obj, "py_func"):
                    out.append((ex, module, attr))
                    break
        return out


def _put(
    folder: Path, student: str, nb, file: str | None = None, lab: str = ""
) -> Path:
    path = folder / student / (file or f"{lab}.ipynb")
    path.parent.mkdir(parents=True, exist_ok=True)
    write_notebook(nb, path)
    return path


def _no_ids(nb):
    nb = copy.deepcopy(nb)
    nb.nbformat_minor = 4
    for cell in nb.cells:
        cell.pop("id", None)
    return nb


def _pasted(nb):
    """Every cell pasted into a new notebook: new ids, no metadata at all."""
    out = nbformat.v4.new_notebook()
    for cell in nb.cells:
        make = {
            "code": nbformat.v4.new_code_cell,
            "markdown": nbformat.v4.new_markdown_cell,
        }.get(cell.cell_type, nbformat.v4.new_raw_cell)
        out.cells.append(make(cell.source))
    out.metadata = {"kernelspec": dict(nb.metadata.get("kernelspec", {}))}
    return out


def _imports(source: str) -> str:
    """The import statements of a cell (its other lines left out)."""
    tree = ast.parse(source)
    keep = [n for n in tree.body if isinstance(n, ast.Import | ast.ImportFrom)]
    return "\n".join(ast.unparse(n) for n in keep)


def _ordinary(lab: _Lab) -> str:
    """Code in an exercise's cell that looks like a route to the library and is not.

    ``__import__`` and ``importlib`` of the standard library, ``re.compile``,
    ``getattr`` on a module, a dictionary looked up by a listed function's own
    name, a variable named like machinery, a message naming a listed function.
    """
    listed = lab.listed()
    _, module, attr = listed[0] if listed else (None, "robotlib.sim", "step")
    return (
        "\n\n_t0 = __import__('time').perf_counter()\n"
        "import importlib, re\n_math = importlib.import_module('math')\n"
        "_hypot = getattr(_math, 'hypot')\n_digits = re.compile(r'\\d+')\n"
        f"_settings = {{}}\n_step = _settings.get({attr!r}, 0.1)\n"
        "modules, system = [_math], 'pioneer'\n"
        f"_note = 'mine is slower than {module}.{attr}; no solutions / no ipynb'\n"
    )


def _honest(lab: _Lab, folder: Path, put) -> None:
    name, exs = lab.name, lab.exercises
    first = exs[0]
    zero = {k: 0.0 for k in lab.full}
    put("answered", lab.answered, lab.full, "the lab answered")
    put("released", lab.released, zero, "the lab as released")
    partial = copy.deepcopy(lab.released)
    partial.cells[first.index].source = lab.answer(first)
    rest = [e.exercise_id for e in exs[1:]]
    put("partial", partial, lab.without(*rest), f"only {first.exercise_id} done")
    ex, fn = lab.first_function()
    wrong = lab.answer(ex) + f"\n\n\ndef {fn}(*args, **kwargs):\n    return None\n"
    put("wrong_answer", lab.with_answer(ex, wrong), lab.without(ex.exercise_id),
        f"{fn} returns None")  # fmt: skip
    put("nbformat_4_4", _no_ids(lab.answered), lab.full, "cell ids lost (nbformat 4.4)")
    put("pasted", _pasted(lab.answered), lab.full, "pasted into a new notebook")
    dup = copy.deepcopy(lab.answered)
    at = lab.demo()
    again = nbformat.v4.new_code_cell(dup.cells[at].source)
    dup.cells.insert(at + 1, again)
    put("duplicated_demo", dup, lab.full, "a demo cell duplicated")
    slow = lab.answer(first) + (
        "\n\nimport time\n\n_t = time.process_time()\n"
        "while time.process_time() - _t < 3:  # slow but correct\n    pass\n"
    )
    put("slow_cell", lab.with_answer(first, slow), lab.full, "3 s of CPU in a cell")
    put("ordinary_code", lab.with_answer(first, lab.answer(first) + _ordinary(lab)),
        lab.full, "imports and lookups that reach nothing of the library's")  # fmt: skip
    if lab.listed():  # the library's own version tried in a cell of one's own
        _, module, attr = lab.listed()[0]
        compared = copy.deepcopy(lab.answered)
        compared.cells.insert(lab.setup + 1, nbformat.v4.new_code_cell(
            f"import {module} as _lib\ntry:\n    _lib.{attr}()\n"
            "except Exception as exc:  # refused: the exercise's own work\n    print(exc)\n"
        ))  # fmt: skip
        put("library_compared", compared, lab.full, f"{attr} of the library tried in a cell of one's own")  # fmt: skip
    older = copy.deepcopy(lab.answered)
    check = lab.plan.checks[0].index
    older.cells[check].source += "\n# (from last year's release)"
    put("older_release", older, lab.full, "a check cell from an older release",
        flagged=True)  # fmt: skip

    path = put(
        "copy_newer", lab.released, lab.full, f"{name} (1).ipynb newer", flagged=True
    )  # the flag says which copy was graded
    write_notebook(lab.answered, path.with_name(f"{name} (1).ipynb"))
    past = time.time() - 3600
    os.utime(path, (past, past))
    path = put("untitled_beside", lab.answered, lab.full, "Untitled.ipynb beside",
               file=f"{name} (1).ipynb")  # fmt: skip
    write_notebook(nbformat.v4.new_notebook(), path.with_name("Untitled.ipynb"))
    put("section2/alice", lab.answered, lab.full, "a section folder")
    put("section2/bob", lab.released, zero, "a section folder")
    put("nbgrader", lab.answered, lab.full, "nbgrader's layout", file=f"{name}/{name}.ipynb")  # fmt: skip
    write_notebook(lab.answered, folder / "top_level.ipynb")
    put("top_level", None, lab.full, "a notebook at the top")
    latin = folder.as_posix().encode() + b"/Jos\xe9"
    os.makedirs(latin)
    write_notebook(lab.answered, Path(os.fsdecode(latin)) / f"{name}.ipynb")
    put("José", None, lab.full, "a Latin-1 folder name")

    helper = (
        f"{_imports(lab.solution.cells[lab.setup].source)}\n\n{lab.answer(first)}\n"
    )
    names = ", ".join(first.names)
    moved = lab.with_answer(first, f"from helpers import {names}")
    path = put("helper_module", moved, lab.full, "an exercise in helpers.py")
    path.with_name("helpers.py").write_text(helper)

    other = "lab1_models" if name == "lab0_getting_started" else "lab0_getting_started"
    put("other_lab", read_notebook(ROOT / "labs" / f"{other}.ipynb"), zero,
        f"{other} handed in as {name}", flagged=None, status=None)  # fmt: skip
    (folder / "unreadable").mkdir()
    (folder / "unreadable" / f"{name}.ipynb").write_text("{ not json")
    put("unreadable", None, zero, "an unreadable file",
        status="unreadable notebook")  # fmt: skip
    (folder / "empty").mkdir()
    put("empty", None, zero, "an empty folder", status="no notebook")
    path = put("two_notebooks", lab.answered, zero, "two notebooks, neither the lab",
               file="a.ipynb", status="several notebooks")  # fmt: skip
    write_notebook(lab.released, path.with_name("b.ipynb"))
    os.symlink(folder / "top_level.ipynb", folder / "linked.ipynb")
    put("linked", None, zero, "a link", status="a symbolic link")
    if name == "lab4_navigation":
        _lab4(lab, put)


def _lab4(lab: _Lab, put) -> None:
    astar = next(e for e in lab.exercises if e.exercise_id == "astar")
    src = lab.answer(astar).replace("closed = set()", "closed = []")
    src = src.replace("closed.add(u)", "closed.append(u)")
    put("slow_astar", lab.with_answer(astar, src), lab.full, "A* with a list as closed set")  # fmt: skip
    steer = next(e for e in lab.exercises if e.exercise_id == "steer")
    src = lab.answer(steer).replace(
        "pose[2], 2 * math.pi)", "pose[2], 2 * math.pi)\n    alpha = -alpha"
    )
    put("steer_sign", lab.with_answer(steer, src), lab.without("steer"), "steer's sign wrong")  # fmt: skip


_ROUTES = {
    "alias": "from {module} import {attr} as _lib",
    "getattr_string": "import {module} as _m\n_lib = getattr(_m, {head!r} + {tail!r})",
    "importlib": "import importlib\n_lib = getattr(importlib.import_module({module!r}), ''.join([{head!r}, {tail!r}]))",  # noqa: E501
    "exec_string": "exec('from {module} import {attr} as _lib')",
    "dunder_import": "_lib = vars(__import__({module!r}, fromlist=['x']))[{attr!r}]",
}


def _adversarial(lab: _Lab, folder: Path, put) -> None:
    listed = lab.listed()
    for i, route in enumerate([*_ROUTES, "helper_module"]):
        if not listed:
            break
        ex, module, attr = listed[i % len(listed)]
        fn = (lab.functions(ex) or list(ex.names))[0]
        call = f"\n\n\ndef {fn}(*args, **kwargs):\n    return _lib(*args, **kwargs)\n"
        what = f"{ex.exercise_id}: {module}.{attr} via {route}"
        if route == "helper_module":
            cell = lab.answer(ex) + f"\nfrom helpers import {fn}"
            path = put(f"cheat_{route}", lab.with_answer(ex, cell),
                       lab.without(ex.exercise_id), what, flagged=True)  # fmt: skip
            path.with_name("helpers.py").write_text(f"from {module} import {attr} as {fn}\n")  # fmt: skip
            continue
        head, tail = attr[:2], attr[2:]
        line = _ROUTES[route].format(module=module, attr=attr, head=head, tail=tail)
        cell = lab.answer(ex) + "\n" + line + call
        put(f"cheat_{route}", lab.with_answer(ex, cell), lab.without(ex.exercise_id),
            what, flagged=True)  # fmt: skip

    ex, fn = lab.first_function()
    broken = lab.without(ex.exercise_id)

    def redefine(student, body, what, status="restarted"):
        src = lab.answer(ex) + f"\n\n\ndef {fn}(*args, **kwargs):\n" + body
        put(student, lab.with_answer(ex, src), broken, f"{fn}: {what}", status=status)

    redefine("constant", "    return 0\n", "returns 0", status="ok")
    redefine("infinite_loop", "    while True:\n        pass\n", "loops for ever")
    redefine("sleeps", "    import time\n    time.sleep(10**6)\n", "sleeps for ever")
    redefine("exit_in_call", "    import os\n    os._exit(1)\n", "os._exit in a call")
    patched = (
        "import builtins, numpy, numpy.testing\n"
        "numpy.allclose = lambda *a, **k: True\nnumpy.isclose = numpy.allclose\n"
        "numpy.testing.assert_allclose = lambda *a, **k: None\n"
        "builtins.AssertionError = type('Fake', (Exception,), {})\n"
    )
    src = lab.answer(ex) + "\n" + patched + f"\n\ndef {fn}(*args, **kwargs):\n    return 0\n"  # fmt: skip
    put("patched_checks", lab.with_answer(ex, src), broken, "numpy and AssertionError patched")  # fmt: skip
    edited = copy.deepcopy(lab.released)
    for check in lab.plan.checks:
        edited.cells[check.index].source = f"print('CHECK {check.grade_id} passed')"
        edited.cells[check.index].metadata["tags"] = ["nbval-skip"]
    put(
        "edited_checks",
        edited,
        {k: 0.0 for k in lab.full},
        "check cells replaced",
        flagged=True,
    )  # not the current release's checks
    numba = lab.answer(ex) + (
        "\nfrom numba import njit\n\n\n@njit\ndef _spin(n):\n    i = 0\n"
        "    while i >= 0:\n        i = (i + n) % 1000003\n    return i\n\n\n_spin(1)\n"
    )
    put(
        "numba_hang",
        lab.with_answer(ex, numba),
        broken,
        "a hang inside numba",
        status="restarted",
    )
    last = lab.exercises[-1]
    src = lab.answer(last) + "\nimport os\nos._exit(3)\n"
    put("os_exit", lab.with_answer(last, src), lab.without(last.exercise_id),
        "os._exit at the top", status="restarted")  # fmt: skip

    def added(student, code, what, points=lab.full, flagged=None, status="ok"):
        nb = copy.deepcopy(lab.answered)
        nb.cells.insert(lab.setup + 1, nbformat.v4.new_code_cell(code))
        put(student, nb, points, what, flagged=flagged, status=status)

    added("memory", "try:\n    big = bytearray(40 << 30)\nexcept MemoryError:\n    pass\n",
          "40 GiB asked for")  # fmt: skip
    added("disk", "try:\n    with open('big', 'wb') as f:\n        for _ in range(20):\n"
          "            f.write(bytes(16 << 20))\nexcept OSError:\n    pass\n",
          "320 MiB written")  # fmt: skip
    added("process_flood", "import os, shutil\nkids, sleep = [], shutil.which('sleep')\n"
          "for _ in range(400):\n    try:\n"
          "        kids.append(os.posix_spawn(sleep, ['sleep', '991'], {}))\n"
          "    except OSError:\n        break\n", "400 sleeping processes")  # fmt: skip
    added("cpu_hog", "import os\nfor _ in range(4):  # busy loops that never end\n"
          "    if os.fork() == 0:\n        while True:\n            pass\n",
          "forks 4 busy loops", points=None, flagged=True, status=None)  # fmt: skip
    added("fork_bomb", "import os, time\nwhile True:\n    try:\n        os.fork()\n"
          "    except OSError:\n        time.sleep(0.01)\n",
          "a fork bomb", points=None, flagged=True, status=None)  # fmt: skip
    stolen = (
        "import os\nSTOLEN = []\n"
        f"for p in [{str(ROOT / 'solutions')!r}, {str(folder / 'answered')!r}]:\n"  # noqa: E501
        "    try:\n        STOLEN.append(os.listdir(p) if os.path.isdir(p) else open(p).read(9))\n"  # noqa: E501
        "    except OSError:\n        pass\n"
        f"if {str(folder)!r} in str(os.environ):\n    STOLEN.append('environment')\n"
        "if STOLEN:  # a leak: the cell fails, the status is not ok\n"
        "    raise SystemExit(f'found {STOLEN}')\n"
    )
    added("secrets", stolen, "reads the solution and a classmate", flagged=True)
    added("signals", "import os, signal\nfor pid in range(1, 200):\n    try:\n"
          "        os.kill(pid, signal.SIGKILL) if pid != os.getpid() else None\n"
          "    except OSError:\n        pass\n", "SIGKILL to every pid", status=None)  # fmt: skip
    added("escape", "import subprocess\nsubprocess.Popen(['setsid', 'sh', '-c', 'sleep 987'])\n"  # noqa: E501
          "subprocess.Popen(['env', '-i', 'sleep', '988'])\n", "processes that leave")  # fmt: skip


def build(
    lab: str, folder: str | Path, kinds=("class", "adversarial")
) -> dict[str, Case]:
    """Write the submissions of ``lab`` into ``folder``; return them by student.

    Parameters
    ----------
    lab : str
        A lab of ``solutions/`` (``lab0_getting_started``, ...).
    folder : str or pathlib.Path
        The submissions folder (created; must not hold these students yet).
    kinds : tuple of str
        ``"class"``, ``"adversarial"`` or both.

    Returns
    -------
    dict
        Student (gradebook row) to `Case`.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    the_lab = _Lab(lab)
    cases: dict[str, Case] = {}
    for kind, make in (("class", _honest), ("adversarial", _adversarial)):
        if kind not in kinds:
            continue

        def put(
            row, nb, points, what, file=None, status="ok", flagged=False, kind=kind
        ):
            """Write ``nb`` (None: written already) as student ``row``'s."""
            cases[row] = Case(row, kind, what, points, status, flagged)
            return None if nb is None else _put(folder, row, nb, file, lab)

        make(the_lab, folder, put)
    return cases


def compare(cases: dict[str, Case], results) -> list[str]:
    """Differences between the cases' worth and the grader's results (one line each)."""
    got = {r.student: r for r in results}
    out = []
    for name, case in cases.items():
        r = got.get(name)
        if r is None:
            out.append(f"{name}: not graded")
            continue
        if case.points is not None:
            points = {k: float(r.points.get(k, 0.0)) for k in case.points}
            if points != case.points:
                out.append(
                    f"{name}: {points} != {case.points} ({'; '.join(f'{k}: {v}' for k, v in r.reasons.items())})"
                )
        if case.status is not None and not r.status.startswith(case.status):
            out.append(f"{name}: status {r.status!r}, not {case.status!r}")
        if case.flagged is not None and bool(r.flags) != case.flagged:
            out.append(f"{name}: flags {r.flags} (flagged expected: {case.flagged})")
    for name in sorted(set(got) - set(cases)):
        out.append(f"{name}: graded but not a case")
    return out
