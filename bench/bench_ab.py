"""A/B of two robotlib source trees: the MCL step, interleaved in one run.

Run ``python bench/bench_ab.py OLD_TREE NEW_TREE [--rounds R] [--exact]
[--world W] [--threads T] SPEC ...`` where each tree is a directory holding a
``robotlib`` package (e.g. ``git archive main | tar -x -C /tmp/old``) and
each SPEC is ``n:reps[:model]`` (model ``beam``, the default, or ``paper``).
Each round runs one fresh process per tree (the order alternates), each
timing ``reps`` steps of `MCL` (systematic resampling every step, particles
reset to the same uniform set before each step, as ``robotlib bench mcl``)
after three warm-up steps. Prints per tree the median of the rounds'
median step, the fastest step, the CPU time per step (all threads), the
ratios old / new, whether both trees gave the same estimate, and the load
average. On a machine shared with other work the CPU time and the fastest
step are the steadier figures. Asserts nothing.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys

_CHILD = r"""
import json, os, sys, time
tree, n, reps, model, world_name, exact = sys.argv[1:7]
sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in repr(f).lower()]
sys.path.insert(0, tree)
import numpy as np
from robotlib.localization import (MCL, BeamParameters, BeamSensorModel,
    PaperSensorModel, ThresholdResampling, expected_readings)
from robotlib.world import load_world
import robotlib
assert robotlib.__file__.startswith(os.path.abspath(tree)), robotlib.__file__
n, reps, fast = int(n), int(reps), exact != "1"
world = load_world(world_name)
z = expected_readings(world, np.array([world.start]))[0]
odo0 = np.array(world.start)
odo1 = odo0 + [0.5, 0.0, 0.05]
start = world.sample_free_poses(n, 0)
sensor = (BeamSensorModel(world, fast=fast, params=BeamParameters(exponent=0.2))
          if model == "beam" else PaperSensorModel(world, fast=fast))
mcl = MCL(world, sensor, resampling=ThresholdResampling("systematic", 1.0), n=n,
          rng=0, check=False)
def step():
    mcl.set_particles(start)
    mcl.step(odo0, odo1, z)
for _ in range(3):
    step()
times = []
c0 = time.process_time()
for _ in range(reps):
    t0 = time.perf_counter()
    step()
    times.append(time.perf_counter() - t0)
cpu = (time.process_time() - c0) / reps
print(json.dumps({"med": 1e3 * float(np.median(times)), "min": 1e3 * min(times),
                  "cpu": 1e3 * cpu, "est": mcl.last_estimate.tolist()}))
"""


def _run(tree, spec, args) -> dict:
    parts = spec.split(":")
    n, reps = parts[0], parts[1]
    model = parts[2] if len(parts) > 2 else "beam"
    env = dict(os.environ)
    if args.threads:
        env["NUMBA_NUM_THREADS"] = str(args.threads)
    cmd = [sys.executable, "-c", _CHILD, tree, n, reps, model, args.world,
           "1" if args.exact else "0"]  # fmt: skip
    done = subprocess.run(cmd, capture_output=True, text=True, env=env, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> int:
    """Run the A/B; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old")
    parser.add_argument("new")
    parser.add_argument("specs", nargs="+", help="n:reps[:model]")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--exact", action="store_true", help="the exact path")
    parser.add_argument("--world", default="corridor")
    parser.add_argument("--threads", type=int, default=0, help="0: numba's default")
    args = parser.parse_args()
    path = "exact" if args.exact else "fast"
    for spec in args.specs:
        runs = {"old": [], "new": []}
        for r in range(args.rounds):
            order = ("old", "new") if r % 2 == 0 else ("new", "old")
            for name in order:
                runs[name].append(_run(getattr(args, name), spec, args))
        o, w = runs["old"], runs["new"]

        def med(rows, key):
            return statistics.median(x[key] for x in rows)

        def low(rows, key):
            return min(x[key] for x in rows)

        same = all(a["est"] == b["est"] for a, b in zip(o, w, strict=True))
        print(  # noqa: T201
            f"{path} {args.world} {spec}: old median {med(o, 'med'):.3f} ms, fastest "
            f"{low(o, 'min'):.3f}, cpu {med(o, 'cpu'):.3f} | new median "
            f"{med(w, 'med'):.3f}, fastest {low(w, 'min'):.3f}, cpu "
            f"{med(w, 'cpu'):.3f} | old/new: median "
            f"{med(o, 'med') / med(w, 'med'):.2f}, fastest "
            f"{low(o, 'min') / low(w, 'min'):.2f}, cpu "
            f"{med(o, 'cpu') / med(w, 'cpu'):.2f} | same estimate: {same}",
            flush=True,
        )
    with open("/proc/loadavg") as f:
        print("load average:", " ".join(f.read().split()[:3]))  # noqa: T201
    return 0


if __name__ == "__main__":
    sys.exit(main())
