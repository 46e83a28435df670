"""``robotlib bench buildings``: MCL set-up time and memory on generated buildings.

``robotlib bench buildings [--sides 50 100 200] [--timeout 120] [--steps N ...]
[--json FILE]`` generates square buildings of 4 m rooms with a 1 m door in
every wall (`robotlib.experiments.bench_mcl.square_world`), and for each
side, in a fresh process, times what `MCL.best` needs before its first step:
the admissible free space (`World.free_space`), the cone table (`ConeTable`)
and the filter itself (its 50,000 particles drawn); it reports each part's
seconds, the process's peak resident memory (MiB, ``ru_maxrss / 1024``: the
unit issue 16's figures were taken in) when the filter is ready and at the
end, and any error (a table too large for `MAX_TABLE_BYTES` says so; then
the exact path, ``MCL.best(fast=False)``, which the error suggests, is set
up and timed instead). A size that takes longer than ``--timeout`` seconds
is reported as such. Then, in the same process, it times one step of the
path it set up with ``--steps`` particles (`MCL.best`'s beam model,
systematic resampling), and prints a verdict against the side's target
(`TARGETS`).

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

__all__ = ["add_arguments", "run", "bench_building", "verdict"]

_CHILD = """
import json, resource, sys, time
t0 = time.perf_counter()
import numpy as np
from robotlib.experiments.bench_mcl import square_world
from robotlib.localization import MCL, cone_table
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
if "error" in out:  # what the error says to do: the exact path
    t = time.perf_counter()
    MCL.best(world, fast=False, rng=0)
    mark("mcl_best_exact", t)
out["ready_peak_mb"] = out.get("fast_peak_mb", out["peak_mb"])
import gc
from numba.extending import is_jitted
out["compiled"] = sorted(  # not loaded from numba's cache: their compiling counted
    d.py_func.__qualname__ for d in gc.get_objects()
    if is_jitted(d) and d.stats.cache_misses
)
print(json.dumps(out), flush=True)
counts = json.loads(sys.argv[2])
if counts:  # one step of the path set up, as `robotlib bench mcl` times it
    from robotlib.experiments.bench_mcl import _time
    from robotlib.localization import (
        BEST, BeamParameters, BeamSensorModel, ThresholdResampling, expected_readings,
    )
    fast = "error" not in out
    z = expected_readings(world, np.array([world.start]))[0]
    odo0 = np.array(world.start)
    odo1 = odo0 + [0.5, 0.0, 0.05]
    sensor = BeamSensorModel(world, fast=fast, params=BeamParameters(**BEST["beam"]))
    out["steps"] = []
    for n in counts:
        start = world.sample_free_poses(n, 0)
        mcl = MCL(world, sensor, resampling=ThresholdResampling("systematic", 1.0),
                  n=n, rng=0, check=False)
        def step(mcl=mcl, start=start):
            mcl.set_particles(start)
            mcl.step(odo0, odo1, z)
        step()
        ms, ms_min = _time({"step": step}, 10)["step"]
        out["steps"].append({"path": "fast" if fast else "exact", "n": n,
                             "ms_per_step": ms, "ms_min": ms_min})
        print(json.dumps(out), flush=True)
"""


TARGETS = {50.0: (3.0, 300.0), 200.0: (30.0, 1500.0)}
"""Issue 16's targets by side (m): ready within (s), peak within (MB, 1e6
bytes: stricter than the MiB the peak is printed in)."""

STEP_COUNTS = (300, 1000, 10_000)
"""Particle counts of the steps timed after the set-up (``--steps``)."""


def bench_building(side: float, timeout: float = 120.0, steps=STEP_COUNTS) -> dict:
    """Set MCL up on a ``side`` m square building in a fresh process.

    Then time one step of the path it set up (the fast one, or the exact one
    when the table does not fit) with ``steps`` particles each: `MCL.best`'s
    tempered beam model, systematic resampling, the particles spread over
    the free space (as ``robotlib bench mcl`` times steps).

    Returns
    -------
    dict
        ``side_m``, ``walls``, seconds per part (``free_space_s``,
        ``cone_table_s``, ``mcl_best_s``, or ``mcl_best_exact_s``), ``table_mb``
        (1e6 bytes), ``peak_mb`` and ``ready_peak_mb`` (MiB: the peak at the
        end and when the filter was ready), ``steps`` (``path``, ``n``,
        ``ms_per_step`` median and ``ms_min`` fastest), ``compiled`` (the
        kernels numba compiled rather than loaded from its cache), and
        ``error`` or ``timeout`` when it did not finish.
    """
    cmd = [sys.executable, "-c", _CHILD, repr(float(side)), json.dumps(list(steps))]
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


def _exact(r: dict) -> bool:
    """Whether ``r`` set up the exact path (the fast table did not fit)."""
    return "mcl_best_exact_s" in r


def _ready_seconds(r: dict) -> float:
    """Seconds until the filter could step: the fast path's parts, or the exact's."""
    parts = ("free_space_s", "cone_table_s", "mcl_best_s")
    if _exact(r):
        parts = ("free_space_s", "mcl_best_exact_s")
    return sum(r.get(k, 0.0) for k in parts)


def verdict(r: dict) -> str | None:
    """Say whether ``r`` (from `bench_building`) meets its side's `TARGETS`.

    None for a side without a target.
    """
    if r["side_m"] not in TARGETS:
        return None
    seconds, mb = TARGETS[r["side_m"]]
    aim = f"ready in {seconds:g} s and {mb:g} MB"
    if "timeout" in r or "ready_peak_mb" not in r:
        return f"target {aim}: MISSED (the set-up did not finish)"
    ready, peak = _ready_seconds(r), r["ready_peak_mb"] * 2**20 / 1e6
    path = "the exact path (the fast table does not fit)" if _exact(r) else (
        "the fast path")  # fmt: skip
    met = ready <= seconds and peak <= mb
    return (
        f"target {aim}: {'met' if met else 'MISSED'} with {path}: ready in "
        f"{ready:.2f} s at {peak:.0f} MB ({r['ready_peak_mb']:.0f} MiB)"
    )


def _print(r: dict) -> None:
    parts = [
        f"{k[:-2]} {r[k]:.2f} s" for k in
        ("free_space_s", "cone_table_s", "mcl_best_s", "mcl_best_exact_s")
        if k in r
    ]  # fmt: skip
    tail = ""
    if "timeout" in r:
        tail = f"; stopped after {r['timeout']:g} s"
    if "error" in r:
        tail += f"; {r['error']}"
    cpu = [
        f"{k[:-4]} {r[k]:.2f} s" for k in
        ("free_space_cpu", "cone_table_cpu", "mcl_best_cpu", "mcl_best_exact_cpu")
        if k in r
    ]  # fmt: skip
    steps = [
        f"N={s['n']:,} {s['ms_per_step']:.3g} ms ({s['ms_min']:.3g})"
        for s in r.get("steps", ())
    ]
    lines = [
        f"{r['side_m']:g} m x {r['side_m']:g} m ({r.get('walls', '?')} walls): "
        f"{_ready_seconds(r):.2f} s set-up{' (exact path)' if _exact(r) else ''}, "
        f"peak {r.get('peak_mb', float('nan')):.0f} MiB "
        f"(MCL ready at {r.get('ready_peak_mb', float('nan')):.0f} MiB), "
        f"table {r.get('table_mb', float('nan')):.0f} MB ({', '.join(parts)}){tail}",
        f"  processor time: {', '.join(cpu)}",
    ]
    if steps:
        path = r["steps"][0]["path"]
        lines.append(f"  {path} step, median (fastest): {', '.join(steps)}")
    if r.get("compiled"):
        lines.append(
            f"  {len(r['compiled'])} kernels compiled in this run (not in numba's "
            "cache): its time and peak include compiling; run again for warm figures"
        )
    if verdict(r) is not None:
        lines.append(f"  {verdict(r)}")
    print("\n".join(lines))  # noqa: T201


def run(args: argparse.Namespace) -> int:
    """Run ``robotlib bench buildings``; return the exit status."""
    results = []
    for side in args.sides:
        results.append(bench_building(side, args.timeout, args.steps))
        _print(results[-1])
    if args.json is not None:
        Path(args.json).write_text(json.dumps({"buildings": results}, indent=2))
    return 0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``robotlib bench buildings``."""
    parser.add_argument("--sides", type=float, nargs="+", default=[50, 100, 200])
    parser.add_argument("--timeout", type=float, default=120.0, help="s per size")
    parser.add_argument("--json", type=Path, default=None, help="write results here")
    parser.add_argument(
        "--steps", type=int, nargs="*", default=list(STEP_COUNTS),
        help="particle counts of the timed steps (none: set-up only)",
    )  # fmt: skip
