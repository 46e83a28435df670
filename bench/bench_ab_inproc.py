"""A/B of two robotlib trees in ONE process: the MCL step, interleaved blocks.

Run ``python bench/bench_ab_inproc.py OLD_TREE [--blocks B] SPEC ...`` with
``OLD_TREE`` a directory holding a ``robotlib`` package (e.g. ``git archive
main | tar -x -C /tmp/old``) and each SPEC ``n:reps[:model]`` (model
``beam``, the default, or ``paper``). The old package is copied (once per
old tree, kept so numba's cache of it is too) to a directory under the
system's temporary one as ``robotlib_old`` (its imports are relative) and
imported beside the ``robotlib`` this interpreter finds (the new one); both
filters are built the same way as in ``bench/bench_ab.py`` (systematic
resampling every step, particles reset to the same uniform set before each
step) and timed in alternating blocks of ``reps`` steps, so both see the
same load. Prints per tree the median and fastest step, the CPU time per
step (this thread's below 4,096 particles, the process's from there on:
the threaded paths), the ratios old / new, whether both gave the same
estimate and particles, and the load average. On a shared machine the CPU
time and the fastest step are the steadier figures. Asserts nothing.
"""

import argparse
import hashlib
import importlib
import os
import shutil
import statistics
import sys
import tempfile
import time

import numpy as np


def _filter(pkg: str, n: int, model: str, world_name="corridor", fast=True):
    loc = importlib.import_module(pkg + ".localization")
    world = importlib.import_module(pkg + ".world").load_world(world_name)
    z = loc.expected_readings(world, np.array([world.start]))[0]
    odo0 = np.array(world.start)
    odo1 = odo0 + [0.5, 0.0, 0.05]
    start = world.sample_free_poses(n, 0)
    sensor = (
        loc.BeamSensorModel(world, fast=fast, params=loc.BeamParameters(exponent=0.2))
        if model == "beam"
        else loc.PaperSensorModel(world, fast=fast)
    )
    mcl = loc.MCL(world, sensor, resampling=loc.ThresholdResampling("systematic", 1.0),
                  n=n, rng=0, check=False)  # fmt: skip

    def step():
        mcl.set_particles(start)
        mcl.step(odo0, odo1, z)

    return mcl, step


def main() -> int:
    """Run the A/B; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old")
    parser.add_argument("specs", nargs="+", help="n:reps[:model]")
    parser.add_argument("--blocks", type=int, default=10)
    parser.add_argument("--world", default="corridor", help="world of the filters")
    parser.add_argument(
        "--exact", action="store_true", help="the exact path (cone casts, no table)"
    )
    args = parser.parse_args()
    old = os.path.abspath(args.old)
    tag = hashlib.sha1(old.encode()).hexdigest()[:12]
    tmp = os.path.join(tempfile.gettempdir(), f"robotlib-ab-{tag}")
    if not os.path.isdir(os.path.join(tmp, "robotlib_old")):
        os.makedirs(tmp, exist_ok=True)
        shutil.copytree(
            os.path.join(old, "robotlib"), os.path.join(tmp, "robotlib_old")
        )
        os.symlink(os.path.join(old, "worlds"), os.path.join(tmp, "worlds"))
    sys.path.insert(0, tmp)
    for spec in args.specs:
        parts = spec.split(":")
        n, reps = int(parts[0]), int(parts[1])
        model = parts[2] if len(parts) > 2 else "beam"
        trees = {
            "old": _filter("robotlib_old", n, model, args.world, not args.exact),
            "new": _filter("robotlib", n, model, args.world, not args.exact),
        }
        for _, step in trees.values():
            for _ in range(3):
                step()
        threaded = n >= (64 if args.exact else 4096)  # the exact casts' threads
        clock = time.process_time if threaded else time.thread_time
        times = {k: [] for k in trees}
        cpu = {k: [] for k in trees}
        for b in range(args.blocks):
            for name in ("old", "new") if b % 2 == 0 else ("new", "old"):
                step = trees[name][1]
                c0 = clock()
                for _ in range(reps):
                    t0 = time.perf_counter()
                    step()
                    times[name].append(time.perf_counter() - t0)
                cpu[name].append((clock() - c0) / reps)
        row = {
            k: (1e3 * statistics.median(times[k]), 1e3 * min(times[k]),
                1e3 * statistics.median(cpu[k]))
            for k in trees
        }  # fmt: skip
        o, w = row["old"], row["new"]
        a, b = trees["old"][0], trees["new"][0]
        same = np.array_equal(a.last_estimate, b.last_estimate) and np.array_equal(
            a.particles, b.particles
        )
        print(  # noqa: T201
            f"{model} N={n}: old median {o[0]:.4f} ms, fastest {o[1]:.4f}, cpu "
            f"{o[2]:.4f} | new median {w[0]:.4f}, fastest {w[1]:.4f}, cpu "
            f"{w[2]:.4f} | old/new: median {o[0] / w[0]:.2f}, fastest "
            f"{o[1] / w[1]:.2f}, cpu {o[2] / w[2]:.2f} | same numbers: {same}",
            flush=True,
        )
    with open("/proc/loadavg") as f:
        print("load average:", " ".join(f.read().split()[:3]))  # noqa: T201
    return 0


if __name__ == "__main__":
    sys.exit(main())
