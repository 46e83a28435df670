"""Numba kernels for the planners: an indexed heap, A*/Dijkstra, the wavefront.

Also the disc inflation of a grid and the segment clearance the sampling
planners use. Kernels take only contiguous arrays and scalars; the public
functions in `robotlib.planning` validate their input and call them. This
module imports nothing of robotlib's but the JIT options and the world's
point-to-segment distance.

Grids are ``(ny, nx)``, row ``i`` is ``y`` and column ``j`` is ``x``; a
node is the flat index ``k = i * nx + j``. A move to a neighbour costs its
length (``res`` or ``res * sqrt(2)``) times ``1 + cost[target]``. A
diagonal move is allowed only when both cells beside it are free (no corner
cutting). The searches run on a padded copy of the grid (below); nothing in
their inner loops allocates, calls a function that takes an array, or
rebinds an array (numba counts references on each of those).
"""

import math

import numba as nb
import numpy as np

from .._config import JIT
from ..world._kernels import point_segment_distance

SQRT2 = math.sqrt(2.0)

# Neighbour offsets: the four orthogonal ones first, then the diagonals.
DI = np.array([0, 1, 0, -1, 1, 1, -1, -1], dtype=np.int64)
DJ = np.array([1, 0, -1, 0, 1, -1, -1, 1], dtype=np.int64)
# the orthogonal neighbours beside each diagonal (diagonal d: DA[d-4], DB[d-4])
DA = np.array([0, 2, 2, 0], dtype=np.int64)
DB = np.array([1, 1, 3, 3], dtype=np.int64)


# -- the padded grid ---------------------------------------------------------
# The searches run on a copy of the grid with a one-cell blocked border, one
# byte a cell, so a neighbour is one load at a fixed flat offset (no bounds
# tests, no division). A node's padded index is ``p = (i + 1) * (nx + 2) +
# j + 1``; its plain index ``k = i * nx + j`` moves by the matching plain
# offset, so both are carried along without dividing.
BLOCKED = np.uint8(1)
CLOSED = np.uint8(2)  # expanded
SEEN = np.uint8(4)  # A*: ``g`` holds a cost (``inf`` otherwise)
MOVE_SHIFT = 3  # A*: bits 3-5 hold the move (index into DI, DJ) that reached a node


@nb.njit(**JIT)
def padded(blocked):
    """Return the grid as flat uint8 with a blocked border, (ny + 2) * (nx + 2)."""
    ny, nx = blocked.shape
    w = nx + 2
    state = np.empty((ny + 2) * w, dtype=np.uint8)
    for j in range(w):
        state[j] = BLOCKED
        state[(ny + 1) * w + j] = BLOCKED
    for i in range(ny):
        row = (i + 1) * w
        state[row] = BLOCKED
        state[row + nx + 1] = BLOCKED
        for j in range(nx):
            state[row + 1 + j] = BLOCKED if blocked[i, j] else np.uint8(0)
    return state


@nb.njit(**JIT)
def _offsets(nx):
    """Flat offsets of the eight neighbours (`DI`, `DJ` order): padded, plain."""
    offp = np.empty(8, dtype=np.int64)
    offk = np.empty(8, dtype=np.int64)
    for d in range(8):
        offp[d] = DI[d] * (nx + 2) + DJ[d]
        offk[d] = DI[d] * nx + DJ[d]
    return offp, offk


# -- indexed 4-ary heap of 128-bit integer keys ------------------------------
# A search node's key is ``(f, h, node)``: ``f = g + h``, then the heuristic
# rounded to float32, then the node's padded index. The key is two int64s:
# the bits of ``f`` (a float64 >= 0 orders as its bit pattern), and the
# float32 bits of ``h`` above the 32-bit node. The order is total, so the
# search expands the same nodes in the same order whatever the heap's shape
# (and as a plain heapq search on the same keys). Each node is in the heap at
# most once; ``pos[node]`` is its slot, and a cheaper path to an open node
# moves it up (decrease-key) instead of pushing a second copy. Four children
# a slot: 64 bytes, one cache line. The pop is written out in `astar`.
@nb.njit(**JIT)
def key_scratch():
    """Return the buffers `search_key` reinterprets bits in.

    ``(fa, fi, ha, hi)``: one float64 and its int64 view, one float32 and
    its int32 view (made once per search: a view made per key would cost an
    allocation and reference counting in the inner loop).
    """
    fa = np.empty(1)
    ha = np.empty(1, dtype=np.float32)
    return fa, fa.view(np.int64), ha, ha.view(np.int32)


@nb.njit(inline="always", **JIT)
def search_key(fa, fi, ha, hi, f, h, node):
    """Return the heap key ``(f bits, h float32 bits << 32 | node)`` of a node.

    ``fa, fi, ha, hi`` are the buffers of `key_scratch`.
    """
    fa[0] = f
    ha[0] = h
    return fi[0], (np.int64(hi[0]) << 32) | node


@nb.njit(inline="always", **JIT)
def heap_up(heap, pos, c, k0, k1):
    """Put key ``(k0, k1)`` in slot ``c`` (free, or its node's) and sift it up."""
    while c > 0:
        p = (c - 1) >> 2
        p0 = heap[2 * p]
        p1 = heap[2 * p + 1]
        if p0 < k0 or (p0 == k0 and p1 < k1):
            break
        heap[2 * c] = p0
        heap[2 * c + 1] = p1
        pos[p1 & 0xFFFFFFFF] = c
        c = p
    heap[2 * c] = k0
    heap[2 * c + 1] = k1
    pos[k1 & 0xFFFFFFFF] = c


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

    Expands nodes in the order of their `search_key` ``(f, h, node)`` with
    ``f = g + h`` (an indexed heap with decrease-key; see above).
    Neighbours are relaxed orthogonal first, then diagonal (the `DI`, `DJ`
    order); a diagonal move needs both cells beside it free.

    Parameters
    ----------
    blocked : (ny, nx) bool
        Cells the robot may not enter; (ny + 2) * (nx + 2) < 2**31.
    cost : (ny, nx) float64, or any array of size 0
        Extra cost factor of entering each cell (0: none; size 0: none
        anywhere, and the array is not read).
    start, goal : int
        Flat node indices; ``goal < 0`` expands every reachable node
        (Dijkstra's full cost field).
    weight : float
        Heuristic weight (octile for 8-connected, Manhattan for 4), >= 0.
    connect8 : bool
        Eight neighbours instead of four.
    res : float
        Cell side, m.
    g : (ny * nx,) float64
        Out: cost from the start of every node reached. With ``goal < 0``
        also ``inf`` at every other node; with a goal, other nodes are not
        written (a search toward a goal touches a small part of the grid).
    parent : (ny * nx,) int64
        Out: the predecessor of each node on the path found (-1 for the
        start); with ``goal < 0``, of every node reached, and -1 at the
        others. (The search keeps each node's last move in its byte of the
        padded grid and writes predecessors only at the end.)
    order : (L,) int64
        Out: the first ``min(L, expanded)`` nodes in the order they were
        expanded (pass a zero-length array to record nothing).

    Returns
    -------
    (bool, int)
        Whether the goal was reached, and how many nodes were expanded.
    """
    ny, nx = blocked.shape
    w = nx + 2
    use_cost = cost.size > 0
    flat_c = cost.ravel()
    state = padded(blocked)
    pos = np.empty(state.shape[0], dtype=np.int32)
    offp, offk = _offsets(nx)
    gi = goal // nx + 1 if goal >= 0 else 0
    gj = goal % nx + 1 if goal >= 0 else 0
    nnb = 8 if connect8 else 4
    heur = goal >= 0 and weight > 0.0
    step_d = res * SQRT2
    # room for every node (pages are touched only as the heap grows; a heap
    # rebound in the loop would cost reference counting on every use)
    heap = np.empty(2 * (ny * nx + 1), dtype=np.int64)
    si = start // nx + 1
    sj = start % nx + 1
    ps = si * w + sj
    g[start] = 0.0
    parent[start] = -1
    state[ps] |= SEEN
    h0 = weight * _heuristic(si, sj, gi, gj, res, connect8) if heur else 0.0
    fa, fi, ha, hi = key_scratch()
    k0, k1 = search_key(fa, fi, ha, hi, h0, h0, ps)
    heap_up(heap, pos, 0, k0, k1)
    size = 1
    expanded = 0
    nrec = order.shape[0]
    found = goal < 0
    while size > 0:
        # pop the first key (written out: a heap function inlined by numba
        # still costs two reference counts a call)
        p = heap[1] & 0xFFFFFFFF
        size -= 1
        k0 = heap[2 * size]
        k1 = heap[2 * size + 1]
        c = 0
        while True:
            m = 4 * c + 1
            if m >= size:
                break
            m0 = heap[2 * m]
            m1 = heap[2 * m + 1]
            for r in range(m + 1, min(m + 4, size)):
                r0 = heap[2 * r]
                r1 = heap[2 * r + 1]
                if r0 < m0 or (r0 == m0 and r1 < m1):
                    m = r
                    m0 = r0
                    m1 = r1
            if k0 < m0 or (k0 == m0 and k1 < m1):
                break
            heap[2 * c] = m0
            heap[2 * c + 1] = m1
            pos[m1 & 0xFFFFFFFF] = c
            c = m
        if size > 0:
            heap[2 * c] = k0
            heap[2 * c + 1] = k1
            pos[k1 & 0xFFFFFFFF] = c
        state[p] |= CLOSED
        ui = p // w
        uj = p - ui * w
        u = (ui - 1) * nx + (uj - 1)
        if expanded < nrec:
            order[expanded] = u
        expanded += 1
        if u == goal:
            found = True
            break
        gu = g[u]
        for d in range(nnb):
            q = p + offp[d]
            sv = state[q]
            if sv & (BLOCKED | CLOSED):
                continue
            if d < 4:
                step = res
            else:
                if (state[p + offp[DA[d - 4]]] | state[p + offp[DB[d - 4]]]) & BLOCKED:
                    continue
                step = step_d
            v = u + offk[d]
            gv = gu + step * (1.0 + flat_c[v]) if use_cost else gu + step * 1.0
            seen = (sv & SEEN) != 0
            if seen:
                if not gv < g[v]:
                    continue
            elif not gv < np.inf:
                continue
            g[v] = gv
            h = 0.0
            if heur:
                h = weight * _heuristic(ui + DI[d], uj + DJ[d], gi, gj, res, connect8)
            fa[0] = gv + h  # search_key, written out (no array passing)
            ha[0] = h
            k0 = fi[0]
            k1 = (np.int64(hi[0]) << 32) | q
            state[q] = SEEN | np.uint8(d << MOVE_SHIFT)
            if seen:
                heap_up(heap, pos, np.int64(pos[q]), k0, k1)
            else:
                heap_up(heap, pos, size, k0, k1)
                size += 1
    if goal < 0:
        for i in range(ny):
            row = (i + 1) * w + 1
            for j in range(nx):
                k = i * nx + j
                sv = state[row + j]
                if not sv & SEEN:
                    g[k] = np.inf
                    parent[k] = -1
                elif k != start:
                    parent[k] = k - offk[sv >> MOVE_SHIFT]
    elif found:
        k = goal
        p = (gi * w) + gj
        while p != ps:
            d = state[p] >> MOVE_SHIFT
            parent[k] = k - offk[d]
            k -= offk[d]
            p -= offp[d]
    return found, expanded


@nb.njit(**JIT)
def level_grid(blocked):
    """Return the wavefront's padded int32 grid: -2 blocked (and the border), -1 free.

    Flat, (ny + 2) * (nx + 2); see the padded layout above.
    """
    ny, nx = blocked.shape
    w = nx + 2
    lev = np.empty((ny + 2) * w, dtype=np.int32)
    for j in range(w):
        lev[j] = -2
        lev[(ny + 1) * w + j] = -2
    for i in range(ny):
        row = (i + 1) * w
        lev[row] = -2
        lev[row + nx + 1] = -2
        for j in range(nx):
            lev[row + 1 + j] = -2 if blocked[i, j] else -1
    return lev


@nb.njit(**JIT)
def flood(blocked, goal, start, connect8, order):
    """Breadth-first flood from ``goal`` (the wavefront / distance transform).

    Stops once ``start`` is dequeued (``start < 0``: floods everything
    reachable); writes the flood order into ``order`` (as in `astar`).

    Returns
    -------
    (int, numpy.ndarray)
        The number of cells dequeued, and the `level_grid` with each reached
        cell's number of moves to the goal (padded layout).

    The flood runs on `level_grid` (each cell's move count written when it
    is enqueued, so the grid is also the visited mark) with one flat int32
    FIFO of padded indices, allocated once; the neighbours are unrolled,
    orthogonal first.
    """
    ny, nx = blocked.shape
    n = ny * nx
    w = nx + 2
    lev = level_grid(blocked)
    offp, _ = _offsets(nx)
    o0, o1, o2, o3 = offp[0], offp[1], offp[2], offp[3]
    o4, o5, o6, o7 = offp[4], offp[5], offp[6], offp[7]
    queue = np.empty(n, dtype=np.int32)
    ps = (start // nx + 1) * w + start % nx + 1 if start >= 0 else -1
    pg = (goal // nx + 1) * w + goal % nx + 1
    lev[pg] = 0
    queue[0] = pg
    head = 0
    tail = 1
    nrec = order.shape[0]
    while head < tail:
        p = np.int64(queue[head])
        if head < nrec:
            i = p // w
            order[head] = (i - 1) * nx + (p - i * w - 1)
        head += 1
        if p == ps:
            break
        du = lev[p] + 1
        q = p + o0
        s0 = lev[q]
        if s0 == -1:
            lev[q] = du
            queue[tail] = q
            tail += 1
        q = p + o1
        s1 = lev[q]
        if s1 == -1:
            lev[q] = du
            queue[tail] = q
            tail += 1
        q = p + o2
        s2 = lev[q]
        if s2 == -1:
            lev[q] = du
            queue[tail] = q
            tail += 1
        q = p + o3
        s3 = lev[q]
        if s3 == -1:
            lev[q] = du
            queue[tail] = q
            tail += 1
        if connect8:
            # a diagonal only when both cells beside it are free
            if s0 != -2 and s1 != -2:
                q = p + o4
                if lev[q] == -1:
                    lev[q] = du
                    queue[tail] = q
                    tail += 1
            if s2 != -2 and s1 != -2:
                q = p + o5
                if lev[q] == -1:
                    lev[q] = du
                    queue[tail] = q
                    tail += 1
            if s2 != -2 and s3 != -2:
                q = p + o6
                if lev[q] == -1:
                    lev[q] = du
                    queue[tail] = q
                    tail += 1
            if s0 != -2 and s3 != -2:
                q = p + o7
                if lev[q] == -1:
                    lev[q] = du
                    queue[tail] = q
                    tail += 1
    return head, lev


@nb.njit(**JIT)
def wavefront(blocked, goal, start, connect8, dist, order):
    """Flood from ``goal`` (see `flood`) and write the field into ``dist``.

    ``dist`` (flat, int64): the number of moves from each cell to the goal,
    -1 where not reached. Returns the number of cells dequeued.
    """
    ny, nx = blocked.shape
    w = nx + 2
    head, lev = flood(blocked, goal, start, connect8, order)
    for i in range(ny):
        row = (i + 1) * w + 1
        for j in range(nx):
            x = lev[row + j]
            dist[i * nx + j] = x if x >= 0 else -1
    return head


@nb.njit(**JIT)
def descend(lev, nx, start, connect8, out):
    """Follow the flood's level grid (`flood`) downhill from ``start`` to the goal.

    ``lev`` is padded (``nx`` cells a row inside the border); ``start`` is a
    plain node index. At each cell take the first neighbour (orthogonal
    before diagonal, a diagonal only with both cells beside it free) one
    move nearer. Writes the plain node indices into ``out`` and returns
    their count (0 when ``start`` was not reached).
    """
    w = nx + 2
    offp, offk = _offsets(nx)
    p = (start // nx + 1) * w + start % nx + 1
    if lev[p] < 0:
        return 0
    nnb = 8 if connect8 else 4
    u = start
    m = 0
    out[m] = u
    m += 1
    while lev[p] > 0:
        want = lev[p] - 1
        for d in range(nnb):
            q = p + offp[d]
            if lev[q] != want:
                continue
            if d >= 4 and (
                lev[p + offp[DA[d - 4]]] == -2 or lev[p + offp[DB[d - 4]]] == -2
            ):
                continue
            p = q
            u += offk[d]
            break
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
    best = point_segment_distance(ax, ay, cx, cy, dx, dy)
    best = min(best, point_segment_distance(bx, by, cx, cy, dx, dy))
    best = min(best, point_segment_distance(cx, cy, ax, ay, bx, by))
    best = min(best, point_segment_distance(dx, dy, ax, ay, bx, by))
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
