"""Grade the class cases and the adversarial set three times: is every grade its worth?

python bench/bench_grade_cases.py [--lab lab2_avoidance] [--runs alone hog load]
                                  [--jobs 2] [--busy 2] [--cell-timeout 10]
                                  [--out bench/results/grade_cases_LAB.md]
                                  [--students answered ordinary_code ...]
                                  [--report DIR]

The submissions are built by ``tests/class_cases.py`` from the lab's
solution and release (honest layouts and mistakes, cheats, hangs, hogs, fork
bombs...), each with its expected points, status and flag. Runs: ``alone``
(the set as built), ``hog`` (one more classmate whose notebook forks four
busy loops), ``load`` (``--busy`` busy processes of this script's own beside
the run, ended after it); the reference run is saved by the first run and
reused. Writes a Markdown table: one line per run (wall time, 1-minute load
average sampled every 5 s, the cases graded as expected), then one row per
case (its points in each run, ``same`` when every run gave the same points
and status). The table is written after each run (a run cut short keeps
the runs before it). ``--report DIR`` also writes each run's class report
(``DIR/<lab>-<run>-report.html``, as ``robotlib grade`` does).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import nbformat

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # tests/class_cases.py

from robotlib.course import grade as g  # noqa: E402
from robotlib.course.notebooks import write_notebook  # noqa: E402
from robotlib.course.report import class_report  # noqa: E402
from tests.class_cases import Case, build, compare  # noqa: E402

HOG = (
    "import os\n"
    "for _ in range(4):  # busy loops that never end\n"
    "    if os.fork() == 0:\n        while True:\n            pass\n"
)


def _run(subs, lab, args, records, busy):
    procs = [
        subprocess.Popen([sys.executable, "-c", "while True:\n    pass"])
        for _ in range(busy)
    ]
    loads, stop = [], threading.Event()

    def sample() -> None:
        while not stop.wait(5.0):
            loads.append(os.getloadavg()[0])

    threading.Thread(target=sample, daemon=True).start()
    t0 = time.monotonic()
    opts = g.Options(cell_timeout=args.cell_timeout)
    try:
        results, checks = g.grade(
            subs,
            lab,
            jobs=args.jobs,
            opts=opts,
            progress=False,
            records=records,
            regrade=True,
            students=args.students,
        )
    finally:
        stop.set()
        for p in procs:
            p.kill()
            p.wait()
    return results, checks, time.monotonic() - t0, loads


def _table(args, cases, runs, rows, diffs) -> list[str]:
    """The Markdown table of the runs done (``runs``: their summary lines)."""
    lines = [
        f"# {args.lab}: class cases and adversarial set, graded {len(runs)} times",
        "",
        f"`{' '.join(sys.argv)}`, jobs {args.jobs}, cell limit floor "
        f"{args.cell_timeout:g} s, {os.cpu_count()} cores",
        "",
        "| run | wall | load (1 min) | as expected |",
        "|---|---|---|---|",
        *runs,
        "",
        "Differences from the expected worth:",
        "",
    ]
    lines += [f"- {d}" for d in diffs] or ["- none"]
    done = [r for r in args.runs if any(r in by_run for by_run in rows.values())]
    lines += [
        "",
        f"| case | kind | expected | {' | '.join(done)} | same |",
        "|---|---|---|" + "---|" * len(done) + "---|",
    ]
    for name, by_run in sorted(rows.items()):
        case = cases.get(name) or Case(name, "bench", "", None)
        want = "-" if case.points is None else f"{sum(case.points.values()):g}"
        got = []
        for run in done:  # "-": not graded in that run (the added hog)
            r = by_run.get(run)
            flag = ", flagged" if r and r.flags else ""
            got.append(f"{r.total:g} ({r.status}{flag})" if r else "-")
        results = list(by_run.values())
        same = len({(str(r.points), r.status) for r in results}) == 1
        lines.append(
            f"| {name} | {case.kind} | {want} | {' | '.join(got)} | "
            f"{'same' if same else 'DIFFERENT'} |"
        )
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lab", default="lab2_avoidance")
    parser.add_argument("--runs", nargs="+", default=["alone", "hog", "load"])
    parser.add_argument("--jobs", type=int, default=os.cpu_count())
    parser.add_argument("--busy", type=int, default=2)
    parser.add_argument("--cell-timeout", type=float, default=10.0)
    parser.add_argument("--out", type=Path)
    parser.add_argument("--students", nargs="+", help="grade only these cases")
    parser.add_argument("--report", type=Path, help="write each run's class report")
    args = parser.parse_args()
    out = args.out or ROOT / "bench" / "results" / f"grade_cases_{args.lab}.md"
    out.parent.mkdir(parents=True, exist_ok=True)
    runs: list[str] = []
    rows: dict[str, dict] = {}  # student -> run -> result
    diffs: list[str] = []
    with tempfile.TemporaryDirectory() as tmp:
        subs = Path(tmp) / "submissions"
        cases = build(args.lab, subs)
        if args.students:
            cases = {k: v for k, v in cases.items() if k in args.students}
        for run in args.runs:
            here = dict(cases)
            if run == "hog" and not (subs / "zz_hog").exists():
                nb = nbformat.read(subs / "answered" / f"{args.lab}.ipynb", 4)
                nb.cells.insert(2, nbformat.v4.new_code_cell(HOG))
                (subs / "zz_hog").mkdir()
                write_notebook(nb, subs / "zz_hog" / f"{args.lab}.ipynb")
            if run == "hog" and args.students:
                args.students.append("zz_hog")
            if (subs / "zz_hog").exists():
                here["zz_hog"] = Case(
                    "zz_hog", "bench", "the hog beside", None, None, True
                )
            busy = args.busy if run == "load" else 0
            results, checks, wall, loads = _run(
                subs, args.lab, args, Path(tmp) / "records", busy
            )
            if args.report:
                args.report.mkdir(parents=True, exist_ok=True)
                page = args.report / f"{args.lab}-{run}-report.html"
                class_report(page, results, checks, args.lab)
            wrong = compare(here, results)
            lo, hi = (min(loads), max(loads)) if loads else (0, 0)
            ok = f"{len(here) - len({w.split(':')[0] for w in wrong})} of {len(here)}"
            runs.append(f"| {run} | {wall:.0f} s | {lo:.1f}-{hi:.1f} | {ok} |")
            print(runs[-1], *wrong, sep="\n  ", flush=True)
            diffs += [f"{run}: {w}" for w in wrong]
            for r in results:
                rows.setdefault(r.student, {})[run] = r
            out.write_text("\n".join(_table(args, cases, runs, rows, diffs)) + "\n")
    print(out.read_text())
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
