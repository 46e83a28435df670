"""``robotlib bench plan``: grid planners, RRT and pure pursuit, measured.

``robotlib bench plan [--json FILE] [--sizes 400 2000] [--seeds 20]`` prints:

- A* (8-connected, unit cells, no cost map) on square grids of random boxes,
  robotlib's numba kernel beside ``pyastar2d`` (a C++ A* from PyPI, the
  ``bench`` extra; skipped with a message when it is not installed) and a
  plain Python A* (``heapq``; on grids up to ``--python-max`` cells a side)
  on the same grid, start and goal, with ratios. pyastar2d's diagonal move
  costs as much as a straight one and may cut corners, so its path cost
  differs; the times compare the same search size.
- The wavefront (breadth-first flood) on the same grids.
- RRT with shortcutting over ``--seeds`` seeds in the office and the maze:
  success rate, and the shortcut path's length over the A* path's.
- Pure pursuit on an A* path in the office at 0.3 m/s: cross-track RMS.

Times are the fastest of ``--reps`` runs, in CPU seconds of this process.

Targets (measured, not asserted): A* at least as fast as pyastar2d on
400 x 400 and 2000 x 2000; the wavefront on 2000 x 2000 in at most 50 ms;
RRT at least 95 % success, shortcut length at most 1.2 x A*; cross-track
RMS at most 0.05 m.
"""

from __future__ import annotations

import argparse
import functools
import heapq
import json
import math
import time

import numpy as np

say = functools.partial(print)  # noqa: T201 (a bench prints)

__all__ = ["add_arguments", "run", "random_grid", "python_astar"]


def random_grid(n: int, seed: int = 0, density: float = 0.2):
    """Make a square grid with random boxes, free corners connected.

    Returns ``(blocked (n, n) bool, start (i, j), goal (i, j))``.
    """
    rng = np.random.default_rng(seed)
    blocked = np.zeros((n, n), dtype=bool)
    side = max(2, n // 40)
    while blocked.mean() < density:
        i, j = rng.integers(0, n - side, size=2)
        h, w = rng.integers(1, 2 * side, size=2)
        blocked[i : i + h, j : j + w] = True
    m = max(1, n // 50)
    blocked[:m, :m] = blocked[-m:, -m:] = False
    return blocked, (0, 0), (n - 1, n - 1)


def python_astar(blocked, start, goal):
    """Plain Python A* (heapq, octile, no corner cutting); returns the cost."""
    ny, nx = blocked.shape
    r2 = math.sqrt(2.0)
    moves = [(0, 1, 1.0), (1, 0, 1.0), (0, -1, 1.0), (-1, 0, 1.0)]
    moves += [(1, 1, r2), (1, -1, r2), (-1, -1, r2), (-1, 1, r2)]
    gi, gj = goal

    def h(i, j):
        a, b = abs(i - gi), abs(j - gj)
        return a + b + (r2 - 2) * min(a, b)

    g = {start: 0.0}
    heap = [(h(*start), 0.0, start)]
    closed = set()
    while heap:
        _, gu, u = heapq.heappop(heap)
        if u in closed:
            continue
        if u == goal:
            return gu
        closed.add(u)
        i, j = u
        for di, dj, c in moves:
            a, b = i + di, j + dj
            if not (0 <= a < ny and 0 <= b < nx) or blocked[a, b]:
                continue
            if di and dj and (blocked[i, b] or blocked[a, j]):
                continue
            gv = gu + c
            if gv < g.get((a, b), math.inf):
                g[(a, b)] = gv
                heapq.heappush(heap, (gv + h(a, b), gv, (a, b)))
    return math.inf


def _best(fn, reps: int):
    """Return the last result of ``fn()`` and its fastest CPU time, s.

    CPU time of this process (``time.process_time``): the peers run in it
    too (pyastar2d through ctypes), and on a shared machine wall time
    counts the waits for a core.
    """
    out, times = None, []
    for _ in range(reps):
        t = time.process_time()
        out = fn()
        times.append(time.process_time() - t)
    return out, min(times)


def bench_grids(sizes, python_max: int, reps: int) -> list[dict]:
    """Time A* (ours, pyastar2d, Python) and the wavefront per grid size."""
    from ..planning import CSpace, astar, wavefront

    try:
        import pyastar2d
    except ImportError:
        pyastar2d = None
        say("pyastar2d not installed (pip install robotlib[bench]): skipped")
    rows = []
    for n in sizes:
        blocked, s, g = random_grid(n)
        cs = CSpace.from_array(blocked)
        xy_s, xy_g = cs.to_metres(np.array(s)), cs.to_metres(np.array(g))
        astar(cs, xy_s, xy_g, use_cost=False)  # compile
        plan, t_ours = _best(
            lambda cs=cs, a=xy_s, b=xy_g: astar(cs, a, b, use_cost=False), reps
        )
        row = {"n": n, "found": plan.found, "cost": plan.cost}
        row.update({"expanded": plan.expanded, "astar_ms": 1e3 * t_ours})
        if pyastar2d is not None:
            weights = np.where(blocked, np.inf, 1.0).astype(np.float32)
            path, t_peer = _best(
                lambda w=weights, s=s, g=g: pyastar2d.astar_path(
                    w, s, g, allow_diagonal=True
                ),
                reps,
            )
            row["pyastar2d_ms"] = 1e3 * t_peer
            row["pyastar2d_steps"] = None if path is None else len(path) - 1
            row["ratio_pyastar2d"] = t_peer / t_ours
        if n <= python_max:
            cost, t_py = _best(lambda b=blocked, s=s, g=g: python_astar(b, s, g), 1)
            row["python_ms"] = 1e3 * t_py
            row["python_cost"] = cost
            row["ratio_python"] = t_py / t_ours
        wavefront(cs, xy_s, xy_g)
        wf, t_wf = _best(lambda cs=cs, a=xy_s, b=xy_g: wavefront(cs, a, b), reps)
        row["wavefront_ms"] = 1e3 * t_wf
        row["wavefront_expanded"] = wf.expanded
        rows.append(row)
        say(_grid_line(row))
    return rows


def _grid_line(r: dict) -> str:
    """Format one printed line per grid size."""
    line = (
        f"A* {r['n']}x{r['n']}: ours {r['astar_ms']:.1f} ms "
        f"(cost {r['cost']:.1f}, {r['expanded']} expanded)"
    )
    if "pyastar2d_ms" in r:
        line += f"; pyastar2d {r['pyastar2d_ms']:.1f} ms (x{r['ratio_pyastar2d']:.2f})"
    if "python_ms" in r:
        line += f"; Python {r['python_ms']:.0f} ms (x{r['ratio_python']:.1f})"
    else:
        line += "; Python reference skipped at this size (--python-max)"
    return line + f"; wavefront {r['wavefront_ms']:.1f} ms"


def bench_rrt(seeds: int) -> list[dict]:
    """RRT success and shortcut length over A*'s, office and maze."""
    from ..planning import astar, configuration_space, path_length, rrt, shortcut
    from ..planning.scenarios import GOALS
    from ..world import load_world

    rows = []
    for name in ("office", "maze"):
        world = load_world(name)
        cs = configuration_space(world, margin=0.0)
        goals = [g for gs in GOALS[name].values() for g in gs]
        ok, ratios, t0 = 0, [], time.perf_counter()
        for seed in range(seeds):
            goal = goals[seed % len(goals)]
            ref = astar(cs, world.start, goal, use_cost=False)
            tree = rrt(world, world.start, goal, rng=seed)
            if tree.found:
                ok += 1
                short = shortcut(world, tree.path, rng=seed)
                ratios.append(path_length(short) / path_length(ref.path))
        row = {
            "world": name,
            "seeds": seeds,
            "success": ok / seeds,
            "length_ratio_mean": float(np.mean(ratios)) if ratios else None,
            "length_ratio_max": float(np.max(ratios)) if ratios else None,
            "seconds": time.perf_counter() - t0,
        }
        rows.append(row)
        say(
            f"RRT {name}: {ok}/{seeds} found; shortcut / A* length mean "
            f"{row['length_ratio_mean']:.3f}, max {row['length_ratio_max']:.3f} "
            f"({row['seconds']:.1f} s)",
            flush=True,
        )
    return rows


def bench_pursuit(speed: float = 0.3) -> dict:
    """Cross-track RMS of pure pursuit on an A* path in the office."""
    from ..planning import PurePursuit, astar, configuration_space, cross_track
    from ..planning.navigate import TURN_MARGIN
    from ..sim import OdometryNoise, SimRobot, Simulator
    from ..world import load_world

    world = load_world("office")
    cs = configuration_space(world, margin=TURN_MARGIN)
    plan = astar(cs, world.start, (17.5, 12.0))
    r = SimRobot(Simulator(world, seed=0, odometry=OdometryNoise.none()))
    pp = PurePursuit(plan.path, lookahead=0.3, speed=speed)
    xy = []
    while not pp.done and len(xy) < 5000:
        v, w = pp.command(r.true_pose())
        r.setvel(v)
        r.setrotvel(w)
        r.readsonar()
        xy.append(r.true_pose()[:2])
    ct = cross_track(plan.path, np.array(xy))
    row = {
        "speed": speed,
        "rms": float(np.sqrt(np.mean(ct**2))),
        "max": float(ct.max()),
    }
    row["seconds_simulated"] = 0.1 * len(xy)
    say(
        f"pure pursuit at {speed} m/s: cross-track RMS {row['rms']:.3f} m, "
        f"max {row['max']:.3f} m over {row['seconds_simulated']:.0f} s",
        flush=True,
    )
    return row


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``robotlib bench plan``."""
    parser.description = "Time the grid planners; RRT and pure pursuit outcomes."
    parser.add_argument("--sizes", type=int, nargs="+", default=[400, 2000])
    parser.add_argument("--python-max", type=int, default=400)
    parser.add_argument("--reps", type=int, default=3)
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--json", metavar="FILE", help="write the results here")


def run(args: argparse.Namespace) -> int:
    """Run the planning benchmarks; return 0."""
    result = {
        "grids": bench_grids(args.sizes, args.python_max, args.reps),
        "rrt": bench_rrt(args.seeds),
        "pursuit": bench_pursuit(),
    }
    if args.json:
        with open(args.json, "w") as f:
            json.dump(result, f, indent=2)
    return 0
