"""``robotlib bench graphslam``: pose-graph SLAM on a CARMEN laser log, scored.

``robotlib bench graphslam --log intel.clf.bz2 --relations intel.relations
[--scans N] [--json FILE]`` reads a CARMEN log (plain or ``.bz2``) with
`robotlib.logs.read_log`, runs `robotlib.mapping.graph_slam` on its laser
scans and odometry, and prints the relative-pose error of Kümmerle et al.
(2009) on the relations file for the raw odometry and for the graph: mean
and standard deviation of the absolute translational (m) and rotational
(degrees) errors, as in their Table 2 and in the published figures that the
benchmark's data note lists, with the CPU time taken. The Freiburg
benchmark's logs and relations are credited in that note (the Intel log:
Dirk Hähnel; the relations: Kümmerle, Steder, Dornhege, Ruhnke, Grisetti,
Stachniss and Kleiner).
"""

from __future__ import annotations

import argparse
import bz2
import json
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

__all__ = ["add_arguments", "run", "laser_log"]


def laser_log(path, scans: int | None = None):
    """Read a CARMEN log's laser polls: odometry, ranges, beam angles, times.

    Returns
    -------
    odometry : numpy.ndarray, shape (T, 3)
    ranges : numpy.ndarray, shape (T, B), m
    angles : numpy.ndarray, shape (B,), rad
    times : numpy.ndarray, shape (T,), s (the lines' timestamps)
    max_range : float, m
    """
    from ..logs import read_log

    path = Path(path)
    with tempfile.TemporaryDirectory() as tmp:
        if path.suffix == ".bz2":
            plain = Path(tmp) / path.stem
            with bz2.open(path, "rb") as src, open(plain, "wb") as dst:
                shutil.copyfileobj(src, dst)
            path = plain
        states = [s for s in read_log(path).states if "laser" in s.extra]
    if scans is not None:
        states = states[:scans]
    if not states:
        raise ValueError(f"{path}: no laser scans")
    ranges = np.array([s.extra["laser"] for s in states])
    lo, hi = states[0].extra["laser_angles"]
    angles = np.linspace(lo, hi, ranges.shape[1])
    odometry = np.array([s.pose for s in states])
    times = np.array([s.time for s in states])
    return odometry, ranges, angles, times, float(states[0].extra["laser_max_range"])


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``robotlib bench graphslam``."""
    parser.add_argument("--log", type=Path, required=True, help="CARMEN log")
    parser.add_argument("--relations", type=Path, required=True, help="relations")
    parser.add_argument("--scans", type=int, default=None, help="first N scans only")
    parser.add_argument("--json", type=Path, default=None, help="write results here")


def run(args: argparse.Namespace) -> int:
    """Run the benchmark; print the table (and write JSON); return 0."""
    from ..mapping import graph_slam, read_relations, relation_errors

    odo, ranges, angles, times, rmax = laser_log(args.log, args.scans)
    rel = read_relations(args.relations)
    rel = rel[(rel[:, 0] <= times[-1] + 1e-3) & (rel[:, 1] <= times[-1] + 1e-3)]
    t0 = time.process_time()
    res = graph_slam(odo, ranges, angles, rmax * 0.99)
    cpu = time.process_time() - t0
    rows = {
        "odometry": relation_errors(times, odo, rel).summary(),
        "graph SLAM": relation_errors(times, res.poses, rel).summary(),
    }
    print(f"{len(odo)} scans, {len(res.keyframes)} keyframes, {res.loops} loops, "  # noqa: T201
          f"{res.failed_matches} failed matches, {cpu:.1f} s CPU")  # fmt: skip
    print(f"{'':12s} {'relations':>9s} {'trans m':>16s} {'rot deg':>14s}")  # noqa: T201
    for name, r in rows.items():
        print(  # noqa: T201 - the bench's report
            f"{name:12s} {r['relations']:9d} "
            f"{r['trans_mean_m']:7.3f} +- {r['trans_std_m']:6.3f} "
            f"{r['rot_mean_deg']:6.2f} +- {r['rot_std_deg']:5.2f}"
        )
    if args.json is not None:
        out = {"table": rows, "cpu_s": cpu, "keyframes": len(res.keyframes),
               "loops": res.loops, "scans": len(odo)}  # fmt: skip
        args.json.write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")
    return 0
