"""Odometry motion model: Thrun's ``sample_motion_model_odometry``.

Two successive odometry poses give an increment decomposed as a rotation
``rot1`` towards the direction of travel, a translation ``trans`` and a final
rotation ``rot2`` (Probabilistic Robotics, table 5.6). Each particle moves by
that increment plus zero-mean Gaussian noise whose variances are

- ``rot1``: ``alpha1 rot1^2 + alpha2 trans^2``
- ``trans``: ``alpha3 trans^2 + alpha4 (rot1^2 + rot2^2)``
- ``rot2``: ``alpha1 rot2^2 + alpha2 trans^2``

(units: rad^2 and m^2; the alphas are dimensionless). A backward move is
decomposed with a negative ``trans`` so that reversing does not look like a
half turn.
"""

from __future__ import annotations

import ctypes
import math
import os
import sys
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numba
import numpy as np

from .._random import as_rng
from . import _kernels

__all__ = ["odometry_increment", "sample_motion_odometry", "OdometryMotionModel"]

PARALLEL_MIN = 4096
"""Particle count from which kernels run over threads."""

_F64 = np.dtype(np.float64)

NORMALS_CHUNK = 8192
"""Rows of motion noise drawn by one generator, beyond (see `standard_normals`)."""

_pool: tuple[int, int, ThreadPoolExecutor] | None = None


def _executor(threads: int) -> ThreadPoolExecutor:
    """Return this process's pool of ``threads`` threads, made on first use."""
    global _pool
    if _pool is None or _pool[0] != os.getpid() or _pool[1] != threads:
        _pool = (os.getpid(), threads, ThreadPoolExecutor(threads, "robotlib-normals"))
    return _pool[2]


def _fill(key: int, chunk: int, out: np.ndarray) -> None:
    gen = np.random.Generator(np.random.SFC64(np.random.SeedSequence([key, chunk])))
    gen.standard_normal(out=out)


class Scratch:
    """Arrays a filter lends its kernels from step to step, by name.

    A step of many particles writes several arrays of the same shapes every
    time; making them afresh costs a page fault per 4 kB (a few ms at 100k
    particles), so the filter keeps them here. An array handed out of the
    filter (its particles or weights) must be `drop`-ped so it is not
    written again.
    """

    def __init__(self):
        self._arrays: dict[str, np.ndarray] = {}

    def take(self, name: str, shape: tuple, dtype=_F64) -> np.ndarray:
        """Return the array ``name`` of this shape and dtype (new if none yet)."""
        a = self._arrays.get(name)
        if a is None or a.shape != shape or (a.dtype is not dtype and a.dtype != dtype):
            a = self._arrays[name] = np.empty(shape, dtype=dtype)
        return a

    def drop(self, a: np.ndarray) -> None:
        """Forget ``a`` (if lent): the next `take` of its name makes a new one."""
        for name, b in list(self._arrays.items()):
            if b is a:
                del self._arrays[name]


def standard_normals(
    rng: np.random.Generator, n: int, out: np.ndarray | None = None
) -> np.ndarray:
    """Draw standard normals (n, 3) for the motion noise of ``n`` particles.

    Up to `NORMALS_CHUNK` rows: ``rng.standard_normal((n, 3))``. Beyond, one
    draw from ``rng`` keys a generator per chunk of `NORMALS_CHUNK` rows
    (chunk ``c`` from ``SeedSequence([key, c])``), and the chunks are filled
    over threads (NumPy draws without the GIL): the numbers depend on ``rng``
    and ``n`` only, not on the number of threads.

    Parameters
    ----------
    rng : numpy.random.Generator
        The randomness.
    n : int
        Particles.
    out : numpy.ndarray, shape (n, 3), optional
        Filled and returned instead of a new array (the same numbers).

    Returns
    -------
    numpy.ndarray, shape (n, 3)
    """
    if out is None:
        out = np.empty((n, 3))
    elif out.shape != (n, 3) or out.dtype != np.float64 or not out.flags.c_contiguous:
        raise ValueError(f"out must be a contiguous float64 array ({n}, 3)")
    if n <= NORMALS_CHUNK:
        return rng.standard_normal(out=out)
    key = int(rng.integers(np.iinfo(np.int64).max))
    chunks = [
        (key, c, out[lo : lo + NORMALS_CHUNK])
        for c, lo in enumerate(range(0, n, NORMALS_CHUNK))
    ]
    threads = min(numba.get_num_threads(), len(chunks))
    if threads <= 1:
        for chunk in chunks:
            _fill(*chunk)
    else:
        for future in [_executor(threads).submit(_fill, *c) for c in chunks]:
            future.result(timeout=60)
    return out


def pcg64_words(rng: np.random.Generator) -> np.ndarray | None:
    """Return the four words of ``rng``'s PCG64 state as an array over its memory.

    ``(state low, state high, increment low, increment high)``, uint64: the
    generator's own memory, so `_kernels.pcg64`'s kernels draw from it and
    advance it as NumPy's methods would (hold ``rng.bit_generator.lock``
    meanwhile). NumPy's ``pcg64_state`` begins with a pointer to the
    ``(state, increment)`` pair of unsigned 128-bit integers, low word
    first; the words are checked against ``bit_generator.state`` before
    use. None when the bit generator is not exactly PCG64 or the check fails.
    """
    bg = rng.bit_generator
    if (
        type(bg) is not np.random.PCG64
        or sys.byteorder != "little"
        or not "1.17.0" <= np.lib.NumpyVersion(np.__version__) < "3.0.0"
    ):  # the layout read below is that of NumPy 1.17 to 2
        return None
    pair = ctypes.c_uint64.from_address(bg.ctypes.state_address).value
    if not pair:
        return None
    words = np.ctypeslib.as_array((ctypes.c_uint64 * 4).from_address(pair))
    st = bg.state["state"]
    w = [int(v) for v in words]
    if w[0] | w[1] << 64 != st["state"] or w[2] | w[3] << 64 != st["inc"]:
        return None
    return words


def _floats(pose) -> list:
    """Return the items of ``pose`` as Python floats (an array: without a loop)."""
    if (
        type(pose) is np.ndarray
        and pose.ndim == 1
        and (pose.dtype is _F64 or pose.dtype == _F64)
    ):  # the canonical dtype compared first: quicker than ``==``
        return pose.tolist()
    return [float(v) for v in pose]


def odometry_increment(odo_prev, odo_now, min_trans: float = 1e-4) -> tuple:
    """Decompose the move between two odometry poses into ``(rot1, trans, rot2)``.

    Parameters
    ----------
    odo_prev, odo_now : array_like, shape (3,)
        Successive odometry poses ``(x, y, theta)``, m and rad.
    min_trans : float
        Below this translation (m) the move counts as a turn in place
        (``rot1 = 0``), so the direction of a tiny move does not matter.

    Returns
    -------
    tuple of float
        ``rot1`` (rad), ``trans`` (m, negative when moving backwards),
        ``rot2`` (rad).
    """
    x0, y0, t0 = _floats(odo_prev)
    x1, y1, t1 = _floats(odo_now)
    dx, dy = x1 - x0, y1 - y0
    trans = math.hypot(dx, dy)
    if trans < min_trans:
        rot1 = 0.0
    else:
        rot1 = math.remainder(math.atan2(dy, dx) - t0, 2 * math.pi)
        if abs(rot1) > math.pi / 2:  # backwards
            rot1 = math.remainder(rot1 + math.pi, 2 * math.pi)
            trans = -trans
    rot2 = math.remainder(t1 - t0 - rot1, 2 * math.pi)
    return rot1, trans, rot2


def _noise_std(alphas, rot1, trans, rot2) -> tuple[float, float, float]:
    a1, a2, a3, a4 = alphas
    sd1 = math.sqrt(a1 * rot1 * rot1 + a2 * trans * trans)
    sdt = math.sqrt(a3 * trans * trans + a4 * (rot1 * rot1 + rot2 * rot2))
    sd2 = math.sqrt(a1 * rot2 * rot2 + a2 * trans * trans)
    return sd1, sdt, sd2


def _particles(particles) -> np.ndarray:
    p = np.ascontiguousarray(particles, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"particles must have shape (N, 3), got {np.shape(particles)}")
    return p


def sample_motion_odometry(
    particles,
    odo_prev,
    odo_now,
    alphas=(0.002, 0.005, 0.01, 0.0005),
    rng: np.random.Generator | int | None = None,
) -> np.ndarray:
    """Move every particle by the odometry increment plus noise.

    Parameters
    ----------
    particles : array_like, shape (N, 3)
        Poses ``(x, y, theta)``, m and rad.
    odo_prev, odo_now : array_like, shape (3,)
        The robot's odometry poses before and after the move.
    alphas : sequence of 4 float
        Noise parameters ``alpha1..alpha4`` (see the module docstring).
    rng : numpy.random.Generator, int or None
        Draws the (N, 3) standard normals (`standard_normals`).

    Returns
    -------
    numpy.ndarray, shape (N, 3)
        The moved particles (a new array), headings wrapped to (-pi, pi].
    """
    p = _particles(particles)
    rot1, trans, rot2 = odometry_increment(odo_prev, odo_now)
    sd = _noise_std(alphas, rot1, trans, rot2)
    noise = standard_normals(as_rng(rng), len(p))
    out = np.empty_like(p)
    kernel = (
        _kernels.sample_odometry_parallel
        if len(p) >= PARALLEL_MIN
        else _kernels.sample_odometry
    )
    kernel(p, rot1, trans, rot2, *sd, noise, out)
    return out


@dataclass(frozen=True)
class OdometryMotionModel:
    """The odometry motion model as an object an `MCL` is composed with.

    Attributes
    ----------
    alphas : tuple of 4 float
        ``alpha1`` (rotation noise from rotation), ``alpha2`` (rotation from
        translation), ``alpha3`` (translation from translation), ``alpha4``
        (translation from rotation); variances as in the module docstring.
        The defaults cover the simulator's default odometry slip with margin.
    """

    alphas: tuple[float, float, float, float] = (0.002, 0.005, 0.01, 0.0005)

    def __post_init__(self):
        if len(self.alphas) != 4 or min(self.alphas) < 0:
            raise ValueError("alphas must be four non-negative numbers")

    def sample(self, particles, odo_prev, odo_now, rng) -> np.ndarray:
        """Return particles moved by the odometry increment plus noise.

        See `sample_motion_odometry` for the parameters.
        """
        return sample_motion_odometry(particles, odo_prev, odo_now, self.alphas, rng)
