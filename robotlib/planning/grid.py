"""Grid planners on a `CSpace`: wavefront, Dijkstra, A*, weighted A*.

Each takes a configuration space, a start and a goal in metres, and returns
a `Plan`: the path in metres (cell centres, start to goal), its cost, and
how many nodes the search expanded. 4- or 8-connected (``connectivity``);
a diagonal move never cuts the corner of a blocked cell. Moves cost their
length in metres times ``1 + cost`` of the cell entered when ``use_cost``
(the cost map), else their length.

Imports the planning kernels and `CSpace` only; never plots.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import _kernels
from .cspace import CSpace

__all__ = [
    "Plan",
    "astar",
    "dijkstra",
    "weighted_astar",
    "wavefront",
    "wavefront_field",
    "cost_field",
    "octile",
    "path_length",
]


@dataclass(frozen=True)
class Plan:
    """A planner's answer.

    Attributes
    ----------
    path : numpy.ndarray, shape (K, 2)
        Waypoints ``(x, y)`` from start to goal, m; (0, 2) when no path.
    cells : numpy.ndarray of int64, shape (K, 2)
        The same as cells ``(i, j)``.
    cost : float
        The path's cost (``inf`` when no path), m (times the cost factors).
    expanded : int
        Nodes the search expanded (cells dequeued, for the wavefront).
    found : bool
        A path exists.
    order : numpy.ndarray of int64, shape (E, 2)
        Cells in the order they were expanded, when asked for (else (0, 2)).
    """

    path: np.ndarray
    cells: np.ndarray
    cost: float
    expanded: int
    found: bool
    order: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))

    def __len__(self) -> int:
        return len(self.path)


def octile(a, b, resolution: float = 1.0) -> np.ndarray:
    """Octile distance between cells ``a`` and ``b`` (..., 2) as ``(i, j)``, m."""
    d = np.abs(np.asarray(a) - np.asarray(b))
    lo = d.min(axis=-1)
    return resolution * (d.sum(axis=-1) - 2 * lo + np.sqrt(2.0) * lo)


def path_length(path) -> float:
    """Length of a polyline (K, 2), m."""
    p = np.asarray(path, dtype=float)
    if len(p) < 2:
        return 0.0
    return float(np.hypot(*np.diff(p, axis=0).T).sum())


def _connect8(connectivity: int) -> bool:
    if connectivity not in (4, 8):
        raise ValueError(f"connectivity must be 4 or 8, got {connectivity}")
    return connectivity == 8


def _cells(cs: CSpace, nodes: np.ndarray) -> np.ndarray:
    return np.column_stack(np.divmod(nodes, cs.shape[1])).astype(np.int64)


def _no_path(expanded: int, order) -> Plan:
    e = np.zeros((0, 2))
    return Plan(e, e.astype(np.int64), float("inf"), int(expanded), False, order)


def _search(cs, start, goal, connectivity, weight, use_cost, record) -> Plan:
    c8 = _connect8(connectivity)
    s = cs.node(start, "start")
    g = cs.node(goal, "goal")
    n = cs.blocked.size
    gcost = np.empty(n)
    parent = np.empty(n, dtype=np.int64)
    order = np.empty(n if record else 0, dtype=np.int64)
    cost = cs.cost if use_cost else np.empty((0, 0))  # size 0: no cost map
    found, expanded = _kernels.astar(
        cs.blocked, cost, s, g, float(weight), c8, cs.resolution, gcost, parent, order
    )
    order_cells = _cells(cs, order[: min(expanded, len(order))])
    if not found:
        return _no_path(expanded, order_cells)
    nodes = np.empty(n, dtype=np.int64)
    m = _kernels.trace(parent, g, nodes)
    cells = _cells(cs, nodes[:m])
    return Plan(
        cs.to_metres(cells), cells, float(gcost[g]), int(expanded), True, order_cells
    )


def astar(
    cs: CSpace,
    start,
    goal,
    connectivity: int = 8,
    use_cost: bool = True,
    record: bool = False,
) -> Plan:
    """Plan with A*: the octile (8-connected) or Manhattan (4) heuristic.

    Parameters
    ----------
    cs : CSpace
        The configuration space.
    start, goal : array_like, shape (2,) or (3,)
        Positions ``(x, y)`` (a heading is ignored), m.
    connectivity : {4, 8}
        Neighbours per cell.
    use_cost : bool
        Add the cost map's factors to the move lengths.
    record : bool
        Keep the expansion order in `Plan.order`.

    Returns
    -------
    Plan
        ``found`` False (and ``cost`` inf) when the goal is unreachable.

    Raises
    ------
    ValueError
        If the start or the goal is off the grid or in a blocked cell.
    """
    return _search(cs, start, goal, connectivity, 1.0, use_cost, record)


def weighted_astar(
    cs: CSpace,
    start,
    goal,
    weight: float = 2.0,
    connectivity: int = 8,
    use_cost: bool = True,
    record: bool = False,
) -> Plan:
    """Plan with weighted A*: the heuristic times ``weight``.

    With ``weight >= 1``: fewer expansions, and a cost at most ``weight``
    times the optimum. See `astar`.
    """
    if not weight >= 0:
        raise ValueError(f"weight must be >= 0, got {weight}")
    return _search(cs, start, goal, connectivity, weight, use_cost, record)


def dijkstra(
    cs: CSpace,
    start,
    goal,
    connectivity: int = 8,
    use_cost: bool = True,
    record: bool = False,
) -> Plan:
    """Plan with Dijkstra's search (A* with a zero heuristic). See `astar`."""
    return _search(cs, start, goal, connectivity, 0.0, use_cost, record)


def cost_field(
    cs: CSpace,
    goal,
    connectivity: int = 8,
    use_cost: bool = True,
    parents: bool = False,
):
    """Optimal cost from ``goal`` to every cell (Dijkstra to exhaustion).

    Moves are symmetric except for the cost factor of the cell entered, so
    this is the cost-to-come from the goal; with ``use_cost`` False it is also
    every cell's cost-to-go. Returns (ny, nx) float64, ``inf`` where
    unreachable; with ``parents`` also (ny, nx) int64, each reached cell's
    flat index one step nearer ``goal`` on its optimal path (-1 at ``goal``
    and at unreached cells).
    """
    c8 = _connect8(connectivity)
    g = cs.node(goal, "goal")
    n = cs.blocked.size
    gcost = np.empty(n)
    parent = np.empty(n, dtype=np.int64)
    cost = cs.cost if use_cost else np.empty((0, 0))  # size 0: no cost map
    _kernels.astar(
        cs.blocked, cost, g, -1, 0.0, c8, cs.resolution, gcost, parent,
        np.empty(0, np.int64),
    )  # fmt: skip
    if parents:
        return gcost.reshape(cs.shape), parent.reshape(cs.shape)
    return gcost.reshape(cs.shape)


def wavefront_field(cs: CSpace, goal, connectivity: int = 8) -> np.ndarray:
    """Count the moves from every cell to ``goal`` by breadth-first flood.

    Returns (ny, nx) int64, -1 where unreachable (the wavefront, or
    distance transform).
    """
    c8 = _connect8(connectivity)
    g = cs.node(goal, "goal")
    dist = np.empty(cs.blocked.size, dtype=np.int64)
    _kernels.wavefront(cs.blocked, g, -1, c8, dist, np.empty(0, np.int64))
    return dist.reshape(cs.shape)


def wavefront(
    cs: CSpace, start, goal, connectivity: int = 8, record: bool = False
) -> Plan:
    """Plan with the wavefront: flood from the goal, descend from the start.

    The flood stops once it reaches the start. The path has the fewest moves
    (each move counts one, diagonal or not); its `Plan.cost` is its length
    in metres. See `astar` for the arguments.
    """
    c8 = _connect8(connectivity)
    s = cs.node(start, "start")
    g = cs.node(goal, "goal")
    n = cs.blocked.size
    nx = cs.shape[1]
    order = np.empty(n if record else 0, dtype=np.int64)
    # the flood's padded level grid, descended as it is (no field copied out)
    expanded, lev = _kernels.flood(cs.blocked, g, s, c8, order)
    order_cells = _cells(cs, order[: min(expanded, len(order))])
    moves = int(lev[(s // nx + 1) * (nx + 2) + s % nx + 1])
    if moves < 0:
        return _no_path(expanded, order_cells)
    nodes = np.empty(moves + 1, dtype=np.int64)
    m = _kernels.descend(lev, nx, s, c8, nodes)
    cells = _cells(cs, nodes[:m])
    path = cs.to_metres(cells)
    return Plan(path, cells, path_length(path), int(expanded), True, order_cells)
