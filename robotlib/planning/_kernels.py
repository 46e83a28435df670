"""Numba kernels for the planners: a binary heap, A*/Dijkstra, the wavefront.

Also the disc inflation of a grid and the segment clearance the sampling
planners use. Kernels take only contiguous arrays and scalars; the public
functions in `robotlib.planning` validate their input and call them. This
module imports nothing of robotlib's but the JIT options.

Grids are ``(ny, nx)``, row ``i`` is ``y`` and column ``j`` is ``x``; a
node is the flat index ``k = i * nx + j``. A move to a neighbour costs its
length (``res`` or ``res * sqrt(2)``) times ``1 + cost[target]``. A
diagonal move is allowed only when both cells beside it are free (no corner
cutting).
"""

import math

import numba as nb
import numpy as np

from .._config import JIT

SQRT2 = math.sqrt(2.0)

# Neighbour offsets: the four orthogonal ones first, then the diagonals.
DI = np.array([0, 1, 0, -1, 1, 1, -1, -1], dtype=np.int64)
DJ = np.array([1, 0, -1, 0, 1, -1, -1, 1], dtype=np.int64)


# -- binary heap on (key, tie) pairs, lexicographic, with node payloads ------
@nb.njit(**JIT)
def heap_grow(key, tie, val, size):
    """Return copies of the heap arrays with room for twice as many items."""
    cap = 2 * size + 16
    nk = np.empty(cap)
    nt = np.empty(cap)
    nv = np.empty(cap, dtype=np.int64)
    nk[:size] = key[:size]
    nt[:size] = tie[:size]
    nv[:size] = val[:size]
    return nk, nt, nv


@nb.njit(**JIT)
def heap_push(key, tie, val, size, k, t, v):
    """Push ``(k, t) -> v`` on a heap of ``size`` items (room for one more)."""
    c = size
    while c > 0:
        p = (c - 1) >> 1
        if k < key[p] or (k == key[p] and t < tie[p]):
            key[c] = key[p]
            tie[c] = tie[p]
            val[c] = val[p]
            c = p
        else:
            break
    key[c] = k
    tie[c] = t
    val[c] = v


@nb.njit(**JIT)
def heap_pop(key, tie, val, size):
    """Pop the smallest item of a heap of ``size`` items; return ``(k, v)``."""
    k0 = key[0]
    v0 = val[0]
    last = size - 1
    k = key[last]
    t = tie[last]
    v = val[last]
    c = 0
    while True:
        m = 2 * c + 1
        if m >= last:
            break
        r = m + 1
        if r < last and (key[r] < key[m] or (key[r] == key[m] and tie[r] < tie[m])):
            m = r
        if key[m] < k or (key[m] == k and tie[m] < t):
            key[c] = key[m]
            tie[c] = tie[m]
            val[c] = val[m]
            c = m
        else:
            break
    key[c] = k
    tie[c] = t
    val[c] = v
    return k0, v0


# -- heuristics ------------------------------------------------------------
@nb.njit(**JIT)
def octile(di, dj, res):
    """Octile distance of a ``(di, dj)`` cell offset, m (cell side ``res``)."""
    a = abs(di)
    b = abs(dj)
    lo = min(a, b)
    return res * ((a + b - 2 * lo) + SQRT2 * lo)


@nb.njit(**JIT)
def _heuristic(i, j, gi, gj, res, connect8):
    if connect8:
        return octile(i - gi, j - gj, res)
    return res * (abs(i - gi) + abs(j - gj))


@nb.njit(**JIT)
def astar(blocked, cost, start, goal, weight, connect8, res, g, parent, order):
    """Search with A* (weight > 0), weighted A* (weight > 1) or Dijkstra (0).

    Parameters
    ----------
    blocked : (ny, nx) bool
        Cells the robot may not enter.
    cost : (ny, nx) float64
        Extra cost factor of entering each cell (0: none).
    start, goal : int
        Flat node indices; ``goal < 0`` expands every reachable node
        (Dijkstra's full cost field).
    weight : float
        Heuristic weight (octile for 8-connected, Manhattan for 4).
    connect8 : bool
        Eight neighbours instead of four.
    res : float
        Cell side, m.
    g : (ny * nx,) float64
        Out: cost from the start (``inf`` where never reached).
    parent : (ny * nx,) int64
        Out: each reached node's predecessor (-1 for the start).
    order : (L,) int64
        Out: the first ``min(L, expanded)`` nodes in the order they were
        expanded (pass a zero-length array to record nothing).

    Returns
    -------
    (bool, int)
        Whether the goal was reached, and how many nodes were expanded.
    """
    ny, nx = blocked.shape
    n = ny * nx
    flat_b = blocked.ravel()
    flat_c = cost.ravel()
    closed = np.zeros(n, dtype=np.uint8)
    for k in range(n):
        g[k] = np.inf
        parent[k] = -1
    gi = goal // nx if goal >= 0 else 0
    gj = goal % nx if goal >= 0 else 0
    nnb = 8 if connect8 else 4
    cap = 1024
    key = np.empty(cap)
    tie = np.empty(cap)
    val = np.empty(cap, dtype=np.int64)
    size = 0
    g[start] = 0.0
    si = start // nx
    sj = start % nx
    h0 = weight * _heuristic(si, sj, gi, gj, res, connect8) if goal >= 0 else 0.0
    heap_push(key, tie, val, size, h0, h0, start)
    size += 1
    expanded = 0
    nrec = order.shape[0]
    while size > 0:
        _, u = heap_pop(key, tie, val, size)
        size -= 1
        if closed[u]:
            continue
        closed[u] = 1
        if expanded < nrec:
            order[expanded] = u
        expanded += 1
        if u == goal:
            return True, expanded
        ui = u // nx
        uj = u % nx
        gu = g[u]
        for d in range(nnb):
            vi = ui + DI[d]
            vj = uj + DJ[d]
            if vi < 0 or vi >= ny or vj < 0 or vj >= nx:
                continue
            v = vi * nx + vj
            if flat_b[v] or closed[v]:
                continue
            if d >= 4:
                if flat_b[ui * nx + vj] or flat_b[vi * nx + uj]:
                    continue
                step = res * SQRT2
            else:
                step = res
            gv = gu + step * (1.0 + flat_c[v])
            if gv < g[v]:
                g[v] = gv
                parent[v] = u
                h = 0.0
                if goal >= 0 and weight > 0.0:
                    h = weight * _heuristic(vi, vj, gi, gj, res, connect8)
                if size == key.shape[0]:
                    key, tie, val = heap_grow(key, tie, val, size)
                heap_push(key, tie, val, size, gv + h, h, v)
                size += 1
    return goal < 0, expanded


@nb.njit(**JIT)
def wavefront(blocked, goal, start, connect8, dist, order):
    """Breadth-first flood from ``goal`` (the wavefront / distance transform).

    Writes into ``dist`` (flat, int64) the number of moves from each cell to
    the goal (-1 where not reached) and the flood order into ``order`` (as
    in `astar`). Stops once ``start`` is dequeued (``start < 0``: floods
    everything reachable). Returns the number of cells dequeued.
    """
    ny, nx = blocked.shape
    n = ny * nx
    flat_b = blocked.ravel()
    for k in range(n):
        dist[k] = -1
    queue = np.empty(n, dtype=np.int64)
    head = 0
    tail = 0
    nnb = 8 if connect8 else 4
    dist[goal] = 0
    queue[tail] = goal
    tail += 1
    nrec = order.shape[0]
    while head < tail:
        u = queue[head]
        if head < nrec:
            order[head] = u
        head += 1
        if u == start:
            break
        ui = u // nx
        uj = u % nx
        du = dist[u] + 1
        for d in range(nnb):
            vi = ui + DI[d]
            vj = uj + DJ[d]
            if vi < 0 or vi >= ny or vj < 0 or vj >= nx:
                continue
            v = vi * nx + vj
            if flat_b[v] or dist[v] >= 0:
                continue
            if d >= 4 and (flat_b[ui * nx + vj] or flat_b[vi * nx + uj]):
                continue
            dist[v] = du
            queue[tail] = v
            tail += 1
    return head


@nb.njit(**JIT)
def descend(blocked, dist, start, connect8, out):
    """Follow the wavefront ``dist`` downhill from ``start`` to the goal.

    At each cell take the first neighbour (orthogonal before diagonal) one
    move nearer. Writes the nodes into ``out`` and returns their count
    (0 when ``start`` was not reached).
    """
    ny, nx = blocked.shape
    if dist[start] < 0:
        return 0
    nnb = 8 if connect8 else 4
    u = start
    m = 0
    out[m] = u
    m += 1
    while dist[u] > 0:
        ui = u // nx
        uj = u % nx
        want = dist[u] - 1
        nxt = -1
        for d in range(nnb):
            vi = ui + DI[d]
            vj = uj + DJ[d]
            if vi < 0 or vi >= ny or vj < 0 or vj >= nx:
                continue
            v = vi * nx + vj
            if dist[v] != want:
                continue
            if d >= 4 and (blocked[ui, vj] or blocked[vi, uj]):
                continue
            nxt = v
            break
        u = nxt
        out[m] = u
        m += 1
    return m


@nb.njit(**JIT)
def trace(parent, goal, out):
    """Write the nodes from the start to ``goal`` into ``out``; return the count."""
    m = 0
    u = goal
    while u >= 0:
        out[m] = u
        m += 1
        u = parent[u]
    for a in range(m // 2):
        out[a], out[m - 1 - a] = out[m - 1 - a], out[a]
    return m


@nb.njit(**JIT)
def inflate(occupied, r_cells, out):
    """Mark cells near occupied ones.

    ``out`` is True where a cell's centre lies within ``r_cells`` of an
    occupied cell's centre (distances in cells).
    """
    ny, nx = occupied.shape
    r = int(math.floor(r_cells))
    r2 = r_cells * r_cells
    for i in range(ny):
        for j in range(nx):
            out[i, j] = False
    for i in range(ny):
        for j in range(nx):
            if not occupied[i, j]:
                continue
            for a in range(max(0, i - r), min(ny, i + r + 1)):
                for b in range(max(0, j - r), min(nx, j + r + 1)):
                    if (a - i) * (a - i) + (b - j) * (b - j) <= r2:
                        out[a, b] = True


# -- continuous geometry for the sampling planners -------------------------
@nb.njit(**JIT)
def _point_segment(px, py, x1, y1, x2, y2):
    dx = x2 - x1
    dy = y2 - y1
    len2 = dx * dx + dy * dy
    t = 0.0
    if len2 > 0.0:
        t = ((px - x1) * dx + (py - y1) * dy) / len2
        t = min(1.0, max(0.0, t))
    ex = x1 + t * dx - px
    ey = y1 + t * dy - py
    return math.sqrt(ex * ex + ey * ey)


@nb.njit(**JIT)
def _cross(ax, ay, bx, by):
    return ax * by - ay * bx


@nb.njit(**JIT)
def segment_distance(ax, ay, bx, by, cx, cy, dx, dy):
    """Distance between segments ``a-b`` and ``c-d`` (0 when they cross)."""
    d1 = _cross(bx - ax, by - ay, cx - ax, cy - ay)
    d2 = _cross(bx - ax, by - ay, dx - ax, dy - ay)
    d3 = _cross(dx - cx, dy - cy, ax - cx, ay - cy)
    d4 = _cross(dx - cx, dy - cy, bx - cx, by - cy)
    if ((d1 > 0.0 and d2 < 0.0) or (d1 < 0.0 and d2 > 0.0)) and (
        (d3 > 0.0 and d4 < 0.0) or (d3 < 0.0 and d4 > 0.0)
    ):
        return 0.0
    best = _point_segment(ax, ay, cx, cy, dx, dy)
    best = min(best, _point_segment(bx, by, cx, cy, dx, dy))
    best = min(best, _point_segment(cx, cy, ax, ay, bx, by))
    best = min(best, _point_segment(dx, dy, ax, ay, bx, by))
    return best


@nb.njit(**JIT)
def segment_clear(ax, ay, bx, by, segments, radius, xmin, ymin, xmax, ymax):
    """Test a straight move of a disc of ``radius`` from ``a`` to ``b``.

    True when the swept disc touches no segment and stays in the bounds.
    """
    lo_x = xmin + radius
    lo_y = ymin + radius
    hi_x = xmax - radius
    hi_y = ymax - radius
    for px, py in ((ax, ay), (bx, by)):
        if px < lo_x or px > hi_x or py < lo_y or py > hi_y:
            return False
    for m in range(segments.shape[0]):
        s = segments[m]
        if segment_distance(ax, ay, bx, by, s[0], s[1], s[2], s[3]) <= radius:
            return False
    return True
