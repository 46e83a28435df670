"""``robotlib bench mcl``: the MCL step beside a plain pipeline and a peer.

``robotlib bench mcl [--json FILE]`` times, in one run and on the same
particles, scan and cone table, one MCL step (predict, weigh, estimate,
systematic resampling every step) per particle count:

- ``robotlib``: `MCL` with the tempered beam model on the cone table (its
  fused kernel);
- ``exact``: the same filter casting every particle's cones instead
  (up to 10,000 particles);
- ``plain``: a plain numba pipeline of the same model written in
  ``bench/plain_mcl.py`` (one kernel per stage; found beside the package in
  a checkout, skipped with a message otherwise);
- ``rtb``: Robotics Toolbox for Python's ``ParticleFilter`` (its own
  landmark model; the optional ``bench`` extra, skipped when missing).

It prints milliseconds per step (median and fastest of the repetitions) and
the ratios robotlib / plain and rtb / robotlib; ``--json`` writes the rows.
It also measures the cone table's build for worlds (``--table-world``) and
the first step of filters in a fresh process (``--first-step``).

Limits (issue 25; measured, never asserted by a test): robotlib at most 2x
the plain pipeline at N=300 and at most 1.3x at N=100k and 1M; at least 3x
faster than the Robotics Toolbox at N=300; the first step of `MCL.best` in
a fresh process within 1 s with warm kernels.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

__all__ = ["add_arguments", "run", "bench_mcl", "bench_table", "bench_first_step"]


def _time(fns: dict, reps: int, min_seconds: float = 0.2) -> dict:
    """Time each of ``fns`` (name -> call), interleaved; return name -> (median, min).

    The calls take turns, so a change in the machine's load falls on all of
    them alike. Calls that take less than ``min_seconds / reps`` are repeated
    up to ``min_seconds`` in all (at most 2000 times), so that a fast step is
    timed warm, over many repetitions. Times in ms.
    """
    once = 0.0
    for fn in fns.values():
        t0 = time.perf_counter()
        fn()
        once = max(once, time.perf_counter() - t0)
    reps = max(reps, min(2000, int(min_seconds / max(once, 1e-9))))
    times = {name: [] for name in fns}
    for _ in range(reps):
        for name, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    return {
        name: (1000.0 * float(np.median(ts)), 1000.0 * float(np.min(ts)))
        for name, ts in times.items()
    }


def _plain_pipeline():
    """Import ``bench/plain_mcl.py`` from the checkout, or return None (no checkout)."""
    path = Path(__file__).resolve().parents[2] / "bench" / "plain_mcl.py"
    if not path.is_file():
        return None
    if "plain_mcl" in sys.modules:
        return sys.modules["plain_mcl"]
    spec = importlib.util.spec_from_file_location("plain_mcl", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["plain_mcl"] = module  # numba's cache finds the module again
    spec.loader.exec_module(module)
    return module


def bench_mcl(
    world_name: str = "corridor",
    counts=(300, 1000, 10_000, 100_000, 1_000_000),
    reps: int = 20,
) -> list[dict]:
    """Time one MCL step per path and particle count.

    Each timed step starts from the same particles spread uniformly over the
    world's free space (global localization: the slowest case for the
    table's cache), with one sonar scan from the start pose.

    Returns
    -------
    list of dict
        ``{"path", "n", "ms_per_step", "ms_min"}`` (median and fastest step).
    """
    from ..localization import (
        MCL,
        BeamParameters,
        BeamSensorModel,
        ThresholdResampling,
        expected_readings,
    )
    from ..localization.motion import DEFAULT_ALPHAS, noise_std, odometry_increment
    from ..world import load_world

    world = load_world(world_name)
    z = expected_readings(world, np.array([world.start]))[0]
    odo0 = np.array(world.start)
    odo1 = odo0 + [0.5, 0.0, 0.05]
    params = BeamParameters(exponent=0.2)
    plain = _plain_pipeline()
    rows = []
    for n in counts:
        start = world.sample_free_poses(n, 0)
        steps = {}
        for path in ("robotlib", "exact", "plain"):
            if (path == "exact" and n > 10_000) or (path == "plain" and plain is None):
                continue
            sensor = BeamSensorModel(world, fast=path != "exact", params=params)
            if path == "plain":
                t = sensor.table
                q = params
                increment = odometry_increment(odo0, odo1)
                std = noise_std(DEFAULT_ALPHAS, *increment)
                consts = (q.sigma_hit, q.lambda_short, q.z_max,
                          q.z_rand / 5.0, 5.0, q.exponent)  # fmt: skip
                pipe = plain.PlainMCL(
                    start, t.table, t.sonar.sensors, t.origin, 1 / t.resolution,
                    sensor._hit_norm, sensor._short_norm, consts,
                    np.random.default_rng(0),
                )  # fmt: skip

                def step(pipe=pipe, start=start, increment=increment, std=std):
                    pipe.p[:] = start
                    pipe.step(increment, std, z)

            else:
                every = ThresholdResampling("systematic", 1.0)
                mcl = MCL(world, sensor, resampling=every, n=n, rng=0, check=False)

                def step(mcl=mcl, start=start):
                    mcl.set_particles(start)
                    mcl.step(odo0, odo1, z)

            steps[path] = step
        r = reps if n <= 100_000 else max(3, reps // 4)
        exact = {"exact": steps.pop("exact")} if "exact" in steps else {}
        timed = {**_time(steps, r), **(_time(exact, max(3, r // 3)) if exact else {})}
        for path, (ms, ms_min) in timed.items():  # robotlib and plain in turns
            rows.append({"path": path, "n": n, "ms_per_step": ms, "ms_min": ms_min})
    return rows


def bench_rtb(counts, reps: int = 10) -> list[dict] | str:
    """Time Robotics Toolbox for Python's particle filter step per particle count.

    Its standard set-up (a bicycle on a random path among 20 landmarks,
    range-bearing readings of one landmark a step): a simpler sensor model
    than eight sonar cones, the peer the issue compares with. Returns rows
    like `bench_mcl`'s (``path`` ``"rtb"``, ``model`` ``"landmark"``), or a
    message when the package is missing (``pip install robotlib[bench]``).
    """
    try:
        from roboticstoolbox import (
            Bicycle,
            LandmarkMap,
            ParticleFilter,
            RandomPath,
            RangeBearingSensor,
        )
    except ImportError:
        return "Robotics Toolbox not installed (pip install 'robotlib[bench]'): skipped"
    lmap = LandmarkMap(20, workspace=10, seed=0)
    robot = Bicycle(covar=np.diag([0.02, np.deg2rad(0.5)]) ** 2, workspace=lmap)
    robot.control = RandomPath(workspace=lmap, seed=0)
    sensor = RangeBearingSensor(
        robot, lmap, covar=np.diag([0.1, np.deg2rad(1)]) ** 2, plot=False, seed=0
    )
    rows = []
    for n in counts:
        pf = ParticleFilter(
            robot, sensor, np.diag([0.1, 0.1, np.deg2rad(1)]) ** 2,
            np.diag([0.1, 0.1]), nparticles=n, history=False, seed=0,
        )  # fmt: skip
        pf._init()
        ms, ms_min = _time({"rtb": pf._step}, reps)["rtb"]
        rows.append({"path": "rtb", "model": "landmark", "n": n, "ms_per_step": ms,
                     "ms_min": ms_min})  # fmt: skip
    return rows


def square_world(side: float = 20.0, room: float = 4.0, door: float = 1.0):
    """Build a ``side`` x ``side`` m world of ``room`` m rooms, ``door`` m doors.

    The size the table-build target is stated for (20 m x 20 m at 5 cm).
    """
    from ..world import World

    segs = [
        (0, 0, side, 0),
        (side, 0, side, side),
        (side, side, 0, side),
        (0, side, 0, 0),
    ]
    k = int(side // room)
    for a in range(1, k):
        for b in range(k):
            lo, hi = b * room, (b + 1) * room
            mid = (lo + hi) / 2
            for wall in (
                (a * room, lo, a * room, mid - door / 2),
                (a * room, mid + door / 2, a * room, hi),
            ):
                segs.append(wall)  # vertical walls with a door per room
                segs.append((wall[1], wall[0], wall[3], wall[2]))  # and horizontal
    return World(segs, bounds=(0.0, 0.0, side, side), start=(room / 2, room / 2, 0.0))


def bench_table(world_name: str) -> dict:
    """Build a fresh cone table for a world; return its time (s) and size (MB).

    ``world_name`` ``"square"`` is `square_world` (20 m x 20 m).
    """
    from ..localization import ConeTable
    from ..world import load_world

    world = square_world() if world_name == "square" else load_world(world_name)
    saved = os.environ.get("ROBOTLIB_TABLE_CACHE")
    os.environ["ROBOTLIB_TABLE_CACHE"] = "off"  # time the build, not a disk read
    try:
        t = ConeTable(world)
    finally:
        if saved is None:
            del os.environ["ROBOTLIB_TABLE_CACHE"]
        else:
            os.environ["ROBOTLIB_TABLE_CACHE"] = saved
    w, h = world.size
    return {
        "world": world_name,
        "size_m": [w, h],
        "segments": int(len(world.obstacles)),
        "cells": int(t.table.shape[0] * t.table.shape[1]),
        "build_s": t.build_seconds,
        "memory_mb": t.nbytes / 1e6,
    }


_FIRST_STEP = """
import json, sys, time
t0 = time.perf_counter()
import numpy as np
from robotlib.localization import MCL, expected_readings
from robotlib.world import load_world
world = load_world(sys.argv[1])
t1 = time.perf_counter()
mcl = {"paper": lambda: MCL.paper(world, rng=0),
       "paper_fast": lambda: MCL.paper(world, fast=True, rng=0),
       "best": lambda: MCL.best(world, rng=0)}[sys.argv[2]]()
t2 = time.perf_counter()
z = expected_readings(world, np.array([world.start]))[0]
odo = np.array(world.start)
t3 = time.perf_counter()
mcl.step(odo, odo + [0.5, 0.0, 0.05], z)
t4 = time.perf_counter()
print(json.dumps({"import_s": t1 - t0, "build_s": t2 - t1, "first_step_s": t4 - t3,
                  "scan_s": t3 - t2, "total_s": t4 - t3 + t2 - t0}))
"""


def bench_first_step(world_name: str = "corridor", filters=("paper", "best")) -> list:
    """Time the first step of filters, each in a fresh process (cache warmed first).

    ``filters``: ``"paper"`` (exact path), ``"paper_fast"``, ``"best"``.

    Returns
    -------
    list of dict
        ``{"filter", "import_s", "build_s", "first_step_s", "scan_s",
        "total_s"}``, s: importing robotlib and loading the world, making the
        filter (the cone table included), its first step (numba loading its
        kernels from the cache), the bench's own scan for that step (exact
        cone casts: not the filter's), and the total of all but the scan.
        Python's bytecode cache is on for the runs (``PYTHONDONTWRITEBYTECODE``
        unset): the first run writes it, as an install does, else every run
        compiles robotlib's sources (about 0.1 s).
    """
    out = []
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    for name in filters:
        cmd = [sys.executable, "-c", _FIRST_STEP, world_name, name]
        for _ in range(2):  # the first run fills numba's cache if needed
            done = subprocess.run(
                cmd, capture_output=True, text=True, timeout=600, check=True, env=env
            )
        out.append({"filter": name, **json.loads(done.stdout.strip().splitlines()[-1])})
    return out


def _print_mcl(results: list[dict], peers: list[dict]) -> None:
    by = {(r["path"], r["n"]): r for r in results + peers}
    paths = ("robotlib", "exact", "plain", "rtb")
    print(f"{'n':>9s}" + "".join(f"{p + ' ms':>13s}" for p in paths)  # noqa: T201
          + f"{'robotlib/plain':>16s}{'rtb/robotlib':>14s}")  # fmt: skip
    for n in sorted({r["n"] for r in results}):
        ms = [by[(p, n)]["ms_per_step"] if (p, n) in by else math.nan for p in paths]
        cells = "".join(f"{m:13.3f}" for m in ms)
        print(f"{n:9d}{cells}{ms[0] / ms[2]:16.2f}{ms[3] / ms[0]:14.1f}")  # noqa: T201
    print("median ms per step; ratios of the medians")  # noqa: T201


def run(args: argparse.Namespace) -> int:
    """Run ``robotlib bench mcl``; return the exit status."""
    load = os.getloadavg()
    print(f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")  # noqa: T201
    results = bench_mcl(args.world, tuple(args.n), reps=args.reps)
    out = {"load": load, "results": results, "peers": []}
    if _plain_pipeline() is None:
        print("bench/plain_mcl.py not found (not a checkout): plain skipped")  # noqa: T201
    if args.peers:
        counts = tuple(n for n in args.n if n <= 100_000)
        rtb = bench_rtb(counts, max(3, args.reps // 2))
        if isinstance(rtb, str):
            print(rtb)  # noqa: T201
        else:
            out["peers"] = rtb
    _print_mcl(results, out["peers"])
    if args.table_world:
        out["table"] = [bench_table(name) for name in args.table_world.split(",")]
        for t in out["table"]:
            print(  # noqa: T201
                "cone table {world} ({size_m[0]:g} m x {size_m[1]:g} m, {segments} "
                "walls): {cells} cells, {build_s:.2f} s, {memory_mb:.1f} MB".format(**t)
            )
    if args.first_step:
        out["first_step"] = bench_first_step(args.world)
        for f in out["first_step"]:
            print(  # noqa: T201
                "fresh process, {filter}: {total_s:.2f} s to the end of the first "
                "step (import {import_s:.2f} s, filter {build_s:.2f} s, step "
                "{first_step_s:.2f} s; the bench's scan {scan_s:.2f} s "
                "apart)".format(**f)
            )
    if args.json is not None:
        Path(args.json).write_text(json.dumps(out, indent=2))
    return 0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``robotlib bench mcl``."""
    parser.add_argument("--json", type=Path, default=None, help="write results here")
    parser.add_argument("--world", default="corridor", help="world for the MCL step")
    parser.add_argument(
        "--n", type=int, nargs="+", default=[300, 10_000, 100_000, 1_000_000]
    )
    parser.add_argument("--reps", type=int, default=20)
    parser.add_argument(
        "--peers",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="time Robotics Toolbox's particle filter too (if installed)",
    )
    parser.add_argument(
        "--first-step",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="time the first step in a fresh process",
    )
    parser.add_argument(
        "--table-world",
        default="office,square",
        help="worlds for the table build, comma-separated ('square': 20 m x 20 m;"
        " '' off)",
    )
