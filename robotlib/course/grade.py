"""``robotlib grade``: grade a folder of lab submissions with nbval.

Usage::

    robotlib grade submissions/ --lab lab3_mcl --out gradebook.csv

For each submission (``submissions/<student>/<lab>.ipynb``, or
``submissions/<student>.ipynb``) the grader

1. rebuilds the notebook around the instructor's check cells: every check
   cell of ``solutions/<lab>.ipynb`` (hidden tests included) replaces the
   student's copy, matched by grade id and then by cell id, or is inserted
   where it belongs if deleted; unknown check cells are dropped; nbval tags
   and stored outputs are removed; each check cell ends by printing a per-run
   token;
2. runs it with nbval in its own pytest process (own session, working
   directory, ``HOME``, caches and ``TMPDIR``; a cell timeout and a notebook
   timeout), through a plugin that records each cell's outcome in a signed
   results file and checks the tokens outside the kernel;
3. ends every process of the job (found by a job id in their environment);
4. if the kernel died or the notebook ran out of time, re-runs it with the
   cells that hung or crashed skipped (a few passes at most): a check counts
   as passed if it passed in any pass;
5. turns each check's pass/fail into points: a check passes when its cell ran
   to its end (token printed) and the ``CHECK ...`` lines it printed equal
   those of the reference run of the solution, done once first (which must
   score full marks).

The gradebook (CSV, written by this process alone, atomically) has one row
per student: ``student``, one column per check, ``total``, ``max``,
``status``, ``seconds``, ``flags`` (code worth a look) and ``notes`` (a short
reason per failed check). A Markdown feedback file per student goes next to it.
"""

from __future__ import annotations

import argparse
import csv
import io
import os
import re
import secrets
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

import nbformat
from nbformat import NotebookNode

from . import _nbval_plugin as plugin
from .notebooks import (
    KERNELSPEC,
    META_KEY,
    NBVAL_TAGS,
    CheckCell,
    NotebookError,
    check_cells,
    check_meta,
    notebook_text,
    read_notebook,
)
from .release import project_dir

__all__ = [
    "GradeError",
    "GradeOptions",
    "Result",
    "build_graded_notebook",
    "find_submissions",
    "grade",
    "grade_notebook",
    "write_gradebook",
    "add_arguments",
    "run",
]

JOB_ENV = "ROBOTLIB_GRADE_JOB"
"""Environment variable carrying the job id of every process of a grading job."""

SUSPICIOUS = {
    "input transformer": r"input_transformers|ast_transformers",
    "hidden errors": r"set_custom_exc|showtraceback|_showtraceback",
    "IPython events": r"events\.register",
    "patched library function": r"\b(np|numpy|math|robotlib\w*)\.[A-Za-z_]\w*\s*=[^=]",
    "custom __eq__": r"__eq__",
    "builtins": r"\bbuiltins\b|__builtins__",
    "os._exit / kill": r"os\._exit|os\.kill|signal\.",
    "reads notebooks or solutions": r"\.ipynb|solutions/",
    "tracing": r"sys\.settrace|sys\.setprofile",
}
"""Patterns that flag a submission's own code for the instructor's review."""


class GradeError(RuntimeError):
    """Grading cannot proceed (e.g. the solution fails its own checks)."""


@dataclass
class GradeOptions:
    """How to run each submission.

    Attributes
    ----------
    cell_timeout : float
        Seconds one cell may run before it is interrupted.
    timeout : float
        Seconds one run of a notebook may take in all.
    passes : int
        Runs at most per submission (re-runs skip cells that hung or crashed).
    keep : bool
        Keep the working folders (for debugging).
    """

    cell_timeout: float = 60.0
    timeout: float = 600.0
    passes: int = 3
    keep: bool = False
    workroot: Path | None = None


@dataclass
class Result:
    """The grade of one submission."""

    student: str
    points: dict[str, float]
    reasons: dict[str, str]
    max_points: float
    status: str = "ok"
    seconds: float = 0.0
    passes: int = 0
    flags: list[str] = field(default_factory=list)
    check_lines: dict[str, list[str]] = field(default_factory=dict)

    @property
    def total(self) -> float:
        """Sum of the points earned."""
        return float(sum(self.points.values()))


# -- building the graded notebook ---------------------------------------------


def _clean_student_cell(cell: dict) -> NotebookNode:
    ctype = cell.get("cell_type")
    source = cell.get("source", "")
    if isinstance(source, list):
        source = "".join(source)
    if ctype == "code":
        new = nbformat.v4.new_code_cell(source)
        tags = [
            t
            for t in cell.get("metadata", {}).get("tags", []) or []
            if isinstance(t, str)
        ]
        tags = [t for t in tags if t.lower() not in NBVAL_TAGS]
        if tags:
            new.metadata["tags"] = tags
    elif ctype == "markdown":
        new = nbformat.v4.new_markdown_cell(source)
    else:
        new = nbformat.v4.new_raw_cell(source)
    return new


def _canonical_cell(
    sol_cell: dict, check: CheckCell, token: str, skip: bool
) -> NotebookNode:
    source = sol_cell["source"].rstrip()
    new = nbformat.v4.new_code_cell(f"{source}\n\nprint({token!r})")
    new.metadata[META_KEY] = {"grade_id": check.grade_id, "points": check.points}
    if skip:
        new.metadata["tags"] = ["nbval-skip"]
    return new


def build_graded_notebook(
    student: NotebookNode | dict,
    solution: NotebookNode,
    key: bytes,
    name: str = "lab",
    skip: frozenset[str] | set[str] = frozenset(),
) -> NotebookNode:
    """Rebuild a submission around the instructor's check cells.

    Parameters
    ----------
    student : NotebookNode or dict
        The submitted notebook (untrusted; only its cells' sources are used).
    solution : NotebookNode
        The lab's source notebook: its check cells are the canonical ones.
    key : bytes
        This run's secret: each check cell ends by printing
        ``check_token(key, grade_id)``.
    name : str
        The lab's name (for messages).
    skip : set of str
        Ids of cells to mark ``nbval-skip`` (cells that hung in a previous
        pass).

    Returns
    -------
    NotebookNode
        Cells with unique ids, no outputs, the canonical check cells in
        place, nbval tags removed from the student's cells.
    """
    checks = check_cells(solution, name)
    by_gid = {c.grade_id: c for c in checks}
    by_id = {c.cell_id: c for c in checks}
    placed: set[str] = set()
    cells: list[NotebookNode] = []
    used_ids: set[str] = set()

    def add(cell: NotebookNode, cid: str | None, at: int | None = None) -> None:
        cid = str(cid) if cid else ""
        if not re.fullmatch(r"[A-Za-z0-9_-]{1,64}", cid) or cid in used_ids:
            n = len(used_ids)
            while f"c{n}" in used_ids:
                n += 1
            cid = f"c{n}"
        used_ids.add(cid)
        cell.id = cid
        if cell.cell_type == "code" and cid in skip and META_KEY not in cell.metadata:
            cell.metadata["tags"] = [*cell.metadata.get("tags", []), "nbval-skip"]
        if at is None:
            cells.append(cell)
        else:
            cells.insert(at, cell)

    def canonical(c: CheckCell) -> NotebookNode:
        token = plugin.check_token(key, c.grade_id)
        return _canonical_cell(solution.cells[c.index], c, token, c.cell_id in skip)

    for cell in student.get("cells", []) if isinstance(student, dict) else []:
        if not isinstance(cell, dict):
            continue
        try:
            meta = check_meta(cell)
        except NotebookError:
            meta = {"grade_id": None}
        match = None
        if meta is not None and meta["grade_id"] in by_gid:
            match = by_gid[meta["grade_id"]]
        elif cell.get("id") in by_id:
            match = by_id[cell.get("id")]
        if match is not None:
            if match.grade_id not in placed:
                placed.add(match.grade_id)
                add(canonical(match), match.cell_id)
            continue
        if meta is not None:
            continue  # a check cell the lab does not have: dropped
        add(_clean_student_cell(cell), cell.get("id"))

    for c in checks:  # deleted checks go back after their predecessor
        if c.grade_id in placed:
            continue
        at = None
        for prev in reversed(solution.cells[: c.index]):
            ids = [x.id for x in cells]
            if prev.get("id") in ids:
                at = ids.index(prev.get("id")) + 1
                break
        add(canonical(c), c.cell_id, at)
        placed.add(c.grade_id)

    nb = nbformat.v4.new_notebook(cells=cells)
    nb.metadata = {"kernelspec": dict(KERNELSPEC), "language_info": {"name": "python"}}
    nb.nbformat, nb.nbformat_minor = 4, 5
    return nb


def suspicious_code(student: NotebookNode | dict, solution: NotebookNode) -> list[str]:
    """Names of `SUSPICIOUS` patterns found in the student's code, not the lab's."""
    lab_code = "\n".join(c.source for c in solution.cells if c.cell_type == "code")
    code = "\n".join(
        "".join(c.get("source", ""))
        for c in (student.get("cells", []) if isinstance(student, dict) else [])
        if isinstance(c, dict) and c.get("cell_type") == "code"
    )
    return [
        what
        for what, pattern in SUSPICIOUS.items()
        if re.search(pattern, code) and not re.search(pattern, lab_code)
    ]


# -- running one notebook --------------------------------------------------------


def _job_pids(job: str, session: int) -> list[int]:
    me = os.getpid()
    tag = f"{JOB_ENV}={job}".encode()
    pids = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit() or int(entry) == me:
            continue
        pid = int(entry)
        try:
            with open(f"/proc/{pid}/stat", "rb") as f:
                stat = f.read()
            fields = stat[stat.rindex(b")") + 2 :].split()
            if fields[0] == b"Z":
                continue
            if int(fields[3]) == session:
                pids.append(pid)
                continue
            with open(f"/proc/{pid}/environ", "rb") as f:
                if tag in f.read().split(b"\0"):
                    pids.append(pid)
        except (OSError, ValueError, IndexError):
            continue
    return pids


def kill_job(job: str, session: int, rounds: int = 10) -> int:
    """End every process of a grading job, one pid at a time.

    A process belongs to the job if ``JOB_ENV=job`` is in its environment or
    it is in the job's session. Returns how many processes were signalled.
    """
    killed = 0
    for _ in range(rounds):
        pids = _job_pids(job, session)
        if not pids:
            break
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
                killed += 1
            except (ProcessLookupError, PermissionError):
                pass
        time.sleep(0.05)
    return killed


_PASSTHROUGH_ENV = (
    "PATH",
    "LANG",
    "LC_ALL",
    "LC_CTYPE",
    "PYTHONPATH",
    "VIRTUAL_ENV",
    "CONDA_PREFIX",
    "NUMBA_CACHE_DIR",
    "NUMBA_DISABLE_JIT",
)


def _environment(work: Path, job: str) -> dict[str, str]:
    home = work / "home"
    env = {k: os.environ[k] for k in _PASSTHROUGH_ENV if k in os.environ}
    env.update(
        {
            JOB_ENV: job,
            "HOME": str(home),
            "XDG_CACHE_HOME": str(home / ".cache"),
            "XDG_CONFIG_HOME": str(home / ".config"),
            "XDG_DATA_HOME": str(home / ".local/share"),
            "XDG_RUNTIME_DIR": str(work / "tmp"),
            "IPYTHONDIR": str(home / ".ipython"),
            "JUPYTER_CONFIG_DIR": str(home / ".jupyter"),
            "JUPYTER_RUNTIME_DIR": str(work / "tmp"),
            "MPLCONFIGDIR": str(home / ".matplotlib"),
            "MPLBACKEND": "Agg",
            "TMPDIR": str(work / "tmp"),
            "PYTEST_DISABLE_PLUGIN_AUTOLOAD": "1",
            "PYTHONDONTWRITEBYTECODE": "1",
            "OMP_NUM_THREADS": "1",
            "OPENBLAS_NUM_THREADS": "1",
            "MKL_NUM_THREADS": "1",
            "NUMBA_NUM_THREADS": "1",
            "PYDEVD_DISABLE_FILE_VALIDATION": "1",
        }
    )
    env.setdefault("PATH", os.defpath)
    return env


@dataclass
class _Pass:
    cells: dict[str, dict]  # cell id -> record
    order: list[str]  # code cell ids, in order
    finished: bool
    wall_timeout: bool
    tampered: bool
    seconds: float
    log: str


def _run_pass(
    nb: NotebookNode, work: Path, key: bytes, lab: str, opts: GradeOptions, n: int
):
    for sub in (
        "home/.cache",
        "home/.ipython",
        "home/.matplotlib",
        "home/.jupyter",
        "tmp",
        "run",
    ):
        (work / sub).mkdir(parents=True, exist_ok=True)
    private = work / "private"
    private.mkdir(exist_ok=True, mode=0o700)
    run_dir = work / "run"
    (run_dir / "pytest.ini").write_text("[pytest]\n")
    nb_path = run_dir / f"{lab}.ipynb"
    nb_path.write_text(notebook_text(nb), encoding="utf-8")
    results = private / f"results-{n}.jsonl"
    log_path = private / f"pytest-{n}.log"
    job = secrets.token_hex(12)
    cmd = [
        sys.executable,
        "-m",
        "pytest",
        "-p",
        "nbval.plugin",
        "-p",
        "robotlib.course._nbval_plugin",
        "-p",
        "no:cacheprovider",
        "--nbval-lax",
        "--nbval-current-env",
        f"--nbval-cell-timeout={opts.cell_timeout:g}",
        "--nbval-kernel-startup-timeout=60",
        f"--robotlib-results={results}",
        "--robotlib-delete-notebook",
        "-q",
        "--tb=line",
        "-c",
        str(run_dir / "pytest.ini"),
        f"--rootdir={run_dir}",
        nb_path.name,
    ]
    rfd, wfd = os.pipe()
    os.write(wfd, key.hex().encode())
    os.close(wfd)
    cmd[-1:-1] = [f"--robotlib-key-fd={rfd}"]
    t0 = time.monotonic()
    wall_timeout = False
    with open(log_path, "wb") as log:
        try:
            proc = subprocess.Popen(
                cmd,
                cwd=run_dir,
                env=_environment(work, job),
                stdin=subprocess.DEVNULL,
                stdout=log,
                stderr=subprocess.STDOUT,
                start_new_session=True,
                pass_fds=(rfd,),
            )
        finally:
            os.close(rfd)
        try:
            _limit(proc.pid)
            proc.wait(timeout=opts.timeout)
        except subprocess.TimeoutExpired:
            wall_timeout = True
        finally:
            kill_job(job, proc.pid)
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                pass
    seconds = time.monotonic() - t0
    records, tampered = _read_results(results, key)
    finished = any(r.get("event") == "done" for r in records)
    cells: dict[str, dict] = {}
    for r in records:
        if r.get("event") == "cell" and r.get("id") not in cells:
            cells[r["id"]] = r
    order = [c.id for c in nb.cells if c.cell_type == "code"]
    try:
        log_text = log_path.read_text(errors="replace")[-4000:]
    except OSError:
        log_text = ""
    return _Pass(cells, order, finished, wall_timeout, tampered, seconds, log_text)


def _limit(pid: int) -> None:
    import resource

    for res, value in ((resource.RLIMIT_CORE, 0), (resource.RLIMIT_FSIZE, 1 << 30)):
        try:
            resource.prlimit(pid, res, (value, value))
        except (OSError, ValueError):
            pass


def _read_results(path: Path, key: bytes) -> tuple[list[dict], bool]:
    import json

    records, tampered = [], False
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return [], False
    for line in text.splitlines():
        try:
            rec = json.loads(line)
            mac = rec.pop("mac")
        except (ValueError, KeyError, AttributeError):
            tampered = True
            continue
        if not isinstance(mac, str) or not secrets.compare_digest(
            mac, plugin.sign(key, rec)
        ):
            tampered = True
            continue
        records.append(rec)
    return records, tampered


# -- grading one submission ---------------------------------------------------------


def _slug(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.@-]+", "_", name).strip("._") or "student"


def grade_notebook(
    student: str,
    submission: Path | NotebookNode | None,
    solution: NotebookNode,
    lab: str,
    reference: dict[str, list[str]] | None,
    opts: GradeOptions,
) -> Result:
    """Grade one submission; never raises for anything the submission does.

    Parameters
    ----------
    student : str
        The student's name (a gradebook row).
    submission : pathlib.Path or NotebookNode or None
        The submitted notebook (None: nothing was submitted).
    solution : NotebookNode
        The lab's source notebook.
    lab : str
        The lab's name.
    reference : dict or None
        Grade id to the ``CHECK`` lines of the reference run; None for the
        reference run itself.
    opts : GradeOptions
        Timeouts and passes.

    Returns
    -------
    Result
    """
    checks = check_cells(solution, lab)
    result = Result(
        student=student,
        points={c.grade_id: 0.0 for c in checks},
        reasons={},
        max_points=float(sum(c.points for c in checks)),
    )
    t0 = time.monotonic()
    if submission is None:
        result.status = "no notebook"
        result.reasons = {c.grade_id: "no notebook submitted" for c in checks}
        return result
    if isinstance(submission, Path):
        try:
            nb = nbformat.reads(submission.read_text(encoding="utf-8"), as_version=4)
        except Exception as exc:  # any unreadable file
            result.status = "unreadable notebook"
            why = f"unreadable notebook ({type(exc).__name__})"
            result.reasons = {c.grade_id: why for c in checks}
            return result
    else:
        nb = submission
    result.flags = suspicious_code(nb, solution)
    root = Path(tempfile.mkdtemp(prefix="rg-", dir=opts.workroot))
    try:
        skip: set[str] = set()
        passes: list[_Pass] = []
        for n in range(max(1, opts.passes)):
            key = secrets.token_bytes(32)
            graded = build_graded_notebook(nb, solution, key, lab, frozenset(skip))
            p = _run_pass(graded, root, key, lab, opts, n)
            started = any(r.get("status") != "error" for r in p.cells.values())
            if not started and n == 0:  # the kernel never started: once more
                p = _run_pass(graded, root, key, lab, opts, n)
            passes.append(p)
            if p.tampered and "tampered results" not in result.flags:
                result.flags.append("tampered results")
            culprits = _culprits(p)
            lost = [
                cid
                for cid in p.order
                if p.cells.get(cid, {}).get("status", "missing") in ("dead", "missing")
                and cid not in skip
            ]
            if not lost or not (culprits - skip):
                break
            skip |= culprits
        result.passes = len(passes)
        _score(result, checks, passes, reference, opts)
        statuses = {r.get("status") for p in passes for r in p.cells.values()}
        if "died" in statuses:
            result.status = "kernel died"
        elif any(p.wall_timeout for p in passes):
            result.status = "notebook timed out"
        elif "timeout" in statuses:
            result.status = "cell timed out"
    finally:
        if not opts.keep:
            shutil.rmtree(root, ignore_errors=True)
    result.seconds = time.monotonic() - t0
    return result


def _culprits(p: _Pass) -> set[str]:
    """Cells to skip next time: those that hung or killed the kernel."""
    out = {cid for cid, r in p.cells.items() if r.get("status") in ("timeout", "died")}
    if not p.finished:  # cut by the notebook timeout: the first cell without a record
        for cid in p.order:
            if cid not in p.cells:
                out.add(cid)
                break
    return out


def _score(result: Result, checks, passes: list[_Pass], reference, opts) -> None:
    for c in checks:
        gid = c.grade_id
        ran = []
        for i, p in enumerate(passes):
            rec = p.cells.get(c.cell_id)
            if rec is None:
                cut = not p.finished and p.wall_timeout
                rec = {
                    "status": "missing",
                    "reason": (
                        f"not run: the notebook time limit ({opts.timeout:g} s) ran out"
                        if cut
                        else "not run"
                    ),
                }
            ran.append((i, rec))
        ok = False
        for _, rec in ran:
            if rec.get("status") != "passed":
                continue
            lines = rec.get("check_lines", [])
            if reference is not None and lines != reference.get(gid, []):
                rec["status"] = "failed"
                got = next(
                    (
                        a
                        for a, b in zip(lines, reference.get(gid, []), strict=False)
                        if a != b
                    ),
                    lines[-1] if lines else "(nothing)",
                )
                rec["reason"] = f"wrong result: printed {got[:120]!r}"
                continue
            result.check_lines[gid] = lines
            ok = True
            break
        if ok:
            result.points[gid] = float(c.points)
            continue
        real = [
            (i, rec)
            for i, rec in ran
            if rec.get("status") not in ("dead", "missing", "skipped")
        ]
        i, rec = real[-1] if real else ran[0]
        reason = rec.get("reason") or rec.get("status", "failed")
        if rec.get("status") == "skipped":
            reason = "not run: it hung or crashed the kernel in an earlier pass"
        elif i > 0:
            reason += " (re-run without the cell that hung or crashed the kernel)"
        result.reasons[gid] = reason


# -- many submissions ----------------------------------------------------------------


def find_submissions(folder: str | Path, lab: str) -> list[tuple[str, Path | None]]:
    """List ``(student, notebook)`` pairs in a submissions folder.

    Accepted layouts: ``<student>/<lab>.ipynb``, ``<student>/<lab>/<lab>.ipynb``
    (nbgrader), ``<student>/<any single notebook>.ipynb`` and
    ``<student>.ipynb``. A student folder without a notebook gives ``None``.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise FileNotFoundError(f"no submissions folder {folder}")
    out = []
    for entry in sorted(folder.iterdir()):
        if entry.name.startswith("."):
            continue
        if entry.is_file() and entry.suffix == ".ipynb":
            out.append((entry.stem, entry))
        elif entry.is_dir():
            found = None
            for cand in (entry / f"{lab}.ipynb", entry / lab / f"{lab}.ipynb"):
                if cand.is_file():
                    found = cand
                    break
            if found is None:
                nbs = [
                    p
                    for p in entry.rglob("*.ipynb")
                    if ".ipynb_checkpoints" not in p.parts
                ]
                found = nbs[0] if len(nbs) == 1 else None
            out.append((entry.name, found))
    return out


class _Progress:
    """A one-line text progress bar on stderr."""

    def __init__(self, total: int, label: str, stream=None, enabled: bool = True):
        self.total, self.label, self.done = total, label, 0
        self.stream = stream or sys.stderr
        self.enabled = enabled
        self.t0 = time.monotonic()
        self.lock = threading.Lock()
        self.tty = getattr(self.stream, "isatty", lambda: False)()
        self._draw()

    def _draw(self, last: str = "") -> None:
        if not self.enabled:
            return
        width = 30
        filled = int(width * self.done / max(1, self.total))
        secs = int(time.monotonic() - self.t0)
        line = (
            f"{self.label} [{'#' * filled}{'.' * (width - filled)}] "
            f"{self.done}/{self.total} {secs // 60}:{secs % 60:02d} {last}"
        )
        if self.tty:
            self.stream.write("\r" + line[:120].ljust(120))
        else:
            self.stream.write(line + "\n")
        self.stream.flush()

    def advance(self, last: str = "") -> None:
        with self.lock:
            self.done += 1
            self._draw(last)

    def close(self) -> None:
        if self.enabled and self.tty:
            self.stream.write("\n")
            self.stream.flush()


def reference_run(
    solution: NotebookNode, lab: str, opts: GradeOptions
) -> dict[str, list[str]]:
    """Grade the solution itself; return each check's ``CHECK`` lines.

    Raises
    ------
    GradeError
        If the solution does not score full marks.
    """
    res = grade_notebook("(solution)", solution, solution, lab, None, opts)
    if res.total != res.max_points:
        failed = "; ".join(f"{k}: {v}" for k, v in res.reasons.items())
        raise GradeError(f"the solution of {lab} fails its own checks: {failed}")
    return res.check_lines


def grade(
    submissions: str | Path,
    lab: str,
    solution: str | Path | None = None,
    jobs: int | None = None,
    opts: GradeOptions | None = None,
    progress: bool = True,
) -> tuple[list[Result], list[CheckCell]]:
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
    opts : GradeOptions, optional
        Timeouts and passes.
    progress : bool
        Draw a progress bar on stderr.

    Returns
    -------
    results : list of Result
        One per student, sorted by name.
    checks : list of CheckCell
        The lab's checks.
    """
    opts = opts or GradeOptions()
    solution = (
        Path(solution) if solution else project_dir() / "solutions" / f"{lab}.ipynb"
    )
    sol = read_notebook(solution)
    checks = check_cells(sol, lab)
    subs = find_submissions(submissions, lab)
    jobs = max(1, jobs or os.cpu_count() or 1)
    bar = _Progress(len(subs) + 1, f"grading {lab}", enabled=progress)
    reference = reference_run(sol, lab, opts)
    bar.advance("(reference run)")
    results: dict[str, Result] = {}

    def one(student: str, path: Path | None) -> Result:
        try:
            return grade_notebook(student, path, sol, lab, reference, opts)
        except Exception as exc:  # a grader bug must not stop the others
            r = Result(student, {c.grade_id: 0.0 for c in checks}, {}, 0.0)
            r.max_points = float(sum(c.points for c in checks))
            r.status = f"grader error: {type(exc).__name__}: {exc}"[:200]
            r.reasons = {c.grade_id: "not graded (grader error)" for c in checks}
            return r

    names: dict[str, int] = {}
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        futures = {}
        for student, path in subs:
            names[student] = names.get(student, 0) + 1
            key = student if names[student] == 1 else f"{student}#{names[student]}"
            futures[pool.submit(one, key, path)] = key
        for fut in as_completed(futures):
            r = fut.result()
            results[r.student] = r
            bar.advance(f"{r.student}: {r.total:g}/{r.max_points:g}")
    bar.close()
    return [results[k] for k in sorted(results)], checks


def gradebook_rows(results: list[Result], checks: list[CheckCell]) -> list[dict]:
    """Return the gradebook as a list of rows (dicts of strings)."""
    rows = []
    for r in results:
        row = {"student": r.student}
        row.update({c.grade_id: f"{r.points.get(c.grade_id, 0.0):g}" for c in checks})
        row["total"] = f"{r.total:g}"
        row["max"] = f"{r.max_points:g}"
        row["status"] = r.status
        row["seconds"] = f"{r.seconds:.1f}"
        row["flags"] = "; ".join(r.flags)
        row["notes"] = "; ".join(f"{k}: {v}" for k, v in r.reasons.items())
        rows.append(row)
    return rows


def write_gradebook(
    path: str | Path, results: list[Result], checks: list[CheckCell]
) -> None:
    """Write the gradebook CSV atomically (a temporary file, then a rename)."""
    path = Path(path)
    fields = ["student", *[c.grade_id for c in checks], "total", "max"]
    fields += ["status", "seconds", "flags", "notes"]
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=fields, lineterminator="\n")
    writer.writeheader()
    writer.writerows(gradebook_rows(results, checks))
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(buf.getvalue(), encoding="utf-8")
    tmp.replace(path)


def feedback_text(result: Result, checks: list[CheckCell], lab: str) -> str:
    """Return a student's feedback, in Markdown."""
    lines = [
        f"# {lab}: feedback for {result.student}",
        "",
        f"Score: **{result.total:g} / {result.max_points:g}**",
        "",
        "| check | points | result |",
        "|---|---|---|",
    ]
    for c in checks:
        got = result.points.get(c.grade_id, 0.0)
        why = (
            result.reasons.get(c.grade_id, "passed")
            .replace("|", "\\|")
            .replace("\n", " ")
        )
        lines.append(f"| {c.grade_id} | {got:g} / {c.points:g} | {why} |")
    if result.status != "ok":
        lines += ["", f"Status: {result.status}."]
    lines += [
        "",
        "Each check was run as written by the instructor (edited or deleted "
        "checks were restored), with hidden tests added.",
        "",
    ]
    return "\n".join(lines)


def write_feedback(folder: str | Path, results: list[Result], checks, lab: str) -> None:
    """Write ``<student>.md`` feedback files into ``folder``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for r in results:
        (folder / f"{_slug(r.student)}.md").write_text(
            feedback_text(r, checks, lab), encoding="utf-8"
        )


# -- command line ------------------------------------------------------------------


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``grade`` options to ``parser``."""
    parser.add_argument("submissions", type=Path, help="folder of submissions")
    parser.add_argument("--lab", required=True, help="lab name (solutions/<lab>.ipynb)")
    parser.add_argument(
        "--out", type=Path, default=Path("gradebook.csv"), help="gradebook CSV"
    )
    parser.add_argument(
        "--feedback",
        type=Path,
        help="feedback folder (default: <out>-feedback/ next to --out)",
    )
    parser.add_argument("--solution", type=Path, help="the lab's source notebook")
    parser.add_argument(
        "--jobs", "-j", type=int, help="submissions at once (default: cores)"
    )
    parser.add_argument("--cell-timeout", type=float, default=60.0, help="s per cell")
    parser.add_argument(
        "--timeout", type=float, default=600.0, help="s per notebook run"
    )
    parser.add_argument(
        "--passes", type=int, default=3, help="runs at most per submission"
    )
    parser.add_argument("--keep", action="store_true", help="keep the working folders")
    parser.add_argument("--quiet", "-q", action="store_true", help="no progress bar")


def run(args: argparse.Namespace) -> int:
    """Run ``robotlib grade``; return the exit status."""
    opts = GradeOptions(args.cell_timeout, args.timeout, args.passes, args.keep)
    t0 = time.monotonic()
    try:
        results, checks = grade(
            args.submissions, args.lab, args.solution, args.jobs, opts, not args.quiet
        )
    except (GradeError, NotebookError, FileNotFoundError) as exc:
        sys.stderr.write(f"robotlib grade: {exc}\n")
        return 2
    write_gradebook(args.out, results, checks)
    feedback = args.feedback or args.out.with_name(f"{args.out.stem}-feedback")
    write_feedback(feedback, results, checks, args.lab)
    full = sum(r.total == r.max_points for r in results)
    sys.stderr.write(
        f"graded {len(results)} submissions of {args.lab} "
        f"in {time.monotonic() - t0:.1f} s "
        f"({full} full marks); gradebook {args.out}, feedback in {feedback}/\n"
    )
    return 0
