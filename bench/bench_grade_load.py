"""Grade the same small class several times, under more load: are the scores equal?

python bench/bench_grade_load.py [--lab lab4_navigation] [--runs 0 hog hog+2]
                                 [--jobs 2]

The class: the solution, a correct but slow A* (a list as its closed set,
Lab 4), a sign error in ``steer`` (Lab 4), the released lab. Each run is
``N`` (that many busy processes of the bench's own, ended after the run,
beside whatever the machine is doing), ``hog`` (a classmate graded
alongside whose notebook forks four busy loops) or ``hog+N`` (both); the
reference run is saved after the first run and reused. Prints one row per
student and run, the wall time of each run and the machine's 1-minute load
average during it, then each student's scores side by side.
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

from robotlib.course import grade as g
from robotlib.course.notebooks import read_notebook, release_notebook, write_notebook

ROOT = Path(__file__).resolve().parents[1]


def _variants(lab: str) -> dict:
    sol = read_notebook(ROOT / "solutions" / f"{lab}.ipynb")
    out = {"solution": sol, "released": release_notebook(sol, lab)}
    if lab == "lab4_navigation":
        slow = read_notebook(ROOT / "solutions" / f"{lab}.ipynb")
        cell = next(c for c in slow.cells if "def astar_grid" in c.source)
        cell.source = cell.source.replace("closed = set()", "closed = []").replace(
            "closed.add(u)", "closed.append(u)"
        )
        out["slow_astar"] = slow
        sign = read_notebook(ROOT / "solutions" / f"{lab}.ipynb")
        cell = next(c for c in sign.cells if "def steer" in c.source)
        wrong = "pose[2], 2 * math.pi)\n    alpha = -alpha"
        cell.source = cell.source.replace("pose[2], 2 * math.pi)", wrong)
        out["steer_sign"] = sign
    return out


HOG = (
    "import os\n"
    "for _ in range(4):  # busy loops that never end\n"
    "    if os.fork() == 0:\n        while True:\n            pass\n"
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lab", default="lab4_navigation")
    parser.add_argument("--runs", nargs="+", default=["0", "hog", "hog+2"])
    parser.add_argument("--jobs", type=int, default=os.cpu_count())
    args = parser.parse_args()
    rows: dict[str, list] = {}
    with tempfile.TemporaryDirectory() as tmp:
        subs = Path(tmp) / "submissions"
        variants = _variants(args.lab)
        names = list(variants)
        hog = read_notebook(ROOT / "solutions" / f"{args.lab}.ipynb")
        hog.cells.append(nbformat.v4.new_code_cell(HOG))
        for name, nb in (*variants.items(), ("hog", hog)):
            (subs / name).mkdir(parents=True)
            write_notebook(nb, subs / name / f"{args.lab}.ipynb")
        for run in args.runs:
            extra = int(run.rpartition("+")[2] if run != "hog" else 0)
            busy = [
                subprocess.Popen([sys.executable, "-c", "while True:\n    pass"])
                for _ in range(extra)
            ]
            loads, stop = [], threading.Event()

            def sample(loads=loads, stop=stop) -> None:
                while not stop.wait(10.0):
                    loads.append(os.getloadavg()[0])

            threading.Thread(target=sample, daemon=True).start()
            t0 = time.monotonic()
            try:
                results, _ = g.grade(
                    subs,
                    args.lab,
                    jobs=args.jobs,
                    progress=False,
                    records=Path(tmp) / "records",
                    # all again, the saved reference run reused
                    students=names + (["hog"] if run.startswith("hog") else []),
                )
            finally:
                stop.set()
                for p in busy:
                    p.kill()
                    p.wait()
            wall = time.monotonic() - t0
            lo, hi = (min(loads), max(loads)) if loads else (0.0, 0.0)
            print(f"run {run}: {wall:.0f} s, load {lo:.1f}-{hi:.1f}", flush=True)
            for r in results:  # printed as they come: an interrupted bench keeps them
                rows.setdefault(r.student, []).append((r.total, r.status, r.points))
                how = f"{r.status}, {r.seconds:.0f} s"
                flags = "; ".join(r.flags)
                print(f"  {r.student:12s} {r.total:g} ({how}) {r.points} {flags}")
    for student, runs in sorted(rows.items()):
        totals = [f"{t:g} ({s})" for t, s, _ in runs]
        same = "same" if len({str(a) for _, _, a in runs}) == 1 else "DIFFERENT"
        print(f"{student:12s} " + " | ".join(totals) + f"  {same}")


if __name__ == "__main__":
    main()
