"""A map made ready for MCL by two checkouts, interleaved, each in a fresh process.

    python bench/bench_prep_ab.py OLD_CHECKOUT [--map FILE] [--rounds 2]

Each round runs this checkout and ``OLD_CHECKOUT`` (e.g. ``/work/main``) one
after the other, each in a fresh process with its own numba cache (kernels
loaded or compiled on a small part of the map first, untimed) and the table
cache off: loading the map, its free space and its cone table, in CPU and
wall seconds, the process's peak resident memory, and a digest of the table
(equal digests: the same table, entry for entry). Prints the CPU ratio
old/new. For a machine shared with other work, where wall times mislead.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

CHILD = r"""
import hashlib, json, os, resource, sys, time
from robotlib.world import load_world
from robotlib.localization import ConeTable
world = load_world(sys.argv[1])
warm = type(world)(world.obstacles[:3000], bounds=world.bounds)
ConeTable(warm, resolution=1.0)
warm.free_space(1.0, 0.2)
out = {}
def timed(name, f):
    w, c = time.perf_counter(), time.process_time()
    r = f()
    out[name] = [time.perf_counter() - w, time.process_time() - c]
    return r
world = timed("load", lambda: load_world(sys.argv[1]))
timed("free", lambda: world.free_space(0.05, 0.2))
table = timed("table", lambda: ConeTable(world))
out["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
# the digest after the peak is read (`tobytes` copied the table: +72 MB on columbia)
out["digest"] = hashlib.sha256(memoryview(table.table)).hexdigest()[:16]
out["load_avg"] = os.getloadavg()[0]
out["robotlib"] = os.path.dirname(os.path.dirname(sys.modules["robotlib"].__file__))
print(json.dumps(out))
"""

HERE = Path(__file__).resolve().parent.parent


def run_one(checkout: Path, world: str, cache: str) -> dict:
    env = {
        **os.environ,
        "PYTHONPATH": str(checkout),
        "NUMBA_CACHE_DIR": cache,
        "ROBOTLIB_TABLE_CACHE": "off",
    }
    done = subprocess.run(  # in the checkout: `-c` puts the working folder first
        [sys.executable, "-c", CHILD, world],
        env=env,
        cwd=checkout,
        capture_output=True,
        text=True,
    )
    if done.returncode != 0:
        raise SystemExit(done.stderr)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("old", type=Path, help="the other checkout")
    p.add_argument(
        "--map", default=str(HERE.parent / "shared/real-worlds/ariacoda_columbia.map")
    )
    p.add_argument("--rounds", type=int, default=2)
    args = p.parse_args()
    cpu = {"old": 0.0, "new": 0.0}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.rounds):
            for name, where in (("new", HERE), ("old", args.old)):
                got = run_one(where, args.map, os.path.join(tmp, name))
                cpu[name] += got["table"][1]
                print(  # noqa: T201
                    f"{name}: load {got['load'][1]:.2f} s, free space "
                    f"{got['free'][1]:.2f} s, table {got['table'][1]:.2f} s CPU "
                    f"({got['table'][0]:.2f} s wall), peak {got['peak_mb']:.0f} MB, "
                    f"table {got['digest']}, load average {got['load_avg']:.1f} "
                    f"({got['robotlib']})"
                )
    print(f"table CPU old/new x{cpu['old'] / cpu['new']:.2f}")  # noqa: T201
    return 0


if __name__ == "__main__":
    sys.exit(main())
