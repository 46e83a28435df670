"""Seeded test worlds of five kinds, and reachable start/goal pairs in them.

Benches that run on one hand-made map get tuned to it. `generate_world`
draws a fresh world of a named kind from a seed, so a controller, planner or
filter can be measured over many maps of a kind instead:

- ``"hall"``: a closed hall cluttered with boxes in jittered rows, the gaps
  between neighbouring boxes (and between rows) 0.8 to 1.0 m;
- ``"warehouse"``: a nearly periodic warehouse of 1 m deep racks in blocks,
  1.8 m aisles between them and 2 m cross aisles (the same places recur
  every aisle);
- ``"office"``: a 32 m office floor, a 2 m corridor between two rows of six
  rooms, each behind a 0.9 m door (the rooms are near mirror images);
- ``"ring"``: a ring corridor 2.5 to 3.5 m wide around a closed atrium, its
  walls long and blank but for a few pilasters;
- ``"traps"``: a hall of U-traps, V's and dead-end corridors, one per cell
  of a 4 m lattice, turned at random.

`reachable_pairs` draws start poses and goals in one connected piece of a
world's free space (the piece holding ``World.start``, at the robot's radius
plus a margin), a given clearance from the walls and a given distance apart.

Walls are segments, boxes four segments each, in metres; the worlds are
closed (no robot leaves them) and their start poses free. Imports the world
model only; never plots.
"""

from __future__ import annotations

import math

import numpy as np

from .._random import as_rng
from ..p3dx import ROBOT_RADIUS
from .geometry import wrap_angle
from .model import World

__all__ = ["KINDS", "PASSAGE", "generate_world", "reachable_pairs"]

KINDS = ("hall", "warehouse", "office", "ring", "traps")
"""The kinds of world `generate_world` draws."""

PASSAGE = 0.05
"""Margin beyond `ROBOT_RADIUS` at which `reachable_pairs` tests connectivity, m."""


def _box(x0: float, y0: float, x1: float, y1: float) -> list[tuple]:
    """Return the four sides of an axis-aligned rectangle, as segments."""
    return [(x0, y0, x1, y0), (x1, y0, x1, y1), (x1, y1, x0, y1), (x0, y1, x0, y0)]


def _hall(rng) -> tuple[list, tuple]:
    """Draw boxes in jittered rows; gaps 0.8-1.0 m between boxes and rows."""
    w, h = rng.uniform(14.0, 18.0), rng.uniform(10.0, 12.0)
    walls = _box(0.0, 0.0, w, h)
    y = 1.5
    while True:
        band = rng.uniform(0.3, 0.9)
        if y + band > h - 1.5:
            break
        x = 1.5 + rng.uniform(0.0, 0.8)
        while True:
            bw = rng.uniform(0.3, 0.9)
            if x + bw > w - 1.5:
                break
            bh = rng.uniform(0.3, band)
            by = y + rng.uniform(0.0, band - bh)
            if rng.random() > 0.2:  # a few boxes missing: wider openings
                walls += _box(x, by, x + bw, by + bh)
            x += bw + rng.uniform(0.8, 1.0)
        y += band + rng.uniform(0.8, 1.0)
    return walls, (0.7, h / 2, 0.0)


def _warehouse(rng) -> tuple[list, tuple]:
    """Draw three blocks of racks, 1.8 m aisles, 2 m cross aisles, small jitter."""
    n_rows = int(rng.integers(4, 6))
    depth, aisle, cross = 1.0, 1.8, 2.0
    h = 2.0 + n_rows * depth + (n_rows - 1) * aisle + 2.0
    rack = rng.uniform(5.0, 6.5)
    w = 2.0 + 3 * rack + 2 * cross + 2.0
    walls = _box(0.0, 0.0, w, h)
    for row in range(n_rows):
        y0 = 2.0 + row * (depth + aisle) + rng.uniform(-0.03, 0.03)
        for block in range(3):
            x0 = 2.0 + block * (rack + cross) + rng.uniform(-0.1, 0.1)
            x1 = x0 + rack + rng.uniform(-0.1, 0.1)
            walls += _box(x0, y0, x1, y0 + depth)
    return walls, (1.0, 1.0, 0.0)


def _office(rng) -> tuple[list, tuple]:
    """Draw twelve rooms on a 2 m corridor, each behind one 0.9 m door."""
    w, d, door = 32.0, rng.uniform(5.5, 6.5), 0.9
    h = 2 * d + 2.0
    walls = _box(0.0, 0.0, w, h)
    xs = np.linspace(0.0, w, 7)
    xs[1:-1] += rng.uniform(-0.3, 0.3, 5)
    for y_wall, y_far in ((d, 0.0), (d + 2.0, h)):
        for x in xs[1:-1]:  # partitions between rooms
            walls.append((x, y_wall, x, y_far))
        for x0, x1 in zip(xs[:-1], xs[1:], strict=True):
            dx = rng.uniform(x0 + 0.4, x1 - 0.4 - door)
            walls += [(x0, y_wall, dx, y_wall), (dx + door, y_wall, x1, y_wall)]
    return walls, (1.0, d + 1.0, 0.0)


def _ring(rng) -> tuple[list, tuple]:
    """Draw a ring corridor around a closed atrium; a few pilasters outside."""
    w, h = rng.uniform(24.0, 30.0), rng.uniform(18.0, 22.0)
    c = rng.uniform(2.5, 3.5)
    walls = _box(0.0, 0.0, w, h) + _box(c, c, w - c, h - c)
    for _ in range(int(rng.integers(2, 5))):  # pilasters 0.6 x 0.3 m on the outside
        side, t = int(rng.integers(4)), 0.3
        along = w if side % 2 == 0 else h
        s = rng.uniform(c + 1.0, along - c - 1.6)
        x0, y0 = [(s, 0.0), (w - t, s), (s, h - t), (0.0, s)][side]
        dx, dy = (0.6, t) if side % 2 == 0 else (t, 0.6)
        walls += _box(x0, y0, x0 + dx, y0 + dy)
    return walls, (c / 2, c / 2, 0.0)


def _turned(points, centre, angle) -> list[tuple]:
    """Return segments through ``points`` (local, m) turned about ``centre``."""
    c, s = math.cos(angle), math.sin(angle)
    xy = [(centre[0] + c * x - s * y, centre[1] + s * x + c * y) for x, y in points]
    return [(*a, *b) for a, b in zip(xy[:-1], xy[1:], strict=True)]


def _traps(rng) -> tuple[list, tuple]:
    """Draw U-traps, V's and dead ends, one per 4 m cell, turned at random."""
    nx, ny = int(rng.integers(3, 5)), int(rng.integers(2, 4))
    cell = 4.0
    w, h = 2.0 + nx * cell + 2.0, 2.0 + ny * cell + 2.0
    walls = _box(0.0, 0.0, w, h)
    for i in range(nx):
        for j in range(ny):
            centre = (2.0 + (i + 0.5) * cell, 2.0 + (j + 0.5) * cell)
            turn = rng.uniform(-math.pi, math.pi)
            kind = int(rng.integers(3))
            if kind == 0:  # U 1.2-2.0 m wide: open on local -x
                a, b = rng.uniform(0.8, 1.1), rng.uniform(0.6, 1.0)
                pts = [(-a, -b), (a, -b), (a, b), (-a, b)]
                walls += _turned(pts, centre, turn)
            elif kind == 1:  # V: apex at local +x
                arm, half = rng.uniform(1.2, 1.5), rng.uniform(0.35, 0.8)
                apex = (arm * math.cos(half) / 2, 0.0)
                pts = [
                    (apex[0] - arm * math.cos(half), -arm * math.sin(half)),
                    apex,
                    (apex[0] - arm * math.cos(half), arm * math.sin(half)),
                ]
                walls += _turned(pts, centre, turn)
            else:  # dead end: a corridor 1.0-1.2 m wide, closed at local +x
                length, half = rng.uniform(2.0, 2.6), rng.uniform(0.5, 0.6)
                pts = [(-length / 2, -half), (length / 2, -half)]
                pts += [(length / 2, half), (-length / 2, half)]
                walls += _turned(pts, centre, turn)
    return walls, (1.0, 1.0, 0.0)


_MAKERS = {
    "hall": _hall,
    "warehouse": _warehouse,
    "office": _office,
    "ring": _ring,
    "traps": _traps,
}


def generate_world(kind: str, rng: np.random.Generator | int | None = None) -> World:
    """Draw a closed test world of one of `KINDS`.

    Parameters
    ----------
    kind : str
        One of `KINDS` (see the module's docstring).
    rng : numpy.random.Generator, int or None
        Randomness; the same seed gives the same world.

    Returns
    -------
    World
        Named ``kind``, its start pose free for the robot, bounds the walls'
        box grown by 0.5 m.

    Raises
    ------
    ValueError
        If ``kind`` is not one of `KINDS`.
    """
    if kind not in _MAKERS:
        raise ValueError(f"unknown world kind {kind!r}; kinds: {', '.join(KINDS)}")
    walls, start = _MAKERS[kind](as_rng(rng))
    segments = np.round(np.array(walls, dtype=float), 3)  # whole millimetres
    return World(segments, start=start, name=kind)


def reachable_pairs(
    world: World,
    n: int,
    rng: np.random.Generator | int | None = None,
    clearance: float = 0.5,
    min_separation: float = 4.0,
    resolution: float = 0.05,
) -> np.ndarray:
    """Draw start poses and goals the robot can drive between.

    Both lie in the free space connected to ``world.start`` at the robot's
    radius plus `PASSAGE` (`World.free_space`), at least ``clearance`` from
    every wall and ``min_separation`` apart; the start heading points at the
    goal within +-45 degrees.

    Parameters
    ----------
    world : World
        The world.
    n : int
        Number of pairs.
    rng : numpy.random.Generator, int or None
        Randomness; the same seed gives the same pairs.
    clearance, min_separation, resolution : float
        Distance to the walls, between start and goal, and grid cell, m.

    Returns
    -------
    numpy.ndarray, shape (n, 5)
        Rows ``(x, y, theta, goal_x, goal_y)``, m and rad.

    Raises
    ------
    ValueError
        If the connected free space holds no two such points.
    """
    rng = as_rng(rng)
    if n < 0 or not clearance >= 0 or not min_separation >= 0:
        raise ValueError("need n >= 0, clearance >= 0 and min_separation >= 0")
    free = world.free_space(resolution, ROBOT_RADIUS + PASSAGE)
    field = world.distance_field(resolution)
    ok = free.data & (field.data >= clearance + resolution)
    cells = np.flatnonzero(ok)
    if len(cells) < 2:
        raise ValueError(f"world {world.name!r}: no free cells {clearance} m clear")
    centres = free.centres().reshape(-1, 2)[cells]
    span = np.ptp(centres, axis=0)
    if math.hypot(*span) < min_separation:
        raise ValueError(f"world {world.name!r}: nothing {min_separation} m apart")
    out = np.empty((int(n), 5))
    for k in range(int(n)):
        for _ in range(1000):
            s, g = centres[rng.integers(len(centres), size=2)]
            if math.hypot(*(g - s)) >= min_separation:
                break
        else:
            raise ValueError(f"world {world.name!r}: no pair {min_separation} m apart")
        heading = math.atan2(g[1] - s[1], g[0] - s[0])
        out[k] = (*s, wrap_angle(heading + rng.uniform(-math.pi / 4, math.pi / 4)), *g)
    return out
