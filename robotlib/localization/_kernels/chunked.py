"""The fused MCL step in pieces a pool of Python threads runs: no OpenMP.

A step over many particles is cut into chunks of rows; each chunk is a
call of `fused.move_and_read` (serial, ``nogil``) on its rows and one of
`beam_rows` or `paper_rows`, and the calls run on the threads of
`robotlib.localization.stepping`. Serial kernels compile in a fraction of
the time numba's ``parallel=True`` takes, and a thread with no chunk left
waits on a lock instead of spinning, which keeps a step steady when
another process shares the cores. A few particles take one call
(`beam_small`, `paper_small`), resampling included.

The numbers are those of `robotlib.localization._kernels.fused` bit for bit:
each particle's arithmetic is the same in the same order, the largest
log-likelihood is the same whichever way the chunks split (the first of
equal values wins, NaN never), and every sum runs serially in `finish`.

`beam_small` and `paper_small` take their scalars one by one: numba unboxes
a float argument faster than NumPy builds an array of them.

Numba kernels: contiguous arrays and scalars in, no Python objects; they
import nothing of robotlib but the JIT options and other kernels.
"""

import numba as nb
import numpy as np

from ..._config import JIT, jit_inner
from .by_reading import (
    beam_loglik_by_reading,
    move_and_read_by_reading,
    paper_loglik_by_reading,
)
from .elementary import exp
from .fused import _top, log_rows, lut_products, move_and_read, paper_rows_log
from .pcg64 import fill_normals, next_double
from .weights import _finish_estimate


@jit_inner
def beam_rows(mm, lut, exponent, out_w):
    """Beam log-likelihoods from looked-up entries ``mm`` (n, S) into ``out_w`` (n,).

    As the last pass of `fused.lut_table_step_parallel` (``lut`` from
    `beam_scan_lut`, times ``exponent``). Returns the largest.
    """
    n = mm.shape[0]
    ll = np.empty(n)
    lut_products(lut, mm, 0, n, ll, out_w)
    log_rows(0, n, ll, exponent, out_w)
    return _top(out_w)


@jit_inner
def paper_rows(mm, terms, inv_n, out_w):
    """As `beam_rows` with the paper's model (`fused.paper_lut_step_parallel`)."""
    paper_rows_log(terms, mm, 0, mm.shape[0], inv_n, out_w)
    return _top(out_w)


@nb.njit(**JIT)
def beam_chunk(particles, normals, motion, sensors, table, where, skip, out_p, cs, mm,
               lut, exponent, out_w):  # fmt: skip
    """`fused.move_and_read` then `beam_rows` on one chunk's rows: one call."""
    move_and_read(
        particles, normals, motion, sensors, table, where, skip, out_p, cs, mm
    )
    return beam_rows(mm, lut, exponent, out_w)


@nb.njit(**JIT)
def paper_chunk(particles, normals, motion, sensors, table, where, skip, out_p, cs, mm,
                terms, inv_n, out_w):  # fmt: skip
    """`fused.move_and_read` then `paper_rows` on one chunk's rows: one call."""
    move_and_read(
        particles, normals, motion, sensors, table, where, skip, out_p, cs, mm
    )
    return paper_rows(mm, terms, inv_n, out_w)


@nb.njit(**JIT)
def exp_chunk(lo, hi, weights, top, out_w):
    """``out_w[j] = weights[j] exp(out_w[j] - top)`` for rows ``lo:hi``."""
    for j in range(lo, hi):
        out_w[j] = weights[j] * exp(out_w[j] - top)


@nb.njit(**JIT)
def lut_part(lo, hi, z, e_short, is_max, hit, short, z_max, p_rand, inv_sigma, lut):
    """Columns ``lo:hi`` of `beam_scan_lut`'s table (the same entries).

    `_beam_mm` with each reading's values read once (a store to ``lut``
    could alias them: read in the loop, they are read again each time).
    """
    for i in range(lut.shape[0]):
        if is_max[i]:
            for mm in range(lo, hi):
                lut[i, mm] = z_max
            continue
        zi = z[i]
        ei = e_short[i]
        for mm in range(lo, hi):
            zhat = mm * 0.001
            u = (zi - zhat) * inv_sigma
            p = hit[mm] * exp(-0.5 * u * u) + p_rand
            if zi <= zhat:
                p += short[mm] * ei
            lut[i, mm] = p


@nb.njit(**JIT)
def finish(weights, top, out_w, out_p, cs):
    """Normalise and estimate: the serial end of a step.

    ``out_w`` holds the updated, unnormalised weights (`exp_chunk`); they
    are normalised in place (`update_weights`) and the pose estimated
    (`weighted_pose_mean`). Returns ``(log_mean, ess, estimate)``. The
    resampling a step may end with is the caller's (`cumulate`, then
    `gather_rows` in pieces): a filter that does not resample every step
    compiles no gathering.
    """
    est = np.empty(3)
    log_mean, ess, _ = _finish_estimate(weights, top, out_w, out_p, cs, est, out_w[:0])
    return log_mean, ess, est


@nb.njit(**JIT, inline="always")
def _finish_into(weights, top, out_w, out_p, cs, u, new_p, new_w, est):
    """`finish`, the estimate written into ``est``; returns ``(log_mean, ess)``.

    One pass normalises, estimates and (``u >= 0``) keeps the cumulative
    weights in ``new_w`` for the resampling, which then overwrites them.
    """
    cum = new_w if u >= 0.0 else new_w[:0]
    log_mean, ess, total = _finish_estimate(weights, top, out_w, out_p, cs, est, cum)
    if u >= 0.0:
        _gather_cum(out_p, cum, total, u, new_p)
        n = new_p.shape[0]
        for k in range(n):
            new_w[k] = 1.0 / n
    return log_mean, ess


@nb.njit(**JIT, inline="always")
def _gather_cum(particles, cum, total, u, out):
    """`resample.systematic_gather` from the running sums ``cum`` (N,) of the weights.

    ``total`` is the last. ``cum`` becomes the quotients ``cum[j] / total``,
    `resample.cumulative`'s entries (its last, forced to 1, is never read),
    so the rows are the same.
    """
    _quotients(cum, total)
    _gather_rows(particles, cum, u, 0, out.shape[0], out)


@nb.njit(**JIT, inline="always")
def _quotients(cum, total):
    """``cum[j] /= total``: independent divisions, none on the walk's path."""
    for j in range(cum.shape[0]):
        cum[j] = cum[j] / total


@nb.njit(**JIT, inline="always")
def _gather_rows(particles, q, u, lo, hi, out):
    """Rows ``lo:hi`` of `_gather_cum`'s set: the walk started where it reaches ``lo``.

    ``q`` (N,) holds the cumulative weights' quotients. The walk stops at
    row ``k`` on the first ``j`` where ``q[j] <= (k + u) / n`` fails (the
    last ``j`` if none); that test never passes again once it fails (``q``
    never decreases, and is all NaN when the weights sum to 0 or NaN), so a
    bisection finds the ``j`` of row ``lo`` and the rows from there are
    those of the whole walk.
    """
    n_q = q.shape[0]
    n = out.shape[0]
    j = 0
    last = n_q - 1
    position = (lo + u) / n
    while j < last:
        mid = (j + last) // 2
        if not q[mid] <= position:  # the walk's own test: NaN quotients stop it
            last = mid
        else:
            j = mid + 1
    for k in range(lo, hi):
        position = (k + u) / n
        while j < n_q - 1 and q[j] <= position:
            j += 1
        out[k, 0] = particles[j, 0]
        out[k, 1] = particles[j, 1]
        out[k, 2] = particles[j, 2]


@nb.njit(**JIT)
def cumulate(weights, q):
    """Write the cumulative weights' quotients into ``q`` (N,), as `_gather_cum` does.

    The running sums of ``weights`` (N,), serially, each divided by the last.
    """
    total = 0.0
    for j in range(weights.shape[0]):
        total += weights[j]
        q[j] = total
    _quotients(q, total)


@nb.njit(**JIT)
def gather_rows(particles, q, u, lo, hi, out):
    """Rows ``lo:hi`` of `resample.systematic_gather`'s set into ``out`` (n, 3).

    From `cumulate`'s quotients ``q`` (`_gather_rows`): pieces of rows run
    on threads give the rows of one serial walk.
    """
    _gather_rows(particles, q, u, lo, hi, out)


# -- a few particles: the whole step in one call -------------------------------------


@nb.njit(**JIT, inline="always")
def _weigh_into(weights, out_p, cs, out_w, u, new_p, new_w, est):
    """`fused._weigh_estimate` then (``u >= 0``) `finish`'s resampling, into ``est``."""
    top = -np.inf
    for j in range(out_w.shape[0]):
        if out_w[j] > top:
            top = out_w[j]
    for j in range(out_w.shape[0]):
        out_w[j] = weights[j] * exp(out_w[j] - top)
    return _finish_into(weights, top, out_w, out_p, cs, u, new_p, new_w, est)


@nb.njit(**JIT, inline="always")
def _refused(z):
    """Whether a reading of ``z`` (S,) is not positive (NaN included)."""
    for i in range(z.shape[0]):
        if not z[i] > 0.0:
            return True
    return False


@nb.njit(**JIT, inline="always")
def _draw(words, draw, noise, u):
    """With ``draw``: ``noise`` := the PCG64's normals, then (``u >= 0``) ``u``.

    The draws `MCL.step` makes before the call, in the same order, as
    ``Generator.standard_normal(out=noise)`` and ``Generator.random()``
    (`robotlib.localization._kernels.pcg64`). Returns ``u``.
    """
    if draw:
        fill_normals(words, noise)
        if u >= 0.0:
            u = next_double(words)
    return u


@nb.njit(**JIT)
def beam_small(words, draw, particles, weights, noise, sensors, table, z, e_short,
               hit, short, rot1, trans, rot2, sd1, sdt, sd2, x0, y0, inv_res, exponent,
               max_read, z_max, p_rand, inv_sigma, u2_skip, u, out_p, out_w, new_p,
               new_w, est):  # fmt: skip
    """`by_reading.beam_table_step`, then (``u >= 0``) resampling as in `finish`.

    The same passes. The scalars come one
    by one (cheaper to pass than an array built per step): the motion
    ``(rot1 .. sd2)``, the table's ``(x0, y0, inv_res)``, the beam model's
    ``exponent``, ``max_read`` (readings from it on are max readings, as
    `BeamSensorModel._model`'s ``is_max``), ``z_max, p_rand, inv_sigma,
    u2_skip``, and the resampling draw ``u``. The estimate goes to ``est``
    (3,); returns ``(log_mean, ess)``.

    With ``draw``, the call makes the filter's draws itself from its PCG64
    state ``words`` (4,) uint64 (`_draw`): ``noise`` (N, 3) receives the
    motion noise and, when ``u >= 0``, ``u`` is drawn after it. Otherwise
    ``noise`` and ``u`` are the caller's (``words`` unused).

    A scan ``z`` with a reading not positive (or NaN) is refused first:
    nothing drawn or written, ``(nan, -1.0)`` returned.
    """
    if _refused(z):
        return np.nan, -1.0
    u = _draw(words, draw, noise, u)
    n = particles.shape[0]
    s_count = sensors.shape[0]
    is_max = np.empty(s_count, dtype=np.bool_)
    for i in range(s_count):
        is_max[i] = z[i] >= max_read
    cs = np.empty((n, 2))
    kt = move_and_read_by_reading(
        particles, noise, (rot1, trans, rot2, sd1, sdt, sd2), sensors, table,
        (x0, y0, inv_res), is_max, out_p, cs,
    )  # fmt: skip
    beam_loglik_by_reading(
        kt, z, e_short, is_max, hit, short, z_max, p_rand, inv_sigma, exponent,
        u2_skip, out_w,
    )  # fmt: skip
    return _weigh_into(weights, out_p, cs, out_w, u, new_p, new_w, est)


@nb.njit(**JIT)
def paper_small(words, draw, particles, weights, noise, sensors, table, z, rot1,
                trans, rot2, sd1, sdt, sd2, x0, y0, inv_res, inv_n, u, out_p, out_w,
                new_p, new_w, est):  # fmt: skip
    """`by_reading.paper_table_step`, then (``u >= 0``) resampling, as `beam_small`.

    A refused scan as there: ``(nan, -1.0)``.
    """
    if _refused(z):
        return np.nan, -1.0
    u = _draw(words, draw, noise, u)
    n = particles.shape[0]
    skip = np.zeros(sensors.shape[0], dtype=np.bool_)
    cs = np.empty((n, 2))
    kt = move_and_read_by_reading(
        particles, noise, (rot1, trans, rot2, sd1, sdt, sd2), sensors, table,
        (x0, y0, inv_res), skip, out_p, cs,
    )  # fmt: skip
    paper_loglik_by_reading(kt, z, inv_n, out_w)
    return _weigh_into(weights, out_p, cs, out_w, u, new_p, new_w, est)
