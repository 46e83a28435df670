"""``robotlib grade``: the command line around `grade.grade`.

Usage::

    robotlib grade submissions/ --lab lab3_mcl --out gradebook.csv
    robotlib grade submissions/ --lab lab3_mcl --student "Ada Lovelace"
    robotlib grade submissions/ --lab lab3_mcl --manual other-sheet.csv

Writes the gradebook from every record of the class (a run over one
student's folder, or with ``--student``, merges into it), the feedback, the
written answers' sheet (``<out>-manual.csv``), the class report
(``<out>-report.html``) and, with ``--lms`` and ``--roster``, the LMS's
grade-import CSV (late penalties applied with ``--due``). What the instructor typed
into that sheet is read into the hand-grade record (``<out>-hand.json``)
before the sheet is rewritten, on every run: no run loses a hand grade.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from . import sandbox as sb
from .grade import OVERLOADED, UNGRADED, GradeError, _plan, grade, solution_path
from .gradebook import (
    HandGrades,
    Records,
    Result,
    export_manual,
    read_manual,
    write_feedback,
    write_gradebook,
)
from .notebooks import NotebookError, notebook_text, read_notebook
from .report import class_report, export_lms, read_roster
from .session import Options

__all__ = ["add_arguments", "fold_manual", "run"]


def fold_manual(results: list[Result], items, hand: HandGrades) -> int:
    """Put the instructor's hand grades into ``results``; return how many are missing.

    A written answer without a score has no points entry (the gradebook
    shows it empty, not 0); a comment reaches the feedback.
    """
    missing = 0
    for r in results:
        for c in (c for c in items if c.manual):
            got = hand.get(r.student, c.grade_id)
            comment = f": {got['comment']}" if got.get("comment") else ""
            if "score" in got:
                r.points[c.grade_id] = float(got["score"])
                r.reasons[c.grade_id] = f"graded by hand{comment}"
            else:
                r.points.pop(c.grade_id, None)  # a record of an older release: 0
                if c.grade_id in r.answers:
                    missing += 1
                    r.reasons[c.grade_id] = UNGRADED + comment
    return missing


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``grade`` options to ``parser``."""
    parser.add_argument("submissions", type=Path, help="folder of submissions")
    parser.add_argument("--lab", required=True, help="lab name (solutions/<lab>.ipynb)")
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("gradebook.csv"),
        help="gradebook CSV; records, feedback and the written answers' sheet "
        "go next to it (default: %(default)s)",
    )
    parser.add_argument(
        "--student",
        action="append",
        metavar="NAME",
        help="grade (again) only this student, with the options given; repeat "
        "for several; the gradebook keeps everyone else",
    )
    parser.add_argument(
        "--feedback",
        type=Path,
        help="feedback folder (default: <out>-feedback/ next to --out)",
    )
    parser.add_argument("--solution", type=Path, help="the lab's source notebook")
    parser.add_argument(
        "--jobs", "-j", type=int, help="submissions at once (default: the cores)"
    )
    parser.add_argument(
        "--cell-timeout",
        type=float,
        default=60.0,
        help="s per student cell, call or check: CPU time, or wall time not spent "
        "waiting for a CPU (default: %(default)s)",
    )
    parser.add_argument(
        "--slower",
        type=float,
        default=20.0,
        help="a check may take this many times the solution's CPU time for it, "
        "or --cell-timeout if more; the submission this many times the "
        "solution's, or --timeout if more (default: %(default)s)",
    )
    parser.add_argument(
        "--timeout",
        type=float,
        default=600.0,
        help="s of CPU time per submission in total (default: %(default)s)",
    )
    parser.add_argument(
        "--backstop",
        type=float,
        default=30.0,
        help="wall-time limit, in multiples of the limits above: a submission "
        "that reaches it is reported 'machine overloaded: re-grade', never "
        "scored (default: %(default)s)",
    )
    parser.add_argument(
        "--restarts",
        type=int,
        default=3,
        help="restarts after a hang or crash (default: %(default)s)",
    )
    parser.add_argument(
        "--memory",
        type=float,
        default=6.0,
        help="GiB of address space per process (default: %(default)s)",
    )
    parser.add_argument(
        "--regrade",
        action="store_true",
        help="grade everyone again, the reference run too (an interrupted "
        "re-grade is finished by the next run)",
    )
    parser.add_argument(
        "--manual", type=Path, help="fold in the written answers' scores (CSV)"
    )
    parser.add_argument(
        "--no-sandbox",
        action="store_true",
        help="grade without bubblewrap (recorded in the gradebook)",
    )
    parser.add_argument(
        "--scheduler",
        help="grade on Dask: 'local' or a scheduler address (extra grade-dask)",
    )
    parser.add_argument(
        "--lms",
        choices=("canvas", "moodle"),
        help="also write <out>-<lms>.csv for the LMS's grade import (needs --roster)",
    )
    parser.add_argument(
        "--roster",
        type=Path,
        help="CSV mapping each submission to a student: folder, id, name, email, "
        "section, and optionally due (ISO date-time) and submitted",
    )
    parser.add_argument(
        "--due", help="due date-time (ISO, e.g. 2026-12-07T23:59; UTC unless given)"
    )
    parser.add_argument(
        "--late-penalty",
        type=float,
        default=0.1,
        help="fraction of the maximum taken per day late, in the LMS export and "
        "the report (default: %(default)s)",
    )
    parser.add_argument("--keep", action="store_true", help="keep the working folders")
    parser.add_argument("--quiet", "-q", action="store_true", help="no progress bar")


def run(args: argparse.Namespace) -> int:
    """Run ``robotlib grade``; return the exit status."""
    limits = sb.Limits(memory=int(args.memory * (1 << 30)))
    opts = Options(
        cell_timeout=args.cell_timeout,
        slower=args.slower,
        timeout=args.timeout,
        backstop=args.backstop,
        restarts=args.restarts,
        keep=args.keep,
        sandbox=not args.no_sandbox,
        limits=limits,
    )
    t0, wall0 = time.monotonic(), time.time()
    records = args.out.with_name(f"{args.out.stem}-records")
    feedback = args.feedback or args.out.with_name(f"{args.out.stem}-feedback")
    sheet = args.out.with_name(f"{args.out.stem}-manual.csv")
    hand_path = args.out.with_name(f"{args.out.stem}-hand.json")
    outputs = (args.out, records, feedback, sheet, hand_path)  # never students
    status = 0
    try:
        results, items = grade(
            args.submissions,
            args.lab,
            args.solution,
            args.jobs,
            opts,
            not args.quiet,
            records,
            args.regrade,
            args.scheduler,
            args.student,
            outputs,
        )
    except (GradeError, NotebookError, FileNotFoundError, ImportError) as exc:
        sys.stderr.write(f"robotlib grade: {exc}\n")
        return 2
    except KeyboardInterrupt:
        sys.stderr.write(
            "robotlib grade: interrupted; finished submissions are kept in "
            f"{records}/, run the same command again to finish\n"
        )
        results = []
        plan = _plan(
            notebook_text(read_notebook(args.solution or solution_path(args.lab))),
            args.lab,
        )
        items = plan.checks + plan.manual
        status = 130
    here = {r.student for r in results}
    earlier = [r for r in Records(records, args.lab).all() if r.student not in here]
    results = sorted(results + earlier, key=lambda r: r.student)
    manual = [c for c in items if c.manual]
    try:  # what the instructor typed into the sheet is kept before it is rewritten
        hand = HandGrades(hand_path)
        for src in (sheet if sheet.exists() else None, args.manual):
            if src is not None and manual:
                hand.merge(read_manual(src, manual))
        if hand.grades:
            hand.save()
    except (OSError, ValueError) as exc:
        sys.stderr.write(f"robotlib grade: {exc}\n")
        return 2
    ungraded = fold_manual(results, items, hand)
    write_gradebook(args.out, results, items)
    if manual:
        export_manual(sheet, results, manual, hand)
    write_feedback(feedback, results, items, args.lab)
    try:
        roster = read_roster(args.roster) if args.roster else None
        report = args.out.with_name(f"{args.out.stem}-report.html")
        class_report(report, results, items, args.lab, args.due, roster)
        if args.lms:
            if roster is None:
                raise ValueError("--lms needs --roster (folder -> student id)")
            lms = args.out.with_name(f"{args.out.stem}-{args.lms}.csv")
            missing = export_lms(
                lms, results, args.lms, args.lab, roster, args.due, args.late_penalty
            )
            if missing:
                sys.stderr.write(
                    f"robotlib grade: not in the roster, left out of {lms}: "
                    + ", ".join(missing[:10])
                    + "\n"
                )
    except (OSError, ValueError) as exc:
        sys.stderr.write(f"robotlib grade: {exc}\n")
        return 2
    auto = [c for c in items if not c.manual]
    full = sum(all(r.points.get(c.grade_id) == c.points for c in auto) for r in results)
    if busy := sum(r.status == OVERLOADED for r in results):
        sys.stderr.write(
            f"robotlib grade: the machine was too busy to grade {busy} submissions "
            "within the wall-time backstop; run the same command again to grade them\n"
        )
    fresh = sum(p.stat().st_mtime >= wall0 for p in records.glob("[!.]*.json"))
    sys.stderr.write(
        f"graded {fresh} submissions of {args.lab} in {time.monotonic() - t0:.1f} s"
        + (
            f", {len(results) - fresh} kept from earlier runs"
            if fresh < len(results)
            else ""
        )
        + f"; {full} of {len(results)} have full marks on the automatic checks"
        + (f", {ungraded} written answers to grade in {sheet}" if ungraded else "")
        + f"; gradebook {args.out}, feedback in {feedback}/\n"
    )
    return status
