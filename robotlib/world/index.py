"""`SegmentIndex`: walls sorted into a uniform grid of buckets, for large maps.

A MobileSim map of a building holds tens of thousands of DATA points (each a
small cross of two segments, see `robotlib.world.World.obstacles`);
measuring every distance against all of them makes a distance field take
minutes. The index lets the kernels look only at the buckets near a point,
and gives the very same numbers (`robotlib.world._kernels.indexed_nearest`).
Imports only the world's kernels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import _kernels

__all__ = ["SegmentIndex", "INDEX_MIN_SEGMENTS"]

INDEX_MIN_SEGMENTS = 256
"""Worlds with at least this many obstacle segments measure through an index."""

_MARGIN = 1e-6  # m: a segment also goes into buckets it misses by this little


@dataclass(frozen=True)
class SegmentIndex:
    """Segment indices per bucket of a uniform grid (CSR layout).

    Attributes
    ----------
    segments : numpy.ndarray, shape (M, 4)
        The segments indexed, m.
    origin : tuple of float
        Lower-left corner of bucket ``[0, 0]``, m.
    size : float
        Side of a bucket, m.
    shape : tuple of int
        ``(nby, nbx)`` buckets.
    start : numpy.ndarray, shape (nby * nbx + 1,), int64
        Bucket ``b`` holds ``items[start[b]:start[b + 1]]``.
    items : numpy.ndarray, int64
        Segment indices, ascending within each bucket.
    """

    segments: np.ndarray
    origin: tuple[float, float]
    size: float
    shape: tuple[int, int]
    start: np.ndarray
    items: np.ndarray

    @classmethod
    def build(
        cls, segments: np.ndarray, bounds, size: float | None = None
    ) -> SegmentIndex:
        """Index ``segments`` (M, 4) over ``bounds`` grown to cover them all.

        Parameters
        ----------
        segments : numpy.ndarray, shape (M, 4)
            Segments, m.
        bounds : tuple of float
            ``(xmin, ymin, xmax, ymax)``, m: the area queries come from.
        size : float, optional
            Bucket side, m; default: about two segments per bucket on
            average, between 0.1 m and 2 m.
        """
        seg = np.ascontiguousarray(segments, dtype=float)
        xmin, ymin, xmax, ymax = (float(b) for b in bounds)
        if len(seg):
            xmin = min(xmin, float(seg[:, [0, 2]].min()))
            xmax = max(xmax, float(seg[:, [0, 2]].max()))
            ymin = min(ymin, float(seg[:, [1, 3]].min()))
            ymax = max(ymax, float(seg[:, [1, 3]].max()))
        xmin, ymin = xmin - 2 * _MARGIN, ymin - 2 * _MARGIN
        xmax, ymax = xmax + 2 * _MARGIN, ymax + 2 * _MARGIN
        if size is None:
            area = (xmax - xmin) * (ymax - ymin)
            size = min(2.0, max(0.1, 1.5 * math.sqrt(area / max(len(seg), 1))))
        nbx = max(1, math.ceil((xmax - xmin) / size))
        nby = max(1, math.ceil((ymax - ymin) / size))
        counts = np.zeros(nbx * nby + 1, dtype=np.int64)
        _kernels.bucket_counts(seg, xmin, ymin, size, nbx, nby, _MARGIN, counts)
        start = np.cumsum(counts)
        items = np.empty(int(start[-1]), dtype=np.int64)
        _kernels.bucket_fill(seg, xmin, ymin, size, nbx, nby, _MARGIN, start, items)
        for a in (seg, start, items):
            a.setflags(write=False)
        return cls(seg, (xmin, ymin), float(size), (nby, nbx), start, items)

    @property
    def args(self) -> tuple:
        """``(x0, y0, size, nbx, nby, start, items)``, as the kernels take them."""
        nby, nbx = self.shape
        return (*self.origin, self.size, nbx, nby, self.start, self.items)

    def distances(self, points: np.ndarray) -> np.ndarray:
        """Distance from each of ``points`` (K, 2) to the nearest segment, m."""
        pts = np.ascontiguousarray(points, dtype=float).reshape(-1, 2)
        out = np.empty(len(pts))
        _kernels.indexed_min_distance(pts, self.segments, *self.args, out)
        return out
