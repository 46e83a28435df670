"""``robotlib grade``: grade a folder of lab submissions, in a sandbox, resumably.

Usage::

    robotlib grade submissions/ --lab lab3_mcl --out gradebook.csv
    robotlib grade submissions/ --lab lab3_mcl --manual gradebook-manual.csv

For each submission the grader

1. picks the student's exercise cells (matched by exercise id, then cell
   id) and the cells they added, and scans them for routes to the library
   functions the exercises ask for (`plan.scan_submission`);
2. runs them in a sandboxed student process and the lab's checks (hidden
   tests included, from ``solutions/``) in a separate sandboxed check
   process that calls the student's functions through the grader
   (`session.run_submission`); tripwires report any call of a listed
   function;
3. scores each check: it passes when it ran to its end and printed the same
   ``CHECK`` lines as the reference run of the solution (done first, which
   must score full marks and warms the numba cache); an exercise whose
   answer reached a listed function scores zero, with a note and a flag.

Each result is saved at once (``<out>-records/``); a re-run skips what is
graded (``--regrade`` replaces). The gradebook (CSV) has one row per
student: ``student``, one column per check and written answer, ``total``,
``max``, ``status``, ``seconds``, ``flags`` and ``notes``; a feedback file
per student; every written answer in ``<out>-manual.csv``, to score and fold
in with ``--manual``. Ctrl-C or SIGTERM stops cleanly: the finished
submissions are kept, nothing keeps running.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
import signal
import threading
import time
from pathlib import Path

import nbformat

from . import cache as numba_cache
from . import sandbox as sb
from .astlock import format_exc
from .gradebook import Again, Records, Result, write_gradebook
from .notebooks import META_KEY, check_graded_exercises, notebook_text, read_notebook
from .parallel import Bar, dask_map, raise_interrupt, thread_map
from .parallel import slot as hold_slot
from .plan import (
    LabPlan,
    lab_plan,
    normalized,
    release_notes,
    scan_submission,
    student_cells,
)
from .release import project_dir
from .session import JOB_ENV, Options, run_submission
from .submissions import check_lab, copies, find_submissions, helpers, pick

__all__ = [
    "GradeError",
    "GradeOptions",
    "Result",
    "JOB_ENV",
    "find_submissions",
    "grade",
    "grade_notebook",
    "limits",
    "reference_run",
    "solution_path",
    "write_gradebook",
]

GradeOptions = Options


UNGRADED = "written answer: not graded by hand yet"
OVERLOADED = "machine overloaded: re-grade"
"""Status of a submission the machine was too busy to grade (the next run does)."""


class GradeError(RuntimeError):
    """Grading cannot proceed (the solution fails its own checks, no sandbox)."""


def _answers(plan: LabPlan, nb: dict) -> dict[str, str]:
    """Return the student's written answers, by grade id.

    A markdown cell is a written answer by its metadata, its id, or, when
    both were lost (an old nbformat, pasted cells), by the question it holds.
    """
    by_id = {c.cell_id: c.grade_id for c in plan.manual}
    gids = set(by_id.values())
    out = {}
    for cell in nb.get("cells", []):
        if not isinstance(cell, dict) or cell.get("cell_type") != "markdown":
            continue
        meta = (cell.get("metadata") or {}).get(META_KEY) or {}
        gid = meta.get("grade_id") if isinstance(meta, dict) else None
        src = cell.get("source", "")
        src = "".join(src) if isinstance(src, list) else str(src)
        text = normalized(src)
        by_text = [g for g, q in plan.prompts.items() if q and q in text]
        gid = gid if gid in gids else by_id.get(cell.get("id"))
        gid = gid or (by_text[0] if len(by_text) == 1 else None)
        if gid and gid not in out:
            out[gid] = src
    return out


def _compare(gid: str, rec: dict, reference: dict | None) -> str | None:
    """None if the check passed, else the reason."""
    if rec.get("status") != "passed":
        return rec.get("error") or "failed"
    if reference is None:
        return None
    want = reference.get(gid, {"lines": [], "hidden": []})
    got_lines, got_hidden = rec.get("lines", []), rec.get("hidden", [])
    for a, b in zip(got_lines, want["lines"], strict=False):
        if a != b:
            return f"wrong result: expected {b[:150]!r}, got {a[:150]!r}"
    if len(got_lines) != len(want["lines"]):
        n, m = len(got_lines), len(want["lines"])
        return f"wrong result: printed {n} CHECK lines, not {m}"
    if got_hidden != want["hidden"]:
        return "wrong result on the hidden inputs (not shown)"
    return None


def grade_notebook(
    student: str,
    submission: Path | dict | None,
    plan: LabPlan,
    reference: dict | None,
    opts: Options,
    slot: int = 0,
    modules: dict[str, str] | None = None,
) -> Result:
    """Grade one submission; never raises for anything the submission does.

    Parameters
    ----------
    student : str
        The student's name (a gradebook row).
    submission : pathlib.Path, dict or None
        The notebook (None: nothing was submitted).
    plan : LabPlan
        The lab (`plan.lab_plan`).
    reference : dict or None
        Grade id to ``{"lines", "hidden"}`` of the reference run; None for
        the reference run itself.
    opts : Options
        Timeouts, limits, sandbox.
    slot : int
        Grading slot (chooses the sandbox's uids).
    modules : dict, optional
        The student's helper modules (file name to source), importable by
        their cells and scanned like them (`submissions.helpers`).
    """
    modules = modules or {}
    items = plan.checks + plan.manual
    result = Result(
        student, {c.grade_id: 0.0 for c in plan.checks}, {}, plan.max_points
    )
    t0 = time.monotonic()
    if not opts.sandbox:
        result.flags.append("graded without sandbox (--no-sandbox)")
    if submission is None:
        result.status = "no notebook"
        result.reasons = {c.grade_id: "no notebook submitted" for c in items}
        return result
    nb = submission
    if isinstance(submission, Path):
        try:
            text = submission.read_bytes().decode("utf-8")
            nb = nbformat.reads(text, as_version=4)
        except Exception as exc:  # noqa: BLE001 - any unreadable file
            result.status = "unreadable notebook"
            why = f"unreadable notebook ({type(exc).__name__})"
            result.reasons = {c.grade_id: why for c in items}
            return result
    if not isinstance(nb, dict) or not isinstance(nb.get("cells"), list):
        result.status = "unreadable notebook"
        result.reasons = {c.grade_id: "not a notebook" for c in items}
        return result
    result.answers = _answers(plan, nb)
    result.flags += release_notes(plan, nb)
    cells = student_cells(plan, nb)
    result.code = {c["exercise"]: c["source"] for c in cells if c["exercise"]}
    scanned = [{"id": n, "source": m, "exercise": None} for n, m in modules.items()]
    zero, flags = scan_submission(plan, cells + scanned)
    result.flags += flags
    budgets, opts = limits(reference, opts)
    out = run_submission(plan, cells, opts, slot, budgets, modules)
    result.passes = 1 + out.restarts
    result.flags += out.flags
    for function, ex, *via in out.tripwires:
        if ex is None or not plan.lists(ex, function):
            continue  # refused (the student's error says why): nothing gained
        name = plan.listed_as(function, ex)
        how = f" (through {via[0]})" if via and via[0] and via[0] != name else ""
        note = f"called {name}{how} (the exercise's own work) while graded"
        zero.setdefault(ex, []).append(note)
        if note not in result.flags:
            result.flags.append(note)
    errors = {cid: c for cid, c in out.cells.items() if c.get("status") == "error"}
    for cid, c in errors.items():
        result.details[f"cell {cid}"] = f"your cell raised:\n{c.get('error', '')}"
    for c in plan.checks:
        rec = out.checks.get(c.grade_id, {})
        why = _compare(c.grade_id, rec, reference)
        cheat = [n for e in c.exercises for n in zero.get(e, [])]
        if cheat:
            why = "zero: " + "; ".join(dict.fromkeys(cheat))
        if why is None:
            result.points[c.grade_id] = float(c.points)
            result.check_lines[c.grade_id] = {
                "lines": rec.get("lines", []),
                "hidden": rec.get("hidden", []),
                "cpu": rec.get("cpu", 0.0),
            }
            continue
        result.reasons[c.grade_id] = why[:300]
        if rec.get("student"):
            result.details[c.grade_id] = f"{why}\n\nyour traceback:\n{rec['student']}"
        elif len(why) > 300:
            result.details[c.grade_id] = why
    for c in plan.manual:
        result.reasons[c.grade_id] = UNGRADED
    result.status = OVERLOADED if out.status == "overloaded" else out.status
    if out.restarts and result.status == "ok":
        result.status = "restarted (your code hung or crashed)"
    if any(n.startswith("zero:") for n in result.reasons.values()):
        result.flags.insert(0, "answer reaches the library's own version")
    result.seconds = time.monotonic() - t0
    return result


def limits(reference: dict | None, opts: Options) -> tuple[dict[str, float], Options]:
    """Return each check's limit and the options, scaled from the solution's times.

    A check may take ``opts.slower`` times the charged time (`cpu`) the
    solution took for it, or ``opts.cell_timeout`` if more; the submission
    ``opts.slower`` times the solution's checks in all, or ``opts.timeout``
    if more. So a correct answer ten times slower than the solution passes
    (the default is twenty), whatever the machine's load.
    """
    times = {g: float(r.get("cpu", 0.0)) for g, r in (reference or {}).items()}
    budgets = {g: max(opts.cell_timeout, opts.slower * t) for g, t in times.items()}
    total = max(opts.timeout, opts.slower * sum(times.values()))
    cpu = max(opts.limits.cpu, int(total) + 60)  # each process's RLIMIT_CPU
    limits = dataclasses.replace(opts.limits, cpu=cpu)
    return budgets, Options(**{**vars(opts), "timeout": total, "limits": limits})


def reference_run(
    plan: LabPlan, solution: dict, opts: Options, slot: int | None = None
) -> dict:
    """Grade the solution itself (warming the numba cache); return its lines.

    ``slot``: the grading slot it runs in (held by the caller); None: it
    holds a free one meanwhile (`parallel.slot`), as each submission does.

    Raises
    ------
    GradeError
        If the solution does not score full marks on its checks, or reaches
        a function its exercises list.
    """
    if slot is None:
        with hold_slot() as k:  # its uids: no other grading's at once
            return reference_run(plan, solution, opts, k)
    warm = Options(**{**vars(opts), "warm": True})
    warm.cell_timeout = max(opts.cell_timeout * 10, 300.0)
    warm.timeout = max(opts.timeout * 3, 1800.0)
    res = grade_notebook("(solution)", solution, plan, None, warm, slot)
    auto = {c.grade_id for c in plan.checks}
    failed = {k: v for k, v in res.reasons.items() if k in auto}
    if failed or any("exercise's own work" in f for f in res.flags):
        why = "; ".join(f"{k}: {v}" for k, v in failed.items()) or "; ".join(res.flags)
        raise GradeError(f"the solution of {plan.name} fails its own checks: {why}")
    return res.check_lines


def solution_path(lab: str) -> Path:
    """Return ``solutions/<lab>.ipynb``; a clear error lists the labs if absent."""
    folder = project_dir() / "solutions"
    path = folder / f"{lab}.ipynb"
    if not path.exists():
        labs = ", ".join(sorted(p.stem for p in folder.glob("*.ipynb"))) or "none"
        raise GradeError(f"no lab {lab!r} in {folder} (labs: {labs})")
    return path


def _fingerprint(path: Path | None, solution_text: str, modules: dict) -> str:
    h = hashlib.sha256(solution_text.encode())
    for name, source in sorted(modules.items()):
        h.update(f"{name}\0{source}\0".encode())
    if path is not None:
        try:
            h.update(path.read_bytes())
        except OSError:
            h.update(b"unreadable")
    return h.hexdigest()[:32]


_PLANS: dict[str, LabPlan] = {}


def _plan(solution_text: str, lab: str) -> LabPlan:
    key = hashlib.sha256(solution_text.encode()).hexdigest() + lab
    if key not in _PLANS:
        solution = nbformat.reads(solution_text, as_version=4)
        check_graded_exercises(solution, lab)
        _PLANS[key] = lab_plan(solution, lab)
    return _PLANS[key]


def grade_task(student, data, solution_text, lab, reference, opts, modules, slot=0):
    """One submission as a self-contained task (threads or Dask workers).

    ``data`` is the notebook's bytes (or None), ``modules`` its helper
    modules; returns the result as JSON.
    """
    plan = _plan(solution_text, lab)
    if data is None:
        sub = None
    else:
        try:
            sub = nbformat.reads(data.decode("utf-8"), as_version=4)
        except Exception as exc:  # noqa: BLE001 - any unreadable file
            res = grade_notebook(student, {"cells": None}, plan, reference, opts)
            res.status = "unreadable notebook"
            why = f"unreadable notebook ({type(exc).__name__})"
            res.reasons = {c.grade_id: why for c in plan.checks + plan.manual}
            return res.to_json()
    try:
        res = grade_notebook(student, sub, plan, reference, opts, slot, modules)
        return res.to_json()
    except Exception as exc:  # noqa: BLE001 - a grader bug must not stop the class
        res = Result(student, {}, {}, plan.max_points)
        res.status = f"grader error: {type(exc).__name__}: {exc}"[:200]
        res.reasons = {c.grade_id: "not graded (grader error)" for c in plan.checks}
        res.details = {"grader error": format_exc()[-3000:]}
        return res.to_json()


def grade(
    submissions: str | Path,
    lab: str,
    solution: str | Path | None = None,
    jobs: int | None = None,
    opts: Options | None = None,
    progress: bool = True,
    records: str | Path | None = None,
    regrade: bool = False,
    scheduler: str | None = None,
    students: list[str] | None = None,
    exclude: tuple[Path, ...] = (),
) -> tuple[list[Result], list]:
    """Grade every submission of a folder.

    Parameters
    ----------
    submissions : str or pathlib.Path
        The folder of submissions (see `find_submissions`).
    lab : str
        The lab's name; its source is ``solutions/<lab>.ipynb`` unless
        ``solution`` is given.
    solution : str or pathlib.Path, optional
        The lab's source notebook.
    jobs : int, optional
        Submissions graded at once (default: the number of cores).
    opts : Options, optional
        Timeouts, limits and the sandbox.
    progress : bool
        Draw a progress bar on stderr.
    records : str or pathlib.Path, optional
        Folder of per-submission records: graded submissions are skipped
        (unless ``regrade``), new results saved as they come.
    regrade : bool
        Grade every submission again.
    scheduler : str, optional
        ``"local"`` or a ``dask.distributed`` scheduler address.
    students : list of str, optional
        Grade (again) only these students; the others are left as recorded.
    exclude : tuple of pathlib.Path
        Paths inside the submissions folder that are not submissions (the
        grader's own outputs).

    Returns
    -------
    results : list of Result
        One per submission, sorted by name (interrupted: the finished ones).
    items : list of CheckCell
        The lab's checks and written answers (gradebook columns).

    Raises
    ------
    GradeError
        No sandbox (and ``opts.sandbox``), or the solution fails its checks.
    KeyboardInterrupt
        On Ctrl-C or SIGTERM, after every process of the class has ended.
    """
    opts = opts or Options()
    solution = Path(solution) if solution else solution_path(lab)
    sol_nb = read_notebook(solution)
    subs = find_submissions(submissions, lab, exclude)
    if not subs:
        raise GradeError(f"no submissions in {submissions}")
    try:  # mistakes in the command first, before anything slow
        check_lab(sol_nb, lab, [p for _, p, _ in subs if p is not None])
        subs = pick(subs, students) if students else subs
    except ValueError as exc:
        raise GradeError(str(exc)) from None
    if opts.sandbox and (why := sb.available()):
        raise GradeError(f"no sandbox: {why}; pass --no-sandbox to grade without")
    sol_text = notebook_text(sol_nb)
    plan = _plan(sol_text, lab)
    jobs = max(1, jobs or os.cpu_count() or 1)
    store = Records(records, lab) if records else None
    again = Again(store, [s for s, _, _ in subs] if regrade or students else None)
    stop = threading.Event()
    opts.stop = stop
    results: dict[str, Result] = {}
    todo = []
    extra: dict[str, tuple[dict, list[str]]] = {}  # helper modules, notes
    for student, path, status in subs:
        extra[student] = helpers(path, Path(submissions)) if path else ({}, [])
        fp = _fingerprint(path, sol_text, extra[student][0])
        old = store.load(student) if store and student not in again else None
        if old is not None and old[1] == fp and old[0].status != OVERLOADED:
            results[student] = old[0]
            continue
        todo.append((student, path, status, fp))
    items = plan.checks + plan.manual
    bar = Bar(len(todo) + 1, f"grading {lab}", progress)
    own = threading.current_thread() is threading.main_thread()
    old_term = signal.signal(signal.SIGTERM, raise_interrupt) if own else None
    try:
        import tempfile

        with tempfile.TemporaryDirectory(prefix="rg-cache-", dir=opts.workroot) as c:
            os.chmod(c, 0o755)
            opts.numba_cache = Path(c) / "numba"
            opts.numba_cache.mkdir()
            opts.mpl_cache = Path(c) / "matplotlib"
            opts.mpl_cache.mkdir()
            saved = store.folder / ".reference" if store else None
            key = numba_cache.reference_key(sol_text, lab)
            reference = None
            if saved is not None and not regrade:
                reference = numba_cache.load_reference(saved, key, opts)
            if reference is None:
                numba_cache.prewarm(plan.setup, opts.mpl_cache)
                numba_cache.seed(opts.numba_cache)
                reference = reference_run(plan, sol_nb, opts)
                if saved is not None:
                    numba_cache.save_reference(saved, key, reference, opts)
                bar.advance("(reference run)")
            else:
                bar.advance("(reference run: saved)")
            fps = {t[0]: t[3] for t in todo}
            times = {s: p.stat().st_mtime for s, p, _, _ in todo if p is not None}
            notes = {
                s: [f"several copies of the lab: graded the newest, {p.name} "
                    f"(not {', '.join(c.name for c in others)})"]
                for s, p, _, _ in todo
                if p is not None and (others := copies(p, lab))
            }  # fmt: skip
            for s, (_, left_out) in extra.items():
                notes.setdefault(s, []).extend(left_out)

            def done(data: dict) -> None:
                r = Result.from_json(data)
                r.flags += notes.get(r.student, [])
                r.submitted = times.get(r.student, 0.0)
                results[r.student] = r
                if store is not None and not r.status.startswith("interrupted"):
                    store.save(r, fps[r.student])
                    again.done(r.student)
                bar.advance(f"{r.student}: {r.total:g}/{r.max_points:g}")

            tasks = []
            for student, path, status, _ in todo:
                if status:
                    r = Result(student, {}, {}, plan.max_points, status=status)
                    r.reasons = {c.grade_id: status for c in items}
                    done(r.to_json())
                    continue
                data = path.read_bytes() if path is not None else None
                modules = extra[student][0]
                tasks.append((student, data, sol_text, lab, reference, opts, modules))
            if scheduler:
                plain = Options(**{**vars(opts), "stop": None})
                tasks = [(*t[:5], plain, t[6]) for t in tasks]

                def failed(student, exc):
                    r = Result(student, {}, {}, plan.max_points)
                    r.status = f"grader error: {type(exc).__name__}: {exc}"[:200]
                    r.reasons = {c.grade_id: "not graded (grader error)" for c in items}
                    done(r.to_json())

                dask_map(grade_task, tasks, scheduler, jobs, stop, done, failed)
            else:
                thread_map(grade_task, tasks, jobs, stop, done)
    except KeyboardInterrupt:
        stop.set()
        raise
    finally:
        stop.set()
        bar.close()
        if old_term is not None:
            signal.signal(signal.SIGTERM, old_term)
    return [results[k] for k in sorted(results)], items
