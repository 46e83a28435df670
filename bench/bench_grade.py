"""Grade a folder of N copies of a lab's solution and print the wall time.

python bench/bench_grade.py [--lab lab3_mcl] [--copies 30] [--jobs 2]
                            [--solution PATH] [--scheduler local]
                            [--records DIR] [--out FILE.md]

``--records DIR`` keeps the reference run there: a second run with the same
folder grades every copy again but reuses it (the time of the class alone).
``--scheduler local`` grades on a local Dask cluster of ``--jobs`` workers.
``--out`` appends the run as a row of a Markdown table (written with its
header when new).

The issue's target, a class of 200 Lab 4 submissions on 2 quiet cores in 30
minutes, reference run included (a fresh ``--records`` folder)::

    python bench/bench_grade.py --lab lab4_navigation --copies 200 --jobs 2 \
        --records /tmp/class200 --out bench/results/grade_class200.md

``--solution`` grades copies of another version of the lab's source notebook
(e.g. an older one from git) against itself, to compare grading costs.
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import threading
import time
from pathlib import Path

from robotlib.course import grade as g

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lab", default="lab3_mcl")
    parser.add_argument("--copies", type=int, default=30)
    parser.add_argument("--jobs", type=int, default=os.cpu_count())
    parser.add_argument("--solution", type=Path, help="the lab's source notebook")
    parser.add_argument("--scheduler", help="local, or a Dask scheduler's address")
    parser.add_argument("--records", type=Path, help="keep the reference run here")
    parser.add_argument("--out", type=Path, help="append a Markdown row here")
    args = parser.parse_args()
    solution = args.solution or ROOT / "solutions" / f"{args.lab}.ipynb"
    with tempfile.TemporaryDirectory() as tmp:
        subs = Path(tmp) / "submissions"
        for i in range(args.copies):
            (subs / f"student{i:02d}").mkdir(parents=True)
            shutil.copy(solution, subs / f"student{i:02d}" / f"{args.lab}.ipynb")
        loads, stop = [], threading.Event()

        def sample() -> None:  # the machine's 1-minute load average, every 10 s
            while not stop.wait(10.0):
                loads.append(os.getloadavg()[0])

        threading.Thread(target=sample, daemon=True).start()
        saved = args.records and any(args.records.glob(".reference/*"))
        ref = "saved" if saved else "included"
        t0 = time.monotonic()
        names = [f"student{i:02d}" for i in range(args.copies)]
        results, checks = g.grade(
            subs,
            args.lab,
            solution,
            jobs=args.jobs,
            progress=False,
            records=args.records,
            scheduler=args.scheduler,
            students=names if args.records else None,  # all again, reference kept
        )
        wall = time.monotonic() - t0
        stop.set()
        g.write_gradebook(Path(tmp) / "gradebook.csv", results, checks)
    auto = [c for c in checks if not c.manual]  # written answers: graded by hand
    full = sum(all(r.points.get(c.grade_id) == c.points for c in auto) for r in results)
    secs = sorted(r.seconds for r in results)
    print(
        f"lab {args.lab} ({solution.name}): {args.copies} copies, "
        f"{args.jobs} jobs ({args.scheduler or 'threads'}), {os.cpu_count()} cores"
    )
    print(
        f"wall time {wall:.1f} s (reference run included unless saved), "
        f"{full}/{len(results)} full marks on the automatic checks"
    )
    print(
        f"per submission: median {secs[len(secs) // 2]:.1f} s, "
        f"min {secs[0]:.1f} s, max {secs[-1]:.1f} s"
    )
    print(f"throughput {args.copies / wall * 60:.1f} submissions per minute")
    if loads:
        print(
            f"load average (1 min, every 10 s): min {min(loads):.1f}, "
            f"median {sorted(loads)[len(loads) // 2]:.1f}, max {max(loads):.1f}"
        )
    if args.out:
        _row(args, ref, wall, f"{full}/{len(results)}", secs, loads)


def _row(args, ref: str, wall: float, full: str, secs, loads) -> None:
    """Append the run to the Markdown table ``args.out``."""
    head = (
        "| when (UTC) | lab | copies | jobs | scheduler | reference | wall | "
        "full marks | per submission (median) | load (1 min: min, median, max) |\n"
        "|---|---|---|---|---|---|---|---|---|---|\n"
    )
    load = (
        f"{min(loads):.1f}, {sorted(loads)[len(loads) // 2]:.1f}, {max(loads):.1f}"
        if loads
        else "-"
    )
    when = time.strftime("%Y-%m-%d %H:%M", time.gmtime())
    row = (
        f"| {when} | {args.lab} | {args.copies} | {args.jobs} | "
        f"{args.scheduler or 'threads'} | {ref} | {wall / 60:.1f} min | {full} | "
        f"{secs[len(secs) // 2]:.1f} s | {load} |\n"
    )
    args.out.parent.mkdir(parents=True, exist_ok=True)
    new = not args.out.exists()
    with open(args.out, "a", encoding="utf-8") as f:
        f.write((head if new else "") + row)


if __name__ == "__main__":
    main()
