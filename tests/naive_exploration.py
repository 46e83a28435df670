"""Plain-loop references for `robotlib.exploration` (frontiers, discount)."""

from __future__ import annotations

import math

import numpy as np


def frontier_cells(state, free=0, unknown=1):
    """Free cells with an unknown 4-neighbour, cell by cell."""
    ny, nx = state.shape
    out = np.zeros((ny, nx), dtype=bool)
    for i in range(ny):
        for j in range(nx):
            if state[i, j] != free:
                continue
            for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                a, b = i + di, j + dj
                if 0 <= a < ny and 0 <= b < nx and state[a, b] == unknown:
                    out[i, j] = True
    return out


def regions(mask):
    """8-connected regions of a mask by flood fill: a list of sets of cells."""
    ny, nx = mask.shape
    seen = np.zeros_like(mask, dtype=bool)
    out = []
    for i in range(ny):
        for j in range(nx):
            if not mask[i, j] or seen[i, j]:
                continue
            stack, cells = [(i, j)], set()
            seen[i, j] = True
            while stack:
                a, b = stack.pop()
                cells.add((a, b))
                for da in (-1, 0, 1):
                    for db in (-1, 0, 1):
                        c, d = a + da, b + db
                        if (
                            0 <= c < ny
                            and 0 <= d < nx
                            and mask[c, d]
                            and not seen[c, d]
                        ):
                            seen[c, d] = True
                            stack.append((c, d))
            out.append(cells)
    return out


def discount(gain, targets, chosen, radius):
    """Burgard's discount, target by target."""
    out = []
    for g, (x, y) in zip(gain, targets, strict=True):
        d = math.hypot(x - chosen[0], y - chosen[1])
        p = max(0.0, 1.0 - d / radius)
        out.append(g * (1.0 - p))
    return np.array(out)
