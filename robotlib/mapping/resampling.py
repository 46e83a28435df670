"""Weights and resampling of map-carrying particles (grid FastSLAM's helpers).

`normalise_log_weights` turns log-weights into weights; `resample_parents`
says which particle each slot holds after a draw, keeping the slots of
particles drawn at least once; `resample_maps` copies the maps in place
accordingly. Re-exported by `robotlib.mapping.fastslam`. Imports this
package's kernels only; never plots.
"""

from __future__ import annotations

import numpy as np

from . import _kernels

__all__ = ["normalise_log_weights", "resample_maps", "resample_parents"]

PARALLEL_MIN = 64
"""Particle count from which the map copies run over threads."""


def normalise_log_weights(logw) -> np.ndarray:
    """Return weights (N,) summing to 1 from log-weights (N,), stably."""
    lw = np.asarray(logw, dtype=float)
    w = np.exp(lw - lw.max())
    return w / w.sum()


def resample_parents(indexes, n: int) -> np.ndarray:
    """Which particle each slot holds after a draw ``indexes`` (N,), keeping slots.

    A particle drawn at least once keeps its slot; each further copy goes to
    the slot of a particle that was not drawn. Returns ``parents`` (N,).
    """
    idx = np.asarray(indexes, dtype=np.int64)
    counts = np.bincount(idx, minlength=n)
    dead = np.flatnonzero(counts == 0)
    parents = np.arange(n)
    parents[dead] = np.repeat(np.arange(n), np.maximum(counts - 1, 0))
    return parents


def resample_maps(maps: np.ndarray, indexes) -> tuple[np.ndarray, np.ndarray]:
    """Make slot ``k`` hold particle ``indexes[k]``'s map, copying in place.

    A particle drawn at least once keeps its slot (and map); each further
    copy goes to the slot of a particle that was not drawn.

    Parameters
    ----------
    maps : numpy.ndarray, shape (N, ny, nx)
        One map per particle; changed in place.
    indexes : array_like of int, shape (N,)
        The resampler's draw.

    Returns
    -------
    parents : numpy.ndarray of int, shape (N,)
        Which old particle each slot now holds.
    order : numpy.ndarray of int, shape (N,)
        The same as ``parents`` (kept for symmetry with ``particles[order]``).
    """
    parents = resample_parents(indexes, len(maps))
    dead = np.flatnonzero(parents != np.arange(len(maps)))
    extra = parents[dead]
    n = len(maps)
    if len(dead):
        kernel = (
            _kernels.copy_maps_parallel if n >= PARALLEL_MIN else _kernels.copy_maps
        )
        kernel(maps, np.ascontiguousarray(extra), np.ascontiguousarray(dead))
    return parents, parents
