"""``robotlib bench logs``: recorded runs' size and speed, against plain NumPy.

``robotlib bench logs [--polls N] [--json FILE]`` drives the simulator for
``N`` polls twice, plain and recorded to MCAP (`robotlib.logs.record`), and
prints the recording's overhead per poll, the file size (and per minute of
robot time), the same arrays saved with ``numpy.savez_compressed`` as the
reference, the time to read the run back (`robotlib.logs.read_log`) beside
``numpy.load``, and the replay's polls per second (`robotlib.logs.LogRobot`).
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

__all__ = ["add_arguments", "run", "bench_logs"]


def _drive(r, polls: int) -> None:
    r.setvel(0.2)
    r.setrotvel(0.1)
    for _ in range(polls):
        r.pose()
    r.stop()


def bench_logs(polls: int = 3000, folder: Path | None = None) -> dict:
    """Measure recording, reading and replaying ``polls`` polls; return the figures."""
    from ..logs import LogRobot, read_log, record
    from ..robot import robot

    folder = Path(folder or tempfile.mkdtemp(prefix="bench-logs-"))
    _drive(robot("sim:arena", seed=0), 20)  # compile
    t0 = time.perf_counter()
    _drive(robot("sim:arena", seed=0), polls)
    plain = time.perf_counter() - t0
    path = folder / "run.mcap"
    t0 = time.perf_counter()
    rec = record(robot("sim:arena", seed=0), path)
    _drive(rec, polls)
    rec.close()
    recorded = time.perf_counter() - t0
    t0 = time.perf_counter()
    run = read_log(path)
    read = time.perf_counter() - t0
    arrays = {"t": run.times, "odo": run.odometry, "sonar": run.sonar}
    arrays["truth"] = run.true_poses
    ref = folder / "run.npz"
    np.savez_compressed(ref, **arrays)
    t0 = time.perf_counter()
    with np.load(ref) as f:
        {k: f[k] for k in f.files}
    npz_read = time.perf_counter() - t0
    r = LogRobot(run)
    t0 = time.perf_counter()
    for _ in range(len(run)):
        r.readsonar()
    replay = time.perf_counter() - t0
    minutes = float(run.times[-1] - run.times[0]) / 60.0
    size = path.stat().st_size
    return {
        "polls": len(run),
        "record_overhead_ms_per_poll": 1000 * (recorded - plain) / polls,
        "sim_ms_per_poll": 1000 * plain / polls,
        "mcap_bytes": size,
        "mcap_kib_per_minute": size / 1024 / minutes,
        "npz_bytes": ref.stat().st_size,
        "read_polls_per_s": len(run) / read,
        "npz_read_polls_per_s": len(run) / npz_read,
        "replay_polls_per_s": len(run) / replay,
    }


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``robotlib bench logs``."""
    parser.add_argument("--polls", type=int, default=3000, help="polls to record")
    parser.add_argument("--json", type=Path, default=None, help="write the figures")


def run(args: argparse.Namespace) -> int:
    """Run the benchmark and print its figures; return the exit status."""
    r = bench_logs(args.polls)
    print(  # noqa: T201 - a benchmark prints
        f"{r['polls']} polls: the simulator {r['sim_ms_per_poll']:.3f} ms/poll, "
        f"recording adds {r['record_overhead_ms_per_poll']:.3f} ms/poll\n"
        f"MCAP {r['mcap_bytes'] / 1024:.0f} KiB ({r['mcap_kib_per_minute']:.0f} KiB "
        f"per robot minute); npz of the same arrays {r['npz_bytes'] / 1024:.0f} KiB "
        f"(x{r['mcap_bytes'] / r['npz_bytes']:.1f})\n"
        f"read {r['read_polls_per_s']:,.0f} polls/s "
        f"(npz {r['npz_read_polls_per_s']:,.0f}, "
        f"x{r['npz_read_polls_per_s'] / r['read_polls_per_s']:.0f} faster); "
        f"replay {r['replay_polls_per_s']:,.0f} polls/s"
    )
    if args.json:
        args.json.write_text(json.dumps(r, indent=1))
    return 0
