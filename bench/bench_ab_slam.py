"""A/B of two robotlib source trees: mapping's sonar update and FastSLAM step.

Run ``python bench/bench_ab_slam.py OLD_TREE NEW_TREE [--rounds R]`` where
each tree is a directory holding a ``robotlib`` package (e.g. ``git archive
main | tar -x -C /tmp/old``). Each round runs one fresh process per tree
(the order alternates); each times, after a warm-up, one sonar ring update
(8 cones) at 5 cm and at 10 cm cells (``OccupancyGrid.update_sonar`` on the
bench's reading, as ``robotlib bench slam``), and 60 steps of laser grid
FastSLAM with 30 particles on the loop world as they come in a run (from a
third of the way round). Prints per tree the median over rounds of the CPU
time per call (the steadier figure on a shared machine) and of the fastest
call, the ratios old / new, and the load average. Asserts nothing.
"""

import argparse
import json
import statistics
import subprocess
import sys

_CHILD = r"""
import json, os, sys, time
tree = sys.argv[1]
sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in repr(f).lower()]
sys.path.insert(0, tree)
import numpy as np
import robotlib
assert robotlib.__file__.startswith(os.path.abspath(tree)), robotlib.__file__
from robotlib.mapping import GridFastSLAM, OccupancyGrid, record_drive
from robotlib.sensing import SonarModel
log = record_drive("loop", seed=0, every=2)
t = len(log) // 3
sonar = SonarModel()
out = {}
def cpu_per_call(fn, n):
    fn()
    best = float("inf")
    c0 = time.process_time()
    for _ in range(n):
        w0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - w0)
    return 1e6 * (time.process_time() - c0) / n, 1e6 * best
for res in (0.05, 0.1):
    g = OccupancyGrid.for_world(log.world, res)
    out[f"sonar_{res}"] = cpu_per_call(
        lambda: g.update_sonar(log.truth[t], log.sonar[t], sonar), 3000)
f = GridFastSLAM.for_world(log.world, 0.05, start=log.odometry[0], n_particles=30,
                           rng=0)
for i in range(t):
    f.step(log.odometry[i], log.laser[i])
times = []
c0 = time.process_time()
for i in range(t, t + 60):
    w0 = time.perf_counter()
    f.step(log.odometry[i], log.laser[i])
    times.append(time.perf_counter() - w0)
out["fastslam_step"] = (1e6 * (time.process_time() - c0) / 60, 1e6 * min(times))
out["path"] = f.best_path()[-1].tolist()
print(json.dumps(out))
"""

ROWS = {
    "sonar_0.05": "sonar update, 8 cones, 5 cm (us)",
    "sonar_0.1": "sonar update, 8 cones, 10 cm (us)",
    "fastslam_step": "laser FastSLAM step, 30 particles (us)",
}


def _run(tree: str) -> dict:
    cmd = [sys.executable, "-c", _CHILD, tree]
    done = subprocess.run(cmd, capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> int:
    """Run the A/B; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old")
    parser.add_argument("new")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    runs = {"old": [], "new": []}
    for r in range(args.rounds):
        for name in ("old", "new") if r % 2 == 0 else ("new", "old"):
            runs[name].append(_run(getattr(args, name)))
    for key, label in ROWS.items():
        o = [x[key] for x in runs["old"]]
        w = [x[key] for x in runs["new"]]
        oc, wc = statistics.median(v[0] for v in o), statistics.median(v[0] for v in w)
        of, wf = min(v[1] for v in o), min(v[1] for v in w)
        print(  # noqa: T201
            f"{label}: old cpu {oc:.1f}, fastest {of:.1f} | new cpu {wc:.1f}, "
            f"fastest {wf:.1f} | old/new cpu x{oc / wc:.2f}, fastest x{of / wf:.2f}",
            flush=True,
        )
    pairs = zip(runs["old"], runs["new"], strict=True)
    same = [a["path"] == b["path"] for a, b in pairs]
    print("same last pose of the best path:", all(same))  # noqa: T201
    with open("/proc/loadavg") as f:
        print("load average:", " ".join(f.read().split()[:3]))  # noqa: T201
    return 0


if __name__ == "__main__":
    sys.exit(main())
