"""``robotlib bench buildings``: MCL set-up time and memory on generated buildings.

``robotlib bench buildings [--sides 50 100 200] [--timeout 120] [--json FILE]``
generates square buildings of 4 m rooms with a 1 m door in every wall
(`robotlib.experiments.bench_mcl.square_world`), and for each side, in a
fresh process, times what `MCL.best` needs before its first step: the
admissible free space (`World.free_space`), the cone table (`ConeTable`) and
the filter itself (its 50,000 particles drawn), then the exact path's wall
blocks; it reports each part's seconds, the process's peak resident memory
(MB) when the fast filter is ready (before the wall blocks, which it does
not use) and at the end, and any error (a table too large for
`MAX_TABLE_BYTES` says so; then the exact path, ``MCL.best(fast=False)``,
which the error suggests, is set up and timed instead). A size that takes
longer than ``--timeout`` seconds is reported as such.

Targets (issue 16, measured and reported, not asserted): 50 m x 50 m at 5 cm
ready in at most 3 s and 300 MB, 200 m x 200 m in at most 30 s and 1.5 GB,
a clear error beyond.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

__all__ = ["add_arguments", "run", "bench_building"]

_CHILD = """
import json, resource, sys, time
t0 = time.perf_counter()
import numpy as np
from robotlib.experiments.bench_mcl import square_world
from robotlib.localization import MCL, cone_table
from robotlib.localization.cones import _wall_blocks
from robotlib.sensing import SonarModel
side = float(sys.argv[1])
out = {"side_m": side}
cpu = [time.process_time()]
def mark(name, t):
    out[name + "_s"] = time.perf_counter() - t
    out[name + "_cpu"] = time.process_time() - cpu[0]  # processor time, s
    cpu[0] = time.process_time()
    out["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(json.dumps(out), flush=True)
t = time.perf_counter()
world = square_world(side)
out["walls"] = int(len(world.obstacles))
mark("import_world", t0)
t = time.perf_counter()
world.free_space(0.05, 0.2)
mark("free_space", t)
t = time.perf_counter()
try:
    table = cone_table(world)
    out["table_mb"] = table.nbytes / 1e6
    mark("cone_table", t)
    t = time.perf_counter()
    MCL.best(world, rng=0)
    mark("mcl_best", t)
    out["fast_peak_mb"] = out["peak_mb"]  # all the fast filter needs
except MemoryError as e:
    out["error"] = str(e)
    mark("cone_table", t)
t = time.perf_counter()  # the exact path's walls per block and heading sector
_wall_blocks(world, 5.0, SonarModel().cone)
mark("wall_blocks", t)
if "error" in out:  # what the error says to do: the exact path
    t = time.perf_counter()
    MCL.best(world, fast=False, rng=0)
    mark("mcl_best_exact", t)
"""


def bench_building(side: float, timeout: float = 120.0) -> dict:
    """Set MCL up on a ``side`` m square building in a fresh process.

    Returns
    -------
    dict
        ``side_m``, ``walls``, seconds per part (``wall_blocks_s``,
        ``free_space_s``, ``cone_table_s``, ``mcl_best_s``), ``table_mb``,
        ``peak_mb``, and ``error`` or ``timeout`` when it did not finish.
    """
    cmd = [sys.executable, "-c", _CHILD, repr(float(side))]
    env = {**os.environ, "ROBOTLIB_TABLE_CACHE": "off"}  # time the build itself
    try:
        done = subprocess.run(
            cmd, capture_output=True, text=True, timeout=timeout, env=env
        )
        lines = done.stdout.strip().splitlines()
        out = json.loads(lines[-1]) if lines else {"side_m": side}
        if done.returncode != 0:
            out["error"] = (done.stderr.strip().splitlines() or ["failed"])[-1]
    except subprocess.TimeoutExpired as e:
        text = e.stdout.decode() if isinstance(e.stdout, bytes) else (e.stdout or "")
        lines = text.strip().splitlines()
        out = json.loads(lines[-1]) if lines else {"side_m": side}
        out["timeout"] = timeout
    return out


def _print(r: dict) -> None:
    parts = [
        f"{k[:-2]} {r[k]:.2f} s" for k in
        ("free_space_s", "cone_table_s", "mcl_best_s", "wall_blocks_s",
         "mcl_best_exact_s") if k in r
    ]  # fmt: skip
    fast = ("free_space_s", "cone_table_s", "mcl_best_s")
    if "error" in r:  # the exact path instead
        fast = ("free_space_s", "wall_blocks_s", "mcl_best_exact_s")
    total = sum(r.get(k, 0.0) for k in fast)
    tail = ""
    if "timeout" in r:
        tail = f"; stopped after {r['timeout']:g} s"
    if "error" in r:
        tail += f"; {r['error']}"
    cpu = [
        f"{k[:-4]} {r[k]:.2f} s" for k in
        ("free_space_cpu", "cone_table_cpu", "mcl_best_cpu", "wall_blocks_cpu",
         "mcl_best_exact_cpu")
        if k in r
    ]  # fmt: skip
    print(  # noqa: T201
        f"{r['side_m']:g} m x {r['side_m']:g} m ({r.get('walls', '?')} walls): "
        f"{total:.2f} s set-up{' (exact path)' if 'error' in r else ''}, "
        f"peak {r.get('peak_mb', float('nan')):.0f} MB "
        f"(fast MCL ready at {r.get('fast_peak_mb', float('nan')):.0f} MB), "
        f"table {r.get('table_mb', float('nan')):.0f} MB ({', '.join(parts)}){tail}"
        f"\n  processor time: {', '.join(cpu)}"
    )


def run(args: argparse.Namespace) -> int:
    """Run ``robotlib bench buildings``; return the exit status."""
    results = []
    for side in args.sides:
        results.append(bench_building(side, args.timeout))
        _print(results[-1])
    if args.json is not None:
        Path(args.json).write_text(json.dumps({"buildings": results}, indent=2))
    return 0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``robotlib bench buildings``."""
    parser.add_argument("--sides", type=float, nargs="+", default=[50, 100, 200])
    parser.add_argument("--timeout", type=float, default=120.0, help="s per size")
    parser.add_argument("--json", type=Path, default=None, help="write results here")
