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

``prm`` packs a step's scalars into one float64 array (one argument is
cheaper to pass than a dozen tuples): ``(rot1, trans, rot2, sd1, sdt, sd2,
x0, y0, inv_res, c)`` with ``c`` the beam model's exponent or the paper's
``1/N``, then for `beam_small` ``(z_max, p_rand, inv_sigma, u2_skip)``.

Numba kernels: contiguous arrays and scalars in, no Python objects; they
import nothing of robotlib but the JIT options and other kernels.
"""

import math

import numba as nb
import numpy as np

from ..._config import JIT
from .fused import (
    _beam_mm_row,
    _buffers,
    _paper_mm,
    _weigh_estimate,
    move_and_read,
)
from .resample import systematic_gather
from .weights import _finish_weights, _pose_mean


@nb.njit(**JIT)
def beam_rows(mm, lut, exponent, out_w):
    """Beam log-likelihoods from looked-up entries ``mm`` (n, S) into ``out_w`` (n,).

    As the last pass of `fused.lut_table_step_parallel` (``lut`` from
    `beam_scan_lut`, times ``exponent``). Returns the largest.
    """
    top = -np.inf
    for j in range(mm.shape[0]):
        ll = 0.0
        prod = 1.0
        for i in range(mm.shape[1]):
            if i % 16 == 15:
                ll += math.log(prod)
                prod = 1.0
            prod *= lut[i, mm[j, i]]
        v = (ll + math.log(prod)) * exponent
        out_w[j] = v
        if v > top:
            top = v
    return top


@nb.njit(**JIT)
def paper_rows(mm, terms, inv_n, out_w):
    """As `beam_rows` with the paper's model (`fused.paper_lut_step_parallel`)."""
    s_count = mm.shape[1]
    top = -np.inf
    for j in range(mm.shape[0]):
        d = 0.0
        for i in range(s_count):
            d += terms[i, mm[j, i]]
        v = math.log(math.exp(-d / s_count) + inv_n)
        out_w[j] = v
        if v > top:
            top = v
    return top


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
        out_w[j] = weights[j] * math.exp(out_w[j] - top)


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
            p = hit[mm] * math.exp(-0.5 * u * u) + p_rand
            if zi <= zhat:
                p += short[mm] * ei
            lut[i, mm] = p


@nb.njit(**JIT)
def finish(weights, top, out_w, out_p, cs):
    """Normalise and estimate: the serial end of a step.

    ``out_w`` holds the updated, unnormalised weights (`exp_chunk`); they
    are normalised in place (`update_weights`) and the pose estimated
    (`weighted_pose_mean`). Returns ``(log_mean, ess, estimate)``. The
    resampling a step may end with is the caller's (`resample.systematic_gather`
    then): a filter that does not resample every step compiles no gathering.
    """
    log_mean, ess = _finish_weights(weights, top, out_w)
    return log_mean, ess, _pose_mean(out_p, out_w, cs)


@nb.njit(**JIT, inline="always")
def _gather_into(particles, weights, u, new_p, new_w):
    """`resample.systematic_gather` into ``new_p``, and uniform weights."""
    systematic_gather(particles, weights, u, new_p)
    n = new_p.shape[0]
    for k in range(n):
        new_w[k] = 1.0 / n


# -- a few particles: the whole step in one call -------------------------------------


_beam_row = nb.njit(**JIT, inline="always")(_beam_mm_row.py_func)
_paper_row = nb.njit(**JIT, inline="always")(_paper_mm.py_func)


@nb.njit(**JIT)
def beam_small(particles, normals, prm, sensors, table, z, e_short, is_max, hit, short,
               weights, out_p, out_w, u, new_p, new_w):  # fmt: skip
    """`fused.beam_table_step`, then (``u >= 0``) resampling as in `finish`.

    The same passes, with the per-particle model written in (a call per
    particle costs about as much as its arithmetic). ``prm[10:14]`` is
    ``(z_max, p_rand, inv_sigma, u2_skip)``.
    """
    n = particles.shape[0]
    cs, mm = _buffers(n, sensors.shape[0])
    move_and_read(
        particles, normals, (prm[0], prm[1], prm[2], prm[3], prm[4], prm[5]), sensors,
        table, (prm[6], prm[7], prm[8]), is_max, out_p, cs, mm,
    )  # fmt: skip
    z_max, p_rand, inv_sigma, exponent, u2_skip = (
        prm[10],
        prm[11],
        prm[12],
        prm[9],
        prm[13],
    )
    for j in range(n):
        _beam_row(
            j, mm, z, e_short, is_max, hit, short, z_max, p_rand, inv_sigma,
            exponent, u2_skip, out_w,
        )  # fmt: skip
    log_mean, ess, est = _weigh_estimate(weights, out_p, cs, out_w)
    if u >= 0.0:
        _gather_into(out_p, out_w, u, new_p, new_w)
    return log_mean, ess, est


@nb.njit(**JIT)
def paper_small(particles, normals, prm, sensors, table, z, weights, out_p, out_w, u,
                new_p, new_w):  # fmt: skip
    """`fused.paper_table_step`, then (``u >= 0``) resampling as in `finish`."""
    n = particles.shape[0]
    skip = np.zeros(sensors.shape[0], dtype=np.bool_)
    cs, mm = _buffers(n, sensors.shape[0])
    move_and_read(
        particles, normals, (prm[0], prm[1], prm[2], prm[3], prm[4], prm[5]), sensors,
        table, (prm[6], prm[7], prm[8]), skip, out_p, cs, mm,
    )  # fmt: skip
    inv_n = prm[9]
    for j in range(n):
        _paper_row(j, mm, z, inv_n, out_w)
    log_mean, ess, est = _weigh_estimate(weights, out_p, cs, out_w)
    if u >= 0.0:
        _gather_into(out_p, out_w, u, new_p, new_w)
    return log_mean, ess, est
