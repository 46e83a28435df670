"""Which sonar echoes mark walls in grid FastSLAM's maps (by sonar or by reading).

`sonar_groups` splits a ring into the sonars that mark their echo arcs as
walls and those that only free their cones (the ``sonar_walls`` rule, by
direction); `incidence_marks` decides per particle and reading from the
angle of incidence in the particle's own map, falling back on that rule
where the map holds no wall yet; `update_sonar_marks` adds a reading with
those choices. Used by `robotlib.mapping.fastslam`. Imports this package's
kernels only; never plots.
"""

from __future__ import annotations

import math

import numpy as np

from . import _kernels_incidence

__all__ = ["incidence_marks", "sonar_groups", "update_sonar_marks"]

INCIDENCE_G_MIN = 3.0
"""Smallest log-odds gradient (`_kernels_incidence.sonar_incidence_many`) taken
as a wall's direction; below it the map holds no wall at the echo yet."""


def sonar_groups(n_sensors: int, walls) -> list:
    """``[(indexes or None, marks_walls)]``: the sonars per map-update call."""
    if walls is None:
        return [(None, True)]
    mark = np.zeros(n_sensors, dtype=bool)
    mark[np.asarray(walls, dtype=np.int64)] = True
    groups = [(np.flatnonzero(mark), True), (np.flatnonzero(~mark), False)]
    return [(np.ascontiguousarray(k), m) for k, m in groups if len(k)]


def _kernel(name: str, parallel: bool):
    return getattr(_kernels_incidence, name + ("_parallel" if parallel else ""))


def incidence_marks(maps, geometry, poses, z, sonar, max_incidence: float,
                    default, parallel: bool = False) -> np.ndarray:  # fmt: skip
    """Which echoes mark walls, (N, S) bool, from the incidence in each map.

    An echo marks its arc when the wall its cone meets in map ``maps[n]``
    (N, ny, nx) lies within ``max_incidence`` (rad) of facing the sonar;
    where the map shows no wall at the echo, ``default[k]`` (S,) decides.
    ``geometry`` is ``(x0, y0, res)``; ``poses`` (N, 3); ``z`` (S,) m.
    """
    cos_inc = np.empty((len(poses), len(z)))
    _kernel("sonar_incidence_many", parallel)(
        maps, *geometry, poses, sonar.sensors, z, sonar.max_range, INCIDENCE_G_MIN,
        cos_inc,
    )  # fmt: skip
    facing = np.nan_to_num(cos_inc) >= math.cos(max_incidence)
    return np.where(np.isnan(cos_inc), np.asarray(default)[None, :], facing)


def update_sonar_marks(maps, geometry, poses, z, marks, sonar, model,
                       parallel: bool = False) -> None:  # fmt: skip
    """Add a ring reading ``z`` (S,) to every map, walls as ``marks`` (N, S) say.

    Sonar ``k`` marks its echo arc in map ``n`` only where ``marks[n, k]``;
    elsewhere it frees its cone only.
    """
    _kernel("sonar_update_marks_many", parallel)(
        maps, *geometry, poses, sonar.sensors, z, np.ascontiguousarray(marks),
        sonar.cone / 2, sonar.max_range, model.thickness, model.l_occ,
        model.l_free, model.sigma or 0.0, model.max_weight, model.l_min,
        model.l_max,
    )  # fmt: skip
