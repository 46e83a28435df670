"""The dynamic window's obstacle grid and its navigation function.

`ObstacleGrid` is a certainty grid in the odometry frame, filled from the
sonar the way VFH's is (`robotlib.avoidance._kernels.certainty_update`: an
echo raises the cell on the sonar's axis at its range, the cells the cone
crossed nearer than that are lowered, so a door painted shut by a jamb's
echo opens once a sonar looks through it). Its memory is short: every cell
within the sonar's range fades with the time constant ``memory``, so what
moved away is forgotten, while the wall ends the front ring saw a moment ago
still count beside and behind the robot.

`navigation` turns the grid into a navigation function (Brock and Khatib's
"global dynamic window", 1999): the length of the shortest 8-connected
path from every cell of a box around the robot and the goal to the goal,
keeping ``block`` from any occupied cell where it can, each step costing
more the nearer it passes to one (within ``margin`` beyond ``block``).
Unseen cells are free. `ObstacleGrid.carrot` follows its
steepest descent from the robot a given length: the point DWA's goal terms
aim at, round the wall of a trap rather than into it.

Imports: numpy, numba, the kernels; never plotting.
"""

from __future__ import annotations

import heapq
import math

import numba as nb
import numpy as np

from .._config import JIT, readonly
from ..p3dx import CYCLE, SONAR_CONE, SONAR_MAX_RANGE, SONAR_POSES
from . import _kernels

__all__ = ["ObstacleGrid", "navigation"]

_SQRT2 = math.sqrt(2.0)


@nb.njit(**JIT)
def _clearance(occupied, res, reach, out):
    """Distance from each cell's centre to the nearest occupied one, m (<= reach)."""
    ny, nx = occupied.shape
    out[:] = reach
    k = int(math.ceil(reach / res))
    for i in range(ny):
        for j in range(nx):
            if not occupied[i, j]:
                continue
            for di in range(-k, k + 1):
                ii = i + di
                if ii < 0 or ii >= ny:
                    continue
                for dj in range(-k, k + 1):
                    jj = j + dj
                    if jj < 0 or jj >= nx:
                        continue
                    d = res * math.sqrt(di * di + dj * dj)
                    if d < out[ii, jj]:
                        out[ii, jj] = d


@nb.njit(**JIT)
def _wavefront(cost, gi, gj, out):
    """Dijkstra from cell ``(gi, gj)`` over 8 neighbours; ``cost``: per unit step."""
    ny, nx = cost.shape
    out[:] = np.inf
    out[gi, gj] = 0.0
    heap = [(0.0, gi * nx + gj)]
    while len(heap) > 0:
        d, k = heapq.heappop(heap)
        i, j = k // nx, k % nx
        if d > out[i, j]:
            continue
        for di in range(-1, 2):
            for dj in range(-1, 2):
                ii, jj = i + di, j + dj
                if (di == 0 and dj == 0) or ii < 0 or ii >= ny or jj < 0 or jj >= nx:
                    continue
                c = cost[ii, jj]
                step = 1.4142135623730951 if di != 0 and dj != 0 else 1.0
                nd = d + step * 0.5 * (c + cost[i, j])
                if nd < out[ii, jj]:
                    out[ii, jj] = nd
                    heapq.heappush(heap, (nd, ii * nx + jj))


def navigation(
    occupied,
    res: float,
    goal_cell,
    block: float,
    margin: float,
    penalty: float = 3.0,
    blocked: float = 50.0,
) -> np.ndarray:
    """Shortest-path distance to the goal from every cell of a grid, m.

    Parameters
    ----------
    occupied : array_like of bool, shape (ny, nx)
        Occupied cells.
    res : float
        Cell side, m.
    goal_cell : tuple of int
        ``(i, j)``: row and column of the goal.
    block : float
        A step into a cell whose centre lies nearer than this to an occupied
        cell's costs ``blocked`` times its length, m: so much that a path
        keeps out unless there is no other way, but the robot's own cell
        (in the band after a close pass) still has a way out.
    margin : float
        Within ``block + margin`` of one a step costs up to ``1 + penalty``
        times its length (linearly more the nearer), m.
    penalty, blocked : float
        The cost factors next to the band and inside it.

    Returns
    -------
    numpy.ndarray, shape (ny, nx)
        Path length to the goal (weighted), m.
    """
    occ = np.ascontiguousarray(occupied, dtype=np.bool_)
    gi, gj = (int(g) for g in goal_cell)
    if occ.ndim != 2 or not (0 <= gi < occ.shape[0] and 0 <= gj < occ.shape[1]):
        raise ValueError(f"goal cell {goal_cell} outside a grid of shape {occ.shape}")
    near = np.empty(occ.shape)
    _clearance(occ, float(res), float(block + margin), near)
    cost = 1.0 + penalty * np.clip((block + margin - near) / max(margin, 1e-9), 0, 1)
    cost[near < block] = blocked
    cost[gi, gj] = 1.0
    out = np.empty(occ.shape)
    _wavefront(cost * res, gi, gj, out)
    return out


class ObstacleGrid:
    """Short-memory certainty grid from the sonar, with a navigation function.

    Parameters
    ----------
    resolution, extent : float
        Cell side and the side of the square grid (centred on the first pose
        seen), m.
    memory : float
        Cells within the sonar's range fade as ``exp(-t / memory)``, s.
    occupied : float
        Certainty at which a cell counts as an obstacle.
    cmax : float
        Certainty ceiling (an echo adds 1; a sonar looking through takes 1).

    Attributes
    ----------
    certainty : numpy.ndarray, shape (n, n)
        Rows are y, columns x.
    origin : numpy.ndarray or None, shape (2,)
        Lower-left corner, odometry frame, m (None before the first scan).
    distance : numpy.ndarray, shape (h, w)
        The last navigation function (`navigation`) over ``box``, m.
    box : tuple of int
        ``(i0, j0)``: where ``distance`` starts in the grid.
    """

    def __init__(
        self, resolution=0.1, extent=40.0, memory=30.0, occupied=2.0, cmax=10.0
    ):
        self.resolution, self.memory = float(resolution), float(memory)
        self.occupied, self.cmax = float(occupied), float(cmax)
        self.n = int(math.ceil(extent / resolution))
        self.sensors = np.ascontiguousarray(SONAR_POSES, dtype=np.float64)
        self.reset()

    def reset(self) -> None:
        """Forget everything."""
        self.certainty = np.zeros((self.n, self.n))
        self.origin = None
        self.distance = np.full((1, 1), np.inf)
        self.box = (0, 0)

    def update(self, sonar: np.ndarray, pose: np.ndarray) -> None:
        """Fade what lies within sonar range, then add one scan."""
        res = self.resolution
        if self.origin is None:
            half = 0.5 * self.n * res
            self.origin = np.array([pose[0] - half, pose[1] - half])
        x0, y0 = self.origin
        if self.memory > 0:
            fade = math.exp(-CYCLE / self.memory)
            _kernels.fade(self.certainty, x0, y0, res, pose[0], pose[1],
                          SONAR_MAX_RANGE, fade)  # fmt: skip
        _kernels.certainty_update(
            self.certainty, x0, y0, res, pose, readonly(self.sensors), sonar,
            SONAR_MAX_RANGE, 0.5 * SONAR_CONE, 2.5, 1.0, 1.0, self.cmax,
        )  # fmt: skip

    def cell(self, xy) -> tuple[int, int]:
        """Return the ``(row, column)`` holding the point ``xy`` (odometry, m)."""
        j = int((xy[0] - self.origin[0]) // self.resolution)
        i = int((xy[1] - self.origin[1]) // self.resolution)
        return i, j

    def points(self, pose, reach: float) -> np.ndarray:
        """Occupied cells' centres within ``reach`` of the robot, robot frame, m.

        Returns
        -------
        numpy.ndarray, shape (P, 2)
        """
        res, (x0, y0) = self.resolution, self.origin
        i0, j0 = self.cell((pose[0] - reach, pose[1] - reach))
        i1, j1 = self.cell((pose[0] + reach, pose[1] + reach))
        i0, j0 = max(i0, 0), max(j0, 0)
        i, j = np.nonzero(self.certainty[i0 : i1 + 1, j0 : j1 + 1] >= self.occupied)
        dx = x0 + (j + j0 + 0.5) * res - pose[0]
        dy = y0 + (i + i0 + 0.5) * res - pose[1]
        c, s = math.cos(pose[2]), math.sin(pose[2])
        local = np.column_stack([c * dx + s * dy, -s * dx + c * dy])
        return local[np.hypot(dx, dy) < reach]

    def plan(self, pose, goal, block: float, margin: float, border: float) -> None:
        """Compute the navigation function to ``goal`` over a box round both.

        The box holds the robot and the goal (clipped to the grid) with
        ``border`` m to spare; a goal outside the grid is replaced by the
        box's cell nearest to it.
        """
        res = self.resolution
        lo = np.minimum(pose[:2], goal) - border
        hi = np.maximum(pose[:2], goal) + border
        i0, j0 = (max(k, 0) for k in self.cell(lo))
        i1, j1 = (min(k, self.n - 1) for k in self.cell(hi))
        occ = self.certainty[i0 : i1 + 1, j0 : j1 + 1] >= self.occupied
        gi, gj = self.cell(goal)
        gi = min(max(gi - i0, 0), occ.shape[0] - 1)
        gj = min(max(gj - j0, 0), occ.shape[1] - 1)
        self.distance = navigation(occ, res, (gi, gj), block, margin)
        self.box = (i0, j0)

    def carrot(self, pose, goal, length: float):
        """Follow the navigation function's descent from the robot ``length`` m.

        Returns
        -------
        point : numpy.ndarray or None, shape (2,)
            Where the descent ends (odometry frame, m; ``goal`` itself if it
            gets there); None when the robot's cell has no path to the goal
            or lies outside the box.
        togo : float
            The navigation function at the robot's cell, m (inf: no path).
        """
        d = self.distance
        i, j = self.cell(pose)
        i, j = i - self.box[0], j - self.box[1]
        inside = 0 <= i < d.shape[0] and 0 <= j < d.shape[1]
        if not inside or not np.isfinite(d[i, j]):
            return None, math.inf
        togo = float(d[i, j])
        walked = 0.0
        while walked < length:
            sub = d[max(i - 1, 0) : i + 2, max(j - 1, 0) : j + 2]
            k = np.unravel_index(int(np.argmin(sub)), sub.shape)
            ni, nj = max(i - 1, 0) + int(k[0]), max(j - 1, 0) + int(k[1])
            if sub[k] >= d[i, j]:  # the goal's cell
                return np.array(goal, dtype=float), togo
            walked += self.resolution * (_SQRT2 if ni != i and nj != j else 1.0)
            i, j = ni, nj
        res = self.resolution
        point = np.array(
            [
                self.origin[0] + (j + self.box[1] + 0.5) * res,
                self.origin[1] + (i + self.box[0] + 0.5) * res,
            ]
        )
        return point, togo
