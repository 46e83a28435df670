"""A/B of two robotlib source trees: grid ray casting and the exact cone casts.

Run ``python bench/bench_ab_cast.py OLD_TREE NEW_TREE [--rounds R]`` where
each tree is a directory holding a ``robotlib`` package (e.g. ``git archive
main | tar -x -C /tmp/old``). Each round runs one fresh process per tree
(the order alternates) on one numba thread, timing:

- grid casting (`robotlib.sensing.cast_rays_grid` with its field computed
  once): 64 rays from each of 10,000 free poses, on the office at 5 cm and
  on a generated 50 m x 50 m building at 5 cm (1000 x 1000 cells);
- the exact path's expected readings (`robotlib.localization.expected_readings`,
  no table) of 300 free poses in the office (113 walls) and the ``building``
  world (308 walls), serially and (a second figure) on 2 threads.

Prints per tree the rays per second of CPU time (median of the rounds) and
of the fastest wall-clock repetition, the milliseconds of the exact casts,
the ratios, whether both trees gave the same bits, and the load average. On
a machine shared with other work the CPU figures are the steadier ones.
Asserts nothing.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys

_CHILD = r"""
import hashlib, json, math, os, statistics, sys, time
tree = sys.argv[1]
sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in repr(f).lower()]
sys.path.insert(0, tree)
import numba
import numpy as np
import robotlib
assert robotlib.__file__.startswith(os.path.abspath(tree)), robotlib.__file__
from robotlib.experiments.bench_mcl import square_world
from robotlib.localization import expected_readings
from robotlib.sensing import cast_rays_grid, grid_field
from robotlib.world import load_world

def timed(f, reps):
    f()
    wall, cpu = [], []
    for _ in range(reps):
        c0, t0 = time.process_time(), time.perf_counter()
        f()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return min(wall), statistics.median(cpu)

out = {}
numba.set_num_threads(1)
angles = np.linspace(-math.pi, math.pi, 64, endpoint=False)
for name, world in (("office", load_world("office")), ("50 m", square_world(50.0))):
    grid = world.occupancy_grid(0.05)
    field = grid_field(grid)
    poses = world.sample_free_poses(10000, 0, radius=0.0)
    got = cast_rays_grid(grid, poses, angles, 5.0, field)
    wall, cpu = timed(lambda: cast_rays_grid(grid, poses, angles, 5.0, field), 5)
    out["grid " + name] = {"wall": got.size / wall, "cpu": got.size / cpu,
                           "bits": hashlib.sha1(got.tobytes()).hexdigest()}
for threads in (1, 2):
    numba.set_num_threads(threads)
    for name in ("office", "building"):
        world = load_world(name)
        poses = world.sample_free_poses(300, 0)
        got = expected_readings(world, poses)
        wall, cpu = timed(lambda: expected_readings(world, poses), 200)
        bits = hashlib.sha1(got.tobytes()).hexdigest()
        out[f"exact {name} {threads}t"] = {"wall": 1e3 * wall, "cpu": 1e3 * cpu,
                                         "bits": bits}
print(json.dumps(out))
"""


def _run(tree) -> dict:
    env = dict(os.environ, NUMBA_NUM_THREADS="2")
    cmd = [sys.executable, "-c", _CHILD, tree]
    done = subprocess.run(cmd, capture_output=True, text=True, env=env, check=True)
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
    for key in runs["old"][0]:
        o = [x[key] for x in runs["old"]]
        w = [x[key] for x in runs["new"]]
        same = all(a["bits"] == b["bits"] for a, b in zip(o, w, strict=True))
        cpu_o = statistics.median(x["cpu"] for x in o)
        cpu_w = statistics.median(x["cpu"] for x in w)
        if key.startswith("grid"):
            best_o, best_w = max(x["wall"] for x in o), max(x["wall"] for x in w)
            print(  # noqa: T201
                f"{key}, 1 thread: old {cpu_o / 1e6:.1f} M rays per CPU s (fastest "
                f"{best_o / 1e6:.1f} M/s) | new {cpu_w / 1e6:.1f} ({best_w / 1e6:.1f})"
                f" | new/old CPU x{cpu_w / cpu_o:.2f}, fastest x{best_w / best_o:.2f}"
                f" | same bits: {same}"
            )
        else:
            best_o, best_w = min(x["wall"] for x in o), min(x["wall"] for x in w)
            print(  # noqa: T201
                f"{key} N=300: old {cpu_o:.3f} ms CPU (fastest {best_o:.3f}) | new "
                f"{cpu_w:.3f} ({best_w:.3f}) | old/new CPU x{cpu_o / cpu_w:.2f}, "
                f"fastest x{best_o / best_w:.2f} | same bits: {same}"
            )
    with open("/proc/loadavg") as f:
        print("load average:", " ".join(f.read().split()[:3]))  # noqa: T201
    return 0


if __name__ == "__main__":
    sys.exit(main())
