"""Which frontier a robot drives to: path cost, information gain, utility, teams.

- `known_space`: the configuration space of what the map knows, unknown
  cells treated as obstacles (a robot plans only through space it has
  seen), occupied cells inflated by the robot's radius, teammates' bodies
  blocked when asked.
- `frontier_costs`: each frontier's reachable target and the path cost to
  it (Dijkstra from the robot over the known space, `cost_field`), with the
  turn in place before the robot can set off along it (`departure`).
- `information_gain`: the unknown area around each target, m^2.
- `utility`: gain minus ``beta`` times cost (Burgard et al., 2005).
- `discount`: the coordination rule: once a teammate has chosen a target,
  the utility of every target within ``radius`` of it shrinks by
  ``1 - d / radius`` of itself (what the teammate will see there is not
  worth as much any more).
- `choose`: the frontiers of every robot that needs one, by ``"nearest"``
  (least path cost), ``"utility"`` (each robot alone) or ``"coordinated"``
  (utility, discounted by the targets already chosen, best pair first).

Imports the planning layer; never plots.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from ..planning import CSpace, cost_field, cost_map, inflate
from .frontiers import OCCUPIED, UNKNOWN, Frontier

__all__ = [
    "STRATEGIES",
    "known_space",
    "frontier_costs",
    "departure",
    "information_gain",
    "utility",
    "discount",
    "choose",
]

STRATEGIES = ("nearest", "utility", "coordinated")
"""The frontier choices `choose` knows."""


def known_space(
    state,
    origin,
    resolution: float,
    radius: float,
    robots=(),
    others=(),
    echoes=None,
    falloff: float = 0.5,
    weight: float = 2.0,
) -> CSpace:
    """Build the configuration space of the known map.

    Parameters
    ----------
    state : array_like of int, shape (ny, nx)
        Cell states (`robotlib.exploration.frontiers.classify`).
    origin : tuple of float
        Lower-left corner, m.
    resolution : float
        Cell side, m.
    radius : float
        Robot radius plus margin, m: occupied cells are inflated by it.
    robots : array_like, shape (R, 2)
        Positions where robots stand, m: a disc of ``radius`` around each is
        free (a body occupies it, so no wall does; the laser never sees the
        cells under and behind the robot).
    others : array_like, shape (P, 2)
        Teammates to plan around, m: a disc of twice ``radius`` around each
        is blocked.
    echoes : array_like of bool, shape (ny, nx), optional
        Cells where the sonar saw something the map may not hold (a thin
        post the laser passes), inflated like occupied cells.
    falloff, weight : float
        The cost band near walls (`robotlib.planning.cost_map`).

    Returns
    -------
    CSpace
        Unknown cells blocked (not inflated), occupied cells inflated.
    """
    s = np.asarray(state)
    occupied = s == OCCUPIED
    if echoes is not None:
        occupied = occupied | np.asarray(echoes, dtype=bool)
    unknown = s == UNKNOWN
    robots = np.asarray(robots, dtype=float).reshape(-1, 2)
    others = np.asarray(others, dtype=float).reshape(-1, 2)
    cells = _cells(robots, origin, resolution, s.shape)
    under = np.zeros(s.shape, dtype=bool)
    under[cells[:, 0], cells[:, 1]] = True
    under = inflate(under, radius, resolution)
    unknown &= ~under
    blocked = inflate(occupied, radius, resolution) | unknown
    dist = ndimage.distance_transform_cdt(~occupied, metric="chessboard") * resolution
    cost = cost_map(dist, radius, falloff, weight)
    if len(others):
        mark = np.zeros(s.shape, dtype=bool)
        c = _cells(others, origin, resolution, s.shape)
        mark[c[:, 0], c[:, 1]] = True
        blocked |= inflate(mark, 2 * radius, resolution)
    return CSpace(blocked, cost, origin, resolution, radius)


def _cells(xy, origin, resolution, shape) -> np.ndarray:
    """Cells ``(i, j)`` of points (P, 2), clipped to the grid."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    j = np.clip(
        ((xy[:, 0] - origin[0]) // resolution).astype(np.int64), 0, shape[1] - 1
    )
    i = np.clip(
        ((xy[:, 1] - origin[1]) // resolution).astype(np.int64), 0, shape[0] - 1
    )
    return np.column_stack([i, j])


def frontier_costs(
    cs: CSpace,
    start,
    frontiers: list[Frontier],
    field=None,
    min_distance: float = 0.4,
    heading: float | None = None,
    turn: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Path cost from ``start`` to each frontier, and the point to drive to.

    Parameters
    ----------
    cs : CSpace
        The known space (`known_space`).
    start : array_like, shape (2,) or (3,)
        The robot's position, m.
    frontiers : list of Frontier
        The regions.
    field : numpy.ndarray, shape (ny, nx), optional
        A cost field from ``start`` already computed (`cost_field`).
    min_distance : float
        Cells nearer ``start`` than this are no target (m): the robot is
        there already.
    heading : float, optional
        The robot's heading, rad. With it and ``turn``, each cost also
        counts the turn in place before the robot sets off along the path
        (`departure`): a robot that must turn round first is that much
        further from the target.
    turn : float
        Cost of that turn, m per rad (a robot turning at ``w_max`` could
        drive ``speed / w_max`` m in the time of a radian).

    Returns
    -------
    costs : numpy.ndarray, shape (F,)
        Path cost to each region's target, m (times the cost band's
        factors); ``inf`` when no cell of the region is reachable (or all
        are within ``min_distance``).
    targets : numpy.ndarray, shape (F, 2)
        Each region's reachable cell nearest its centroid, m (its
        `Frontier.target` when none is reachable).
    """
    turning = heading is not None and turn > 0
    parent = None
    if field is None and turning:
        field, parent = cost_field(cs, start, parents=True)
    elif field is None:
        field = cost_field(cs, start)
    costs = np.full(len(frontiers), np.inf)
    targets = np.zeros((len(frontiers), 2))
    cells = np.zeros((len(frontiers), 2), dtype=np.int64)
    here = np.asarray(start, dtype=float)[:2]
    for k, f in enumerate(frontiers):
        c = field[f.cells[:, 0], f.cells[:, 1]]
        far = np.hypot(*(cs.to_metres(f.cells) - here).T) > min_distance
        ok = np.isfinite(c) & far
        targets[k] = f.target
        if not ok.any():
            continue
        centres = cs.to_metres(f.cells[ok])
        near = int(np.argmin(np.sum((centres - f.centroid) ** 2, axis=1)))
        targets[k] = centres[near]
        cells[k] = f.cells[ok][near]
        costs[k] = c[ok][near]
    if turning:
        if parent is None:
            raise ValueError("heading needs the field's parents: leave field None")
        go = np.isfinite(costs)
        way = departure(cs, parent, here, cells[go])
        off = np.abs((way - heading + np.pi) % (2 * np.pi) - np.pi)
        costs[go] += turn * off
    return costs, targets


def departure(cs: CSpace, parent, start, cells, reach: float = 0.5) -> np.ndarray:
    """Return the way each path leaves ``start``, rad.

    Parameters
    ----------
    cs : CSpace
        The space the paths were planned in.
    parent : numpy.ndarray of int64, shape (ny, nx)
        Each cell's next cell towards ``start`` (`cost_field` with
        ``parents``).
    start : array_like, shape (2,)
        Where the paths begin, m.
    cells : array_like of int, shape (K, 2)
        The paths' ends ``(i, j)``, reachable.
    reach : float
        The direction is taken to the path's last cell (walking back from
        its end) at least this far from ``start``, m.

    Returns
    -------
    numpy.ndarray, shape (K,)
        Bearing from ``start`` to that cell, rad.
    """
    cells = np.asarray(cells, dtype=np.int64).reshape(-1, 2)
    nx = parent.shape[1]
    flat = parent.ravel()
    here = np.asarray(start, dtype=float)[:2]
    at = cells[:, 0] * nx + cells[:, 1]
    for _ in range(flat.size):  # walk back while the next cell is far enough
        nxt = flat[at]
        go = nxt >= 0
        xy = cs.to_metres(np.column_stack([nxt[go] // nx, nxt[go] % nx]))
        go[go] = np.hypot(*(xy - here).T) >= reach
        if not go.any():
            break
        at = np.where(go, nxt, at)
    xy = cs.to_metres(np.column_stack([at // nx, at % nx]))
    return np.arctan2(xy[:, 1] - here[1], xy[:, 0] - here[0])


def information_gain(state, origin, resolution: float, targets, radius: float):
    """Unknown area within a square of half-side ``radius`` around each target.

    Parameters
    ----------
    state : array_like of int, shape (ny, nx)
        Cell states.
    origin : tuple of float
        Lower-left corner, m.
    resolution : float
        Cell side, m.
    targets : array_like, shape (F, 2)
        Points, m.
    radius : float
        Half-side of the window, m (about what the sensor sees from there).

    Returns
    -------
    numpy.ndarray, shape (F,)
        Unknown area, m^2.
    """
    s = np.asarray(state)
    unknown = (s == UNKNOWN).astype(np.int64)
    table = np.zeros((s.shape[0] + 1, s.shape[1] + 1), dtype=np.int64)
    table[1:, 1:] = unknown.cumsum(0).cumsum(1)
    c = _cells(targets, origin, resolution, s.shape)
    r = int(round(radius / resolution))
    i0 = np.clip(c[:, 0] - r, 0, s.shape[0])
    i1 = np.clip(c[:, 0] + r + 1, 0, s.shape[0])
    j0 = np.clip(c[:, 1] - r, 0, s.shape[1])
    j1 = np.clip(c[:, 1] + r + 1, 0, s.shape[1])
    n = table[i1, j1] - table[i0, j1] - table[i1, j0] + table[i0, j0]
    return n * resolution**2


def utility(gain, cost, beta: float):
    """Burgard's utility ``gain - beta * cost`` (``-inf`` where the cost is).

    ``gain`` in m^2, ``cost`` in m, ``beta`` in m^2 per m.
    """
    gain = np.asarray(gain, dtype=float)
    cost = np.asarray(cost, dtype=float)
    with np.errstate(invalid="ignore"):
        u = gain - beta * cost
    return np.where(np.isfinite(cost), u, -np.inf)


def discount(gain, targets, chosen, radius: float) -> np.ndarray:
    """Reduce the gains near a target a teammate chose (Burgard et al., 2005).

    Parameters
    ----------
    gain : array_like, shape (F,)
        The targets' gains (or utilities before their cost), m^2.
    targets : array_like, shape (F, 2)
        The targets, m.
    chosen : array_like, shape (2,)
        The target a teammate chose, m.
    radius : float
        Range of the discount, m (about the sensor's range).

    Returns
    -------
    numpy.ndarray, shape (F,)
        ``gain * (1 - p(d))`` with ``p(d) = max(0, 1 - d / radius)``, ``d``
        each target's distance to ``chosen`` (the chosen target's own gain
        becomes 0).
    """
    g = np.asarray(gain, dtype=float)
    t = np.asarray(targets, dtype=float).reshape(-1, 2)
    if not radius > 0:
        raise ValueError("radius must be positive")
    d = np.hypot(*(t - np.asarray(chosen, dtype=float)[:2]).T)
    return g * (1.0 - np.clip(1.0 - d / radius, 0.0, 1.0))


def choose(
    costs,
    gains,
    targets,
    strategy: str = "coordinated",
    beta: float = 1.0,
    radius: float = 4.0,
    taken=(),
) -> np.ndarray:
    """Pick a target for each robot that needs one.

    Parameters
    ----------
    costs : array_like, shape (R, F)
        Path cost from each robot needing a target to each target, m.
    gains : array_like, shape (F,)
        Each target's information gain, m^2.
    targets : array_like, shape (F, 2)
        The targets, m.
    strategy : {"nearest", "utility", "coordinated"}
        ``"nearest"``: least cost; ``"utility"``: most ``gain - beta *
        cost`` for each robot alone; ``"coordinated"``: the same after
        `discount` by every target already ``taken`` and chosen, the best
        (robot, target) pair assigned first.
    beta : float
        Weight of the cost, m^2 per m.
    radius : float
        The discount's range, m.
    taken : array_like, shape (P, 2)
        Targets teammates are already driving to, m.

    Returns
    -------
    numpy.ndarray of int64, shape (R,)
        The index of each robot's target, -1 when it can reach none.
    """
    if strategy not in STRATEGIES:
        raise ValueError(f"strategy must be one of {STRATEGIES}, got {strategy!r}")
    c = np.atleast_2d(np.asarray(costs, dtype=float))
    g = np.asarray(gains, dtype=float).copy()
    t = np.asarray(targets, dtype=float).reshape(-1, 2)
    n_robots, n_targets = c.shape
    out = np.full(n_robots, -1, dtype=np.int64)
    if n_targets == 0:
        return out
    if strategy == "nearest":
        ok = np.isfinite(c).any(axis=1)
        out[ok] = np.argmin(c[ok], axis=1)
        return out
    if strategy == "utility":
        u = utility(g[None, :], c, beta)
        ok = np.isfinite(u).any(axis=1)
        out[ok] = np.argmax(u[ok], axis=1)
        return out
    for p in np.asarray(taken, dtype=float).reshape(-1, 2):
        g = discount(g, t, p, radius)
    todo = np.ones(n_robots, dtype=bool)
    while todo.any():
        u = utility(g[None, :], c, beta)
        u[~todo] = -np.inf
        if not np.isfinite(u).any():
            break
        r, k = np.unravel_index(int(np.argmax(u)), u.shape)
        out[r] = k
        todo[r] = False
        g = discount(g, t, t[k], radius)
    return out
