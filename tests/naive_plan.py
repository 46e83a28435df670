"""Plain Python references for the planning kernels (heapq, dicts, deque)."""

import heapq
import math
from collections import deque

import numpy as np

ORTHO = [(0, 1), (1, 0), (0, -1), (-1, 0)]
DIAG = [(1, 1), (1, -1), (-1, -1), (-1, 1)]


def neighbours(blocked, u, connectivity):
    ny, nx = blocked.shape
    i, j = u
    for di, dj in ORTHO + (DIAG if connectivity == 8 else []):
        a, b = i + di, j + dj
        if not (0 <= a < ny and 0 <= b < nx) or blocked[a, b]:
            continue
        if di and dj and (blocked[i, b] or blocked[a, j]):
            continue
        yield (a, b), math.hypot(di, dj)


def dijkstra_costs(blocked, cost, source, connectivity, res=1.0):
    """Every cell's optimal cost from ``source`` (dict), with heapq."""
    best = {source: 0.0}
    heap = [(0.0, source)]
    done = set()
    while heap:
        g, u = heapq.heappop(heap)
        if u in done:
            continue
        done.add(u)
        for v, step in neighbours(blocked, u, connectivity):
            gv = g + res * step * (1.0 + cost[v])
            if gv < best.get(v, math.inf):
                best[v] = gv
                heapq.heappush(heap, (gv, v))
    return best


def bfs_moves(blocked, source, connectivity):
    """Fewest moves from ``source`` to every reachable cell (dict)."""
    dist = {source: 0}
    q = deque([source])
    while q:
        u = q.popleft()
        for v, _ in neighbours(blocked, u, connectivity):
            if v not in dist:
                dist[v] = dist[u] + 1
                q.append(v)
    return dist


def inflate(occupied, r_cells):
    occ = np.asarray(occupied, bool)
    ny, nx = occ.shape
    ii, jj = np.mgrid[0:ny, 0:nx]
    out = np.zeros_like(occ)
    for i, j in zip(*np.nonzero(occ), strict=True):
        out |= (ii - i) ** 2 + (jj - j) ** 2 <= r_cells**2
    return out


def segment_distance(a, b, c, d, samples=400):
    """Distance between two segments by dense sampling of the first (upper bound
    within the sampling step) and exact point-segment distances."""

    def ps(p, u, v):
        u, v, p = map(np.asarray, (u, v, p))
        e = v - u
        ee = float(np.dot(e, e))
        t = 0.0 if ee < 1e-300 else np.clip(np.dot(p - u, e) / ee, 0, 1)
        return float(np.hypot(*(u + t * e - p)))

    ts = np.linspace(0, 1, samples)
    a, b = np.asarray(a, float), np.asarray(b, float)
    return min(ps(a + t * (b - a), c, d) for t in ts)


def astar_order(blocked, cost, start, goal, connectivity, res=1.0, weight=1.0):
    """A* with heapq and a dict, keyed as the kernel documents its heap.

    Nodes are expanded in the order of ``(f, float32(h), i * nx + j)`` with
    ``f = g + h`` and ``h`` the weighted octile (8) or Manhattan (4)
    heuristic; a cheaper path to an open node pushes a second entry (the
    stale one is skipped when popped), which expands the same nodes in the
    same order as a heap with decrease-key. Returns ``(order, path, cost)``:
    the expanded cells, the path's cells (start to goal) and its cost
    (``None, inf`` when unreachable).
    """
    ny, nx = blocked.shape
    gi, gj = goal
    r2 = math.sqrt(2.0)

    def h(cell):
        if weight == 0:
            return 0.0
        a, b = abs(cell[0] - gi), abs(cell[1] - gj)
        if connectivity == 8:
            lo = min(a, b)
            return weight * (res * ((a + b - 2 * lo) + r2 * lo))
        return weight * (res * (a + b))

    def key(g, cell):
        hv = h(cell)
        return (g + hv, float(np.float32(hv)), cell[0] * nx + cell[1])

    best = {start: 0.0}
    parent = {start: None}
    heap = [(key(0.0, start), start)]
    done = set()
    order = []
    while heap:
        _, u = heapq.heappop(heap)
        if u in done:
            continue
        done.add(u)
        order.append(u)
        if u == goal:
            path = [u]
            while parent[path[-1]] is not None:
                path.append(parent[path[-1]])
            return order, path[::-1], best[u]
        for v, length in neighbours(blocked, u, connectivity):
            if v in done:
                continue
            step = res if length == 1.0 else res * r2
            gv = best[u] + step * (1.0 + cost[v])
            if gv < best.get(v, math.inf):
                best[v] = gv
                parent[v] = u
                heapq.heappush(heap, (key(gv, v), v))
    return order, None, math.inf
