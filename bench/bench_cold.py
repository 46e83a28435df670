"""Cold and warm start of `MCL.best` for two robotlib source trees, interleaved.

Run ``python bench/bench_cold.py OLD_TREE NEW_TREE [--rounds R] [--warm K]
[--world W]`` (trees as for ``bench/bench_ab.py``). Each round, per tree (the
order alternates), one fresh process with an empty numba cache (a new
``NUMBA_CACHE_DIR``, so the cone table's disk cache is empty too), and then
``K`` more on the cache it left (warm), alternating between the trees:
each imports robotlib, loads the world, builds `MCL.best` and takes its
first step. Prints per tree the
median CPU time (all threads) and wall time of each part (import, filter,
first step), the total, the ratios old / new, the number of kernels numba
compiled in the process, and the load average; for a tree whose `MCL.best`
compiles in a helper process (`robotlib.localization._prebuild`), also the
helper's processor time (to the end of the steps it takes, and to its
end) and how long the first step waited for it. The
totals are this process's own. The scan the step weighs is computed
before the timer of the step starts (outside the totals). Asserts nothing.

Python's own bytecode cache is treated like numba's: each round runs a
fresh copy of the tree's ``robotlib/`` and ``worlds/`` (no ``__pycache__``)
with ``PYTHONDONTWRITEBYTECODE`` unset, so the cold process compiles
robotlib's sources and the warm one reads them compiled, as after an
install (``--bytecode off`` keeps the environment's setting: with it set,
every process compiles robotlib's sources, about 0.1 s). numpy's and
numba's bytecode is whatever their install left, the same for both trees.
"""

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile

_CHILD = r"""
import json, os, sys, time
tree, world_name = sys.argv[1:3]
sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in repr(f).lower()]
sys.path.insert(0, tree)
c0, t0 = time.process_time(), time.perf_counter()
import numpy as np
from robotlib.localization import MCL, expected_readings
from robotlib.world import load_world
import robotlib
assert robotlib.__file__.startswith(os.path.abspath(tree)), robotlib.__file__
from numba.core import event  # after robotlib's imports, as numba comes in there
compiled = []
class _Count(event.Listener):
    def on_start(self, ev):
        pass
    def on_end(self, ev):
        compiled.append(1)
event.register("numba:compile", _Count())
world = load_world(world_name)
c1, t1 = time.process_time(), time.perf_counter()
mcl = MCL.best(world, rng=0)
c2, t2 = time.process_time(), time.perf_counter()
n_before = len(compiled)
z = expected_readings(world, np.array([world.start]))[0]
odo = np.array(world.start)
n_scan = len(compiled) - n_before
c3, t3 = time.process_time(), time.perf_counter()
mcl.step(odo, odo + [0.5, 0.0, 0.05], z)
c4, t4 = time.process_time(), time.perf_counter()
import resource
try:  # a tree that compiles in a helper process: its processor time too
    from robotlib.localization import _prebuild
except ImportError:
    _prebuild = None
waited, to_ready = 0.0, 0.0
for h in getattr(_prebuild, "started", ()):
    h.proc.wait()
    waited += h.waited
    to_ready += h.cpu
ru = resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({"import": [c1 - c0, t1 - t0], "filter": [c2 - c1, t2 - t1],
                  "step": [c4 - c3, t4 - t3],
                  "total": [c4 - c3 + c2 - c0, t4 - t3 + t2 - t0],
                  "helper": [ru.ru_utime + ru.ru_stime, waited, to_ready],
                  "compiled": len(compiled) - n_scan}))
"""

_PARTS = ("import", "filter", "step", "total")


def _copy(tree: str, into: str) -> str:
    """A copy of ``tree``'s ``robotlib/`` and ``worlds/`` in ``into``, no caches."""
    src = os.path.join(into, "src")
    skip = shutil.ignore_patterns("__pycache__")
    for part in ("robotlib", "worlds"):
        shutil.copytree(os.path.join(tree, part), os.path.join(src, part), ignore=skip)
    return src


def _run(tree: str, cache: str, world: str, bytecode: bool = True,
         prebuild: str | None = None) -> dict:  # fmt: skip
    env = dict(os.environ, NUMBA_CACHE_DIR=cache)
    if prebuild is not None:
        env["ROBOTLIB_PREBUILD"] = prebuild
    env.pop("ROBOTLIB_TABLE_CACHE", None)
    if bytecode:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
    cmd = [sys.executable, "-c", _CHILD, tree, world]
    done = subprocess.run(cmd, capture_output=True, text=True, env=env, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> int:
    """Run the comparison; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old")
    parser.add_argument("new")
    parser.add_argument("--rounds", type=int, default=1)
    parser.add_argument("--world", default="corridor")
    parser.add_argument("--bytecode", choices=("on", "off"), default="on")
    parser.add_argument(
        "--warm", type=int, default=1, help="warm runs per tree and round (alternating)"
    )
    parser.add_argument(
        "--prebuild",
        default=None,
        help="ROBOTLIB_PREBUILD for the runs: 1 (a helper even on a busy machine),"
        " 0, auto (a helper with a core to spare); default: the environment's",
    )
    args = parser.parse_args()
    bytecode = args.bytecode == "on"
    runs = {(t, k): [] for t in ("old", "new") for k in ("cold", "warm")}
    for r in range(args.rounds):
        order = ("old", "new") if r % 2 == 0 else ("new", "old")
        caches = {name: tempfile.mkdtemp(prefix="robotlib-cold-") for name in order}
        try:
            trees = {}
            for name in order:
                trees[name] = getattr(args, name)
                if bytecode:
                    trees[name] = _copy(trees[name], caches[name])
                tree, cache = trees[name], caches[name]
                runs[name, "cold"].append(
                    _run(tree, cache, args.world, bytecode, args.prebuild)
                )
            for _ in range(args.warm):  # warm runs alternate between the trees
                for name in order:
                    tree, cache = trees[name], caches[name]
                    runs[name, "warm"].append(
                        _run(tree, cache, args.world, bytecode, args.prebuild)
                    )
        finally:
            for cache in caches.values():
                shutil.rmtree(cache, ignore_errors=True)
    for kind in ("cold", "warm"):
        for name in ("old", "new"):
            rows = runs[name, kind]
            parts = ", ".join(
                f"{p} {statistics.median(x[p][0] for x in rows):.2f}"
                f" ({statistics.median(x[p][1] for x in rows):.2f} wall)"
                for p in _PARTS
            )
            n = statistics.median(x["compiled"] for x in rows)
            print(f"{kind} {name}: CPU s {parts}; {n:g} kernels compiled")  # noqa: T201
            helper = [x.get("helper", [0.0, 0.0, 0.0]) for x in rows]
            if any(h[0] for h in helper):
                print(  # noqa: T201
                    f"  {kind} {name}: helper process CPU s"
                    f" {statistics.median(h[2] for h in helper):.2f} to its ready"
                    f" ({statistics.median(h[0] for h in helper):.2f} to its end),"
                    f" waited for {statistics.median(h[1] for h in helper):.2f} s wall"
                )
        ratio = statistics.median(x["total"][0] for x in runs["old", kind]) / (
            statistics.median(x["total"][0] for x in runs["new", kind])
        )
        print(f"{kind} old/new total CPU: {ratio:.2f}")  # noqa: T201
    with open("/proc/loadavg") as f:
        print("load average:", " ".join(f.read().split()[:3]))  # noqa: T201
    return 0


if __name__ == "__main__":
    sys.exit(main())
