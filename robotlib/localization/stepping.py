"""Running a fused MCL step on a cone table: one kernel call, or chunks over threads.

The sensor models' fused step (``_run``, which `MCL.step` calls when its
models allow: the odometry motion model, a ``fast`` paper or beam model)
runs here from `PARALLEL_MIN` particles on (below, the models call one
serial kernel, `chunked.beam_small` or `chunked.paper_small`, that moves,
weighs, estimates and, when the caller passes the resampling draw,
resamples): `run_step`, in pieces on a pool of Python threads
(`robotlib.localization._kernels.chunked`), twice as many as threads, each
a task of its own so that a thread another process slows takes fewer. The
motion noise follows `robotlib.localization.motion.standard_normals`'
streams, so the numbers do not depend on the threads: up to
`FILL_FIRST_MAX` particles it is drawn first, beyond each piece is one of
the noise's chunks and draws its own rows; from `OPENMP_MIN` particles
numba's threaded kernel draws it where it is used
(`_kernels.normals`). The sums run serially at the end; from `OPENMP_MIN`
particles a resampling's rows are gathered in pieces over the threads
again. A waiting thread sleeps (no OpenMP spinning), so a step keeps its
pace when another process shares the cores. Same numbers, bit for bit,
as the models' kernels in turn.

The arrays a fused step writes come from the filter's scratch
(`_outputs`, `_small_outputs`). Imports the localization's kernels and
`robotlib.localization.motion`; never the sensor models or
`robotlib.localization.mcl`.
"""

from __future__ import annotations

import numba
import numpy as np

from . import _kernels
from ._kernels import chunked
from .motion import NORMALS_CHUNK, PARALLEL_MIN, _executor, _fill

__all__ = ["PARALLEL_MIN", "beam_lut", "run_step", "spans"]

LUT_CHUNKS = 2
"""Column ranges `beam_lut` splits a scan's model table into."""

OPENMP_MIN = 65_536
"""Particle count from which `run_step` runs numba's threaded kernels instead.

Compiled with ``parallel=True`` (some seconds the first time, so only a
filter this large pays it: `MCL.best` starts at 50,000), they keep a step
over hundreds of thousands of particles about a tenth cheaper in CPU time
than the chunks on Python threads. The same numbers either way.
"""


FILL_FIRST_MAX = 4 * NORMALS_CHUNK
"""Up to this many particles `run_step` draws the noise first, in the calling thread.

The noise is about a sixth of a particle's work; drawn first, the rest is
cut into even pieces instead of the noise's chunks of `NORMALS_CHUNK`
rows (at 10,000 particles: 8,192 and 1,808 rows, one thread doing four
fifths of the step).
"""

PIECES_PER_THREAD = 2
"""Pieces of a step per thread: a thread that another process slows takes fewer."""


def _outputs(scratch, n: int, s: int) -> tuple:
    """Arrays a fused step writes: particles (n, 3), weights (n,), and its work.

    The work arrays (heading cosines and sines (n, 2), table entries (n, s)
    int32) are used by the threaded kernels only. From ``scratch`` (a
    `robotlib.localization.motion.Scratch`) when given, else new.
    """
    if scratch is None:
        return (
            np.empty((n, 3)), np.empty(n), np.empty((n, 2)),
            np.empty((n, s), dtype=np.int32) if s else None,
        )  # fmt: skip
    return (
        scratch.take("particles", (n, 3)),
        scratch.take("weights", (n,)),
        scratch.take("cs", (n, 2)),
        scratch.take("mm", (n, s), np.int32) if s else None,
    )


def _small_outputs(scratch, n: int, u: float) -> tuple:
    """``(out_p, out_w, new_p, new_w, est)`` of a one-call step (`chunked.beam_small`).

    The moved particles (n, 3) and their weights (n,) from ``scratch`` (new
    when None), the resampled set (new: the filter keeps it) when ``u >=
    0`` (else empty), the estimate (3,) (new: the step returns it).
    """
    if scratch is None:
        out_p, out_w = np.empty((n, 3)), np.empty(n)
    else:
        out_p, out_w = scratch.take("particles", (n, 3)), scratch.take("weights", (n,))
    if u >= 0.0:
        return out_p, out_w, np.empty((n, 3)), np.empty(n), np.empty(3)
    return out_p, out_w, _NONE_P, _NONE_W, np.empty(3)


_NONE_P = np.empty((0, 3))
_NONE_W = np.empty(0)


def spans(n: int, parts: int) -> list[tuple[int, int]]:
    """Split ``range(n)`` into ``parts`` near-equal ``(lo, hi)`` ranges (none empty)."""
    parts = max(1, min(parts, n))
    edges = [n * k // parts for k in range(parts + 1)]
    return [(edges[k], edges[k + 1]) for k in range(parts)]


def _threads() -> int:
    return numba.get_num_threads()


def _run(fn, args: list) -> list:
    """Return ``[fn(*a) for a in args]``, over the pool when there are threads."""
    threads = min(_threads(), len(args))
    if threads <= 1:
        return [fn(*a) for a in args]
    pool = _executor(threads)
    return [f.result(timeout=600) for f in [pool.submit(fn, *a) for a in args]]


def beam_lut(model, n_mm: int) -> np.ndarray:
    """`_kernels.beam_scan_lut`'s table (S, n_mm), over threads."""
    lut = np.empty((len(model[0]), n_mm))

    def part(lo, hi):
        chunked.lut_part(lo, hi, *model, lut)

    _run(part, spans(n_mm, LUT_CHUNKS if n_mm >= 1024 else 1))
    return lut


def run_step(kind, particles, weights, prm, noise, key, sensors, skip, table, lut,
             out, u):  # fmt: skip
    """Move, weigh, normalise, estimate (and resample) ``particles`` in chunks.

    Parameters
    ----------
    kind : str
        ``"beam"`` (``lut``: `beam_lut`'s table, ``prm[9]`` the exponent)
        or ``"paper"`` (``lut``: the per-millimetre terms, ``prm[9] = 1/N``).
    particles, weights : numpy.ndarray, shapes (N, 3) and (N,)
        The set before the step.
    prm : numpy.ndarray, shape (10,)
        The per-step scalars (`robotlib.localization._kernels.chunked`).
    noise : numpy.ndarray, shape (N, 3)
        The motion noise; when ``key`` is given, filled here chunk by chunk
        from the streams ``SeedSequence([key, c])`` (from `OPENMP_MIN`
        particles on, drawn inside the threaded kernel and not stored).
    key : int or None
        The noise's key (`standard_normals` beyond `NORMALS_CHUNK` rows), or
        None for noise drawn already.
    sensors, skip : numpy.ndarray
        Sensor poses (S, 3) and readings whose entries are not read (S,).
    table : numpy.ndarray, shape (ny, nx, n_bins)
        The cone table; ``prm[6:9]`` its origin and ``1 / resolution``.
    out : tuple
        ``(out_p, out_w, cs, mm, new_p, new_w)``: moved particles (N, 3),
        their weights (N,), heading cosines and sines (N, 2), table entries
        (N, S) int32, and the resampled set (N, 3) and its weights (N,),
        written when ``u >= 0``.
    u : float
        The systematic resampling's draw in [0, 1), or -1 for none.

    Returns
    -------
    tuple
        ``(log_mean, ess, estimate)``.
    """
    n = len(particles)
    out_p, out_w, cs, mm, new_p, new_w = out
    if n >= OPENMP_MIN:
        return _openmp_step(kind, particles, weights, prm, noise, key, sensors, skip,
                            table, lut, out, u)  # fmt: skip
    kernel = chunked.beam_chunk if kind == "beam" else chunked.paper_chunk
    motion, where, const = (
        tuple(prm[:6].tolist()),
        tuple(prm[6:9].tolist()),
        float(prm[9]),
    )
    threads = _threads()
    if key is not None and n <= FILL_FIRST_MAX:  # the noise first, in this thread
        for c, lo in enumerate(range(0, n, NORMALS_CHUNK)):
            _fill(key, c, noise[lo : lo + NORMALS_CHUNK])
        key = None
    if key is None:  # even pieces, more than threads: a slowed thread takes fewer
        parts = [(lo, hi, -1) for lo, hi in spans(n, PIECES_PER_THREAD * threads)]
    else:  # the noise's own chunks, each drawn by the task that uses it
        parts = [
            (lo, min(lo + NORMALS_CHUNK, n), c)
            for c, lo in enumerate(range(0, n, NORMALS_CHUNK))
        ]

    def move_weigh(lo, hi, c):
        if c >= 0:
            _fill(key, c, noise[lo:hi])
        return kernel(
            particles[lo:hi], noise[lo:hi], motion, sensors, table, where, skip,
            out_p[lo:hi], cs[lo:hi], mm[lo:hi], lut, const, out_w[lo:hi],
        )  # fmt: skip

    # one task per piece, taken by whichever thread is free
    top = -np.inf
    for t in _run(move_weigh, parts):  # in order: the first of equal values
        if t > top:  # never NaN
            top = t

    def exp(lo, hi):
        chunked.exp_chunk(lo, hi, weights, top, out_w)

    _run(exp, spans(n, _threads()))
    res = chunked.finish(weights, top, out_w, out_p, cs)
    if u >= 0.0:  # kernels of their own: compiled only for filters that need them
        _gather(out_p, out_w, u, new_p, new_w)
    return res


def _openmp_step(kind, particles, weights, prm, noise, key, sensors, skip, table, lut,
                 out, u):  # fmt: skip
    """`run_step` with numba's threaded kernels (`OPENMP_MIN` particles and more)."""
    out_p, out_w, cs, mm, new_p, new_w = out
    motion, where = tuple(prm[:6].tolist()), tuple(prm[6:9].tolist())
    if key is not None:  # the noise drawn in the kernel's first pass
        if kind == "beam":
            res = _kernels.lut_table_step_keyed_parallel(
                particles, key, NORMALS_CHUNK, motion, sensors, table, where, lut,
                skip, float(prm[9]), weights, out_p, out_w, cs, mm,
            )  # fmt: skip
        else:
            res = _kernels.paper_lut_step_keyed_parallel(
                particles, key, NORMALS_CHUNK, motion, sensors, table, where, lut,
                float(prm[9]), weights, out_p, out_w, cs, mm,
            )  # fmt: skip
    elif kind == "beam":
        res = _kernels.lut_table_step_parallel(
            particles, noise, motion, sensors, table, where, lut, skip, float(prm[9]),
            weights, out_p, out_w, cs, mm,
        )  # fmt: skip
    else:
        res = _kernels.paper_lut_step_parallel(
            particles, noise, motion, sensors, table, where, lut, float(prm[9]),
            weights, out_p, out_w, cs, mm,
        )  # fmt: skip
    if u >= 0.0:
        _gather(out_p, out_w, u, new_p, new_w)
    return res


def _gather(particles, weights, u, new_p, new_w):
    """`resample.systematic_gather` into ``new_p``, then ``new_w`` set to ``1 / n``.

    The cumulative weights (summed serially: the same bits) are kept in
    ``new_w``; from `OPENMP_MIN` particles the rows are gathered in even
    pieces over the threads (`chunked.gather_rows`). Below, one call: at
    10,000 particles the gather takes 0.04 ms, and handing out pieces
    doubled it.
    """
    chunked.cumulate(weights, new_w)
    n = len(new_p)
    if n < OPENMP_MIN:
        chunked.gather_rows(particles, new_w, u, 0, n, new_p)
    else:

        def rows(lo, hi):
            chunked.gather_rows(particles, new_w, u, lo, hi, new_p)

        _run(rows, spans(n, _threads()))
    new_w.fill(1.0 / n)
