"""Cheap copies of FastSLAM's particle maps: copy only where two maps differ.

Resampling makes slot ``d`` hold particle ``s``'s map. The two maps are the
same except in cells written since they last were (both came from one
ancestor, or one was copied from the other), so `MapDiff` keeps, for every
pair of slots, a box (rows and columns, inclusive) holding every cell where
their maps may differ, and `MapDiff.resample` copies only that box. Each
map update widens the boxes of the slot it wrote; after a resampling the
boxes are the old ones between the slots' parents. The maps come out the
same, bit for bit, as with whole copies (a test checks), and a copy costs
the area driven through since the particles split, not the whole grid.

Imports NumPy only; never plots.
"""

from __future__ import annotations

import numpy as np

__all__ = ["EMPTY_BOX", "MapDiff", "union_boxes"]

_BIG = np.iinfo(np.int64).max // 4

EMPTY_BOX = np.array([_BIG, -_BIG, _BIG, -_BIG], dtype=np.int64)
"""The empty box ``(i0, i1, j0, j1)`` (``i0 > i1``); union with it changes nothing."""


def union_boxes(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Return the smallest boxes (..., 4) holding boxes ``a`` and ``b`` (..., 4)."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape), dtype=np.int64)
    out[..., 0::2] = np.minimum(a[..., 0::2], b[..., 0::2])
    out[..., 1::2] = np.maximum(a[..., 1::2], b[..., 1::2])
    return out


class MapDiff:
    """Where N particle maps may differ, pair by pair.

    Parameters
    ----------
    n : int
        Slots (particles).
    same : bool
        True if the maps start equal (an empty box for every pair), else a
        whole-grid box for every pair (``shape`` needed).
    shape : tuple of int, optional
        ``(ny, nx)`` of the maps.

    Attributes
    ----------
    boxes : numpy.ndarray of int64, shape (N, N, 4)
        ``boxes[a, b]``: a box holding every cell where maps ``a`` and ``b``
        may differ; empty on the diagonal.
    """

    def __init__(self, n: int, same: bool = True, shape=None):
        self.boxes = np.tile(EMPTY_BOX, (n, n, 1))
        if not same:
            ny, nx = (int(v) for v in shape)
            self.boxes[:] = (0, ny - 1, 0, nx - 1)
            self.boxes[np.arange(n), np.arange(n)] = EMPTY_BOX

    def copy(self) -> MapDiff:
        """Return an independent copy."""
        out = MapDiff(0)
        out.boxes = self.boxes.copy()
        return out

    def wrote(self, written: np.ndarray) -> None:
        """Record that slot ``k`` wrote (at most) box ``written[k]`` (N, 4)."""
        w = np.asarray(written, dtype=np.int64)
        b = union_boxes(self.boxes, w[:, None, :])
        b = union_boxes(b, w[None, :, :])
        n = len(w)
        b[np.arange(n), np.arange(n)] = EMPTY_BOX
        self.boxes = b

    def resample(self, maps: np.ndarray, parents) -> int:
        """Make slot ``k`` hold map ``parents[k]``, copying only what differs.

        Each slot is either its own parent or a slot no slot descends from
        (`robotlib.mapping.fastslam.resample_maps`'s ``parents``).

        Parameters
        ----------
        maps : numpy.ndarray, shape (N, ny, nx)
            Changed in place.
        parents : array_like of int, shape (N,)

        Returns
        -------
        int
            Cells copied.
        """
        p = np.asarray(parents, dtype=np.int64)
        dst = np.flatnonzero(p != np.arange(len(p)))
        src = p[dst]
        if np.any(np.isin(src, dst)):
            raise ValueError("a slot that is copied over may not be copied from")
        boxes = self.boxes[src, dst]
        for s, d, (i0, i1, j0, j1) in zip(src, dst, boxes, strict=True):
            if i0 <= i1 and j0 <= j1:  # a slice copy runs at memcpy speed
                maps[d, i0 : i1 + 1, j0 : j1 + 1] = maps[s, i0 : i1 + 1, j0 : j1 + 1]
        self.boxes = self.boxes[np.ix_(p, p)]
        self.boxes[np.arange(len(p)), np.arange(len(p))] = EMPTY_BOX
        rows = np.maximum(boxes[:, 1] - boxes[:, 0] + 1, 0)
        cols = np.maximum(boxes[:, 3] - boxes[:, 2] + 1, 0)
        return int(np.sum(rows * cols))
