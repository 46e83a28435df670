"""Sampling planners in the continuous world: RRT, RRT* and path shortcutting.

They plan for a disc of a given radius against the world's obstacle
segments (`World.obstacles`) inside its bounds; an edge is valid when the
disc swept along it touches nothing. Every function takes ``rng`` (a
``Generator``, a seed or None): the same seed gives the same tree.

Imports the world layer and the planning kernels only; never plots.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._random import as_rng
from ..p3dx import ROBOT_RADIUS
from ..world import World
from . import _kernels
from .grid import path_length

__all__ = ["Tree", "rrt", "rrt_star", "shortcut", "edge_free", "path_free"]


@dataclass(frozen=True)
class Tree:
    """A sampling planner's answer.

    Attributes
    ----------
    path : numpy.ndarray, shape (K, 2)
        Start to goal, m ((0, 2) if none was found).
    cost : float
        Path length, m (``inf`` if none).
    found : bool
        A path was found.
    nodes : numpy.ndarray, shape (T, 2)
        The tree's vertices, m (``nodes[0]`` is the start).
    parents : numpy.ndarray of int64, shape (T,)
        Each vertex's parent (-1 for the start).
    iterations : int
        Samples drawn.
    """

    path: np.ndarray
    cost: float
    found: bool
    nodes: np.ndarray
    parents: np.ndarray
    iterations: int

    @property
    def expanded(self) -> int:
        """Vertices in the tree."""
        return len(self.nodes)


def edge_free(world: World, a, b, radius: float = ROBOT_RADIUS) -> bool:
    """Test a straight move from ``a`` to ``b`` (m) of a disc of ``radius``.

    True when it stays inside the bounds and touches no obstacle.
    """
    xmin, ymin, xmax, ymax = world.bounds
    return bool(
        _kernels.segment_clear(
            float(a[0]), float(a[1]), float(b[0]), float(b[1]),
            world.obstacles, float(radius), xmin, ymin, xmax, ymax,
        )
    )  # fmt: skip


def path_free(world: World, path, radius: float = ROBOT_RADIUS) -> bool:
    """Test whether every leg of ``path`` (K, 2) is `edge_free`."""
    p = np.asarray(path, dtype=float)
    return all(edge_free(world, p[k], p[k + 1], radius) for k in range(len(p) - 1))


def _check_ends(world, start, goal, radius):
    s = np.asarray(start, dtype=float)[:2]
    g = np.asarray(goal, dtype=float)[:2]
    for what, p in (("start", s), ("goal", g)):
        if not edge_free(world, p, p, radius):
            raise ValueError(
                f"{what} {tuple(float(v) for v in p)} is not free for a robot of "
                f"radius {radius} m in world {world.name!r}"
            )
    return s, g


def _grow(
    world, start, goal, radius, step, goal_bias, max_iter, rng, star, gamma, goal_tol
):
    rng = as_rng(rng)
    s, g = _check_ends(world, start, goal, radius)
    xmin, ymin, xmax, ymax = world.bounds
    nodes = np.empty((max_iter + 2, 2))
    parents = np.full(max_iter + 2, -1, dtype=np.int64)
    costs = np.zeros(max_iter + 2)
    nodes[0] = s
    t = 1
    goal_node = -1
    it = 0
    lo = np.array([xmin + radius, ymin + radius])
    span = np.array([xmax - xmin - 2 * radius, ymax - ymin - 2 * radius])
    for it in range(1, max_iter + 1):  # noqa: B007 (it is reported)
        u = rng.random(3)
        q = g if u[0] < goal_bias else lo + u[1:] * span
        d2 = ((nodes[:t] - q) ** 2).sum(axis=1)
        near = int(np.argmin(d2))
        dist = math.sqrt(d2[near])
        if dist < 1e-9:
            continue
        new = q if dist <= step else nodes[near] + (q - nodes[near]) * (step / dist)
        if not edge_free(world, nodes[near], new, radius):
            continue
        parent = near
        best = costs[near] + math.hypot(*(new - nodes[near]))
        neighbours = np.zeros(0, dtype=np.int64)
        if star:
            r = min(step * 2.0, gamma * math.sqrt(math.log(t + 1) / (t + 1)))
            dn = np.hypot(*(nodes[:t] - new).T)
            neighbours = np.flatnonzero(dn <= max(r, step))
            for k in neighbours:
                c = costs[k] + dn[k]
                if c < best and k != near and edge_free(world, nodes[k], new, radius):
                    parent, best = int(k), c
        nodes[t] = new
        parents[t] = parent
        costs[t] = best
        if star:
            for k in neighbours:
                c = best + dn[k]
                if c < costs[k] and edge_free(world, new, nodes[k], radius):
                    delta = costs[k] - c
                    parents[k] = t
                    _lower(parents, costs, t + 1, int(k), delta)
        t += 1
        if math.hypot(*(new - g)) <= goal_tol and edge_free(world, new, g, radius):
            c = best + math.hypot(*(new - g))
            if goal_node < 0:
                nodes[t] = g
                parents[t] = t - 1
                costs[t] = c
                goal_node = t
                t += 1
                if not star:
                    break
            elif c < costs[goal_node]:
                parents[goal_node] = t - 1
                costs[goal_node] = c
    nodes, parents = nodes[:t].copy(), parents[:t].copy()
    if goal_node < 0:
        e = np.zeros((0, 2))
        return Tree(e, float("inf"), False, nodes, parents, it)
    chain = [goal_node]
    while parents[chain[-1]] >= 0:
        chain.append(int(parents[chain[-1]]))
    path = nodes[chain[::-1]]
    return Tree(path, path_length(path), True, nodes, parents, it)


def _lower(parents, costs, t, root, delta):
    """Lower the cost of ``root`` and its descendants by ``delta``."""
    costs[root] -= delta
    stack = [root]
    while stack:
        u = stack.pop()
        kids = np.flatnonzero(parents[:t] == u)
        costs[kids] -= delta
        stack.extend(int(k) for k in kids)


def rrt(
    world: World,
    start,
    goal,
    radius: float = ROBOT_RADIUS,
    step: float = 0.5,
    goal_bias: float = 0.1,
    max_iter: int = 5000,
    rng: np.random.Generator | int | None = None,
) -> Tree:
    """Rapidly-exploring random tree from ``start`` to ``goal``.

    Parameters
    ----------
    world : World
        The obstacles and bounds.
    start, goal : array_like, shape (2,) or (3,)
        Positions, m (headings ignored).
    radius : float
        Robot radius, m.
    step : float
        Longest edge, m; the goal is joined from within this distance.
    goal_bias : float
        Probability of sampling the goal itself.
    max_iter : int
        Samples drawn at most.
    rng : numpy.random.Generator, int or None
        Randomness.

    Returns
    -------
    Tree
        Stops at the first path found.

    Raises
    ------
    ValueError
        If the start or the goal is not free.
    """
    return _grow(world, start, goal, radius, step, goal_bias, max_iter, rng,
                 False, 0.0, step)  # fmt: skip


def rrt_star(
    world: World,
    start,
    goal,
    radius: float = ROBOT_RADIUS,
    step: float = 0.5,
    goal_bias: float = 0.05,
    max_iter: int = 3000,
    gamma: float | None = None,
    rng: np.random.Generator | int | None = None,
) -> Tree:
    """Plan with RRT*, RRT that rewires.

    Each new vertex takes the cheapest parent near it, and the neighbours
    are rewired through it. Runs all ``max_iter`` samples and returns the
    best path found. ``gamma`` scales the neighbour radius (default from
    the area). See `rrt` for the other arguments.
    """
    if gamma is None:
        w, h = world.size
        gamma = 2.0 * math.sqrt(1.5 * w * h / math.pi)
    return _grow(world, start, goal, radius, step, goal_bias, max_iter, rng,
                 True, gamma, step)  # fmt: skip


def shortcut(
    world: World,
    path,
    radius: float = ROBOT_RADIUS,
    iterations: int = 200,
    rng: np.random.Generator | int | None = None,
) -> np.ndarray:
    """Shorten a path by straight cuts that stay free.

    First greedily: from each kept vertex, jump to the farthest later vertex
    in reach. Then ``iterations`` times: pick two random points on the path
    (seeded) and join them straight if that leg is free.

    Parameters
    ----------
    world : World
        The obstacles.
    path : array_like, shape (K, 2)
        A free path, m.
    radius : float
        Robot radius, m.
    iterations : int
        Random cuts tried.
    rng : numpy.random.Generator, int or None
        Randomness.

    Returns
    -------
    numpy.ndarray, shape (K', 2)
        A path no longer than ``path``, with the same ends.
    """
    rng = as_rng(rng)
    p = np.asarray(path, dtype=float)[:, :2]
    if len(p) < 3:
        return p.copy()
    keep = [p[0]]
    k = 0
    while k < len(p) - 1:
        far = k + 1
        for m in range(len(p) - 1, k + 1, -1):
            if edge_free(world, p[k], p[m], radius):
                far = m
                break
        keep.append(p[far])
        k = far
    p = np.array(keep)
    for _ in range(iterations):
        if len(p) < 3:
            break
        seg = np.hypot(*np.diff(p, axis=0).T)
        cum = np.concatenate([[0.0], np.cumsum(seg)])
        a, b = np.sort(rng.random(2) * cum[-1])
        ia = min(int(np.searchsorted(cum, a, side="right")) - 1, len(seg) - 1)
        ib = min(int(np.searchsorted(cum, b, side="right")) - 1, len(seg) - 1)
        if ib <= ia:
            continue
        pa = p[ia] + (p[ia + 1] - p[ia]) * ((a - cum[ia]) / max(seg[ia], 1e-12))
        pb = p[ib] + (p[ib + 1] - p[ib]) * ((b - cum[ib]) / max(seg[ib], 1e-12))
        if edge_free(world, pa, pb, radius):
            p = np.vstack([p[: ia + 1], pa, pb, p[ib + 1 :]])
            # drop vertices that repeat
            keepm = np.concatenate([[True], np.hypot(*np.diff(p, axis=0).T) > 1e-9])
            p = p[keepm]
    return p
