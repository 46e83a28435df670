"""The fused MCL steps: predict, read the cone table, weigh, normalise and estimate.

Numba kernels: contiguous arrays and scalars in, no Python objects; they
import nothing of robotlib but the JIT options and other kernels.
"""

import numba as nb
import numpy as np

from ..._config import JIT, JIT_PARALLEL, serial_and_parallel
from .common import _TWO_PI
from .elementary import exp, log, sincos
from .motion import odometry_pose
from .normals import fill, sfc64_state
from .weights import _finish_estimate


@nb.njit(**JIT, inline="always")
def _flat_index(sx, sy, a, ny, nx, n_bins, x0, y0, inv_res):
    """`table_bin`'s cell and bin as one flat index, without a branch.

    ``(sx, sy)`` is the sensor's position and ``a`` its heading times
    ``n_bins / (2 pi)``. The clamps and the bin's wrap are done on floats
    (exact on these whole numbers), as selects a vector lane can run; NaN
    and out-of-grid positions land on the edge, so the index is always in
    the table. For every position within the grid's reach (|x|, |y| below
    2^52 cells) it is `table_bin`'s cell and bin.
    """
    fc = np.floor((sx - x0) * inv_res)
    fr = np.floor((sy - y0) * inv_res)
    fb = np.floor(a + 0.5)
    last_c = nx - 1.0
    last_r = ny - 1.0
    fn = float(n_bins)
    fc = fc if fc > 0.0 else 0.0
    fc = fc if fc < last_c else last_c
    fr = fr if fr > 0.0 else 0.0
    fr = fr if fr < last_r else last_r
    fb = fb - fn * np.floor(fb / fn)  # b mod n_bins, on whole numbers
    fb = fb if fb > 0.0 else 0.0
    fb = fb if fb < fn - 1.0 else fn - 1.0
    # np.int64, not int(): the same truncation, and no int() for numba to compile
    return np.int32((np.int64(fr) * nx + np.int64(fc)) * n_bins + np.int64(fb))


# -- one fused step: predict, weigh, normalise, estimate ---------------------------
#
# `MCL.step` on a cone table in one call: each particle is moved
# (`sample_odometry`), weighed by the table model from the cosine and sine of
# its new heading, which the estimate reuses; then the weights are updated
# and normalised (`update_weights`) and the pose estimated
# (`weighted_pose_mean`). Same numbers as those kernels one after the other.
# ``motion`` is ``(rot1, trans, rot2, sd1, sdt, sd2)``, ``where`` the table's
# ``(x0, y0, inv_res)``; ``out_p`` (N, 3) receives the moved particles and
# ``out_w`` (N,) their weights. Each returns ``(log_mean, ess, estimate)``.


@nb.njit(**JIT)
def _top(loglik):
    top = -np.inf
    for j in range(loglik.shape[0]):
        if loglik[j] > top:
            top = loglik[j]
    return top


def _weigh_estimate(weights, particles, cs, out_w):
    """`update_weights` with ``out_w`` holding log-likelihoods, then the estimate."""
    top = _top(out_w)
    for j in nb.prange(out_w.shape[0]):
        out_w[j] = weights[j] * exp(out_w[j] - top)
    est = np.empty(3)
    no_cum = np.empty(0)
    log_mean, ess, _ = _finish_estimate(weights, top, out_w, particles, cs, est, no_cum)
    return log_mean, ess, est


_weigh_estimate, _weigh_estimate_parallel = serial_and_parallel(_weigh_estimate)


@nb.njit(**JIT, inline="always")
def _sensor_columns(sensors, skip):
    """Return the sensors' (S, 3) columns as contiguous arrays and a read mask.

    Returns ``(x, y, angle, keep)``: each (S,), ``keep[i]`` int32 0 where
    ``skip[i]`` (the index is zeroed: not read) and -1 (all bits) elsewhere.
    """
    s_count = sensors.shape[0]
    ax = np.empty(s_count)
    ay = np.empty(s_count)
    aa = np.empty(s_count)
    keep = np.empty(s_count, dtype=np.int32)
    for i in range(s_count):
        ax[i] = sensors[i, 0]
        ay[i] = sensors[i, 1]
        aa[i] = sensors[i, 2]
        keep[i] = 0 if skip[i] else -1
    return ax, ay, aa, keep


BLOCK = 512
"""Rows a threaded move takes at a time: its columns stay in the core's cache."""


@nb.njit(**JIT, inline="always")
def move_columns(lo, m, particles, xs, ys, ths, n1, nt, n2, motion, out_p, cs):
    """Move rows ``lo:lo + m`` of ``particles`` (`odometry_pose`) as columns.

    ``n1, nt, n2`` (at least m,) hold the rows' motion noise; ``xs, ys,
    ths`` (at least m,) are scratch. The moved rows go to ``out_p`` and their
    headings' cosines and sines to ``cs``, as `sample_odometry` and
    `weights.weighted_pose_mean` compute them; on return ``xs, ys, ths``
    hold the moved poses and ``n1, nt`` the cosines and sines (the noise
    is used up). Loops over contiguous columns, which the compiler runs on
    vector lanes (`elementary`'s ``sincos``).
    """
    rot1, trans, rot2, sd1, sdt, sd2 = motion
    for b in range(m):
        xs[b] = particles[lo + b, 0]
        ys[b] = particles[lo + b, 1]
        ths[b] = particles[lo + b, 2]
    for b in range(m):
        x, y, th = odometry_pose(
            xs[b], ys[b], ths[b], n1[b], nt[b], n2[b], rot1, trans, rot2, sd1, sdt,
            sd2,
        )  # fmt: skip
        xs[b] = x
        ys[b] = y
        ths[b] = th
        nt[b], n1[b] = sincos(th)  # each noise slot read before it is written
    for b in range(m):
        out_p[lo + b, 0] = xs[b]
        out_p[lo + b, 1] = ys[b]
        out_p[lo + b, 2] = ths[b]
        cs[lo + b, 0] = n1[b]
        cs[lo + b, 1] = nt[b]


@nb.njit(**JIT, inline="always")
def _index_rows(lo, m, xs, ys, ths, cc, ss, columns, table, where, mm):
    """Rows ``lo:lo + m`` of ``mm`` (N, S): each sensor's flat table index.

    From the moved poses ``xs, ys, ths`` and headings' cosines ``cc`` and
    sines ``ss`` of `move_columns`; ``columns`` is `_sensor_columns`'.
    """
    ax, ay, aa, keep = columns
    x0, y0, inv_res = where
    ny, nx, n_bins = table.shape
    bins = n_bins / _TWO_PI
    for b in range(m):
        row = mm[lo + b]
        x = xs[b]
        y = ys[b]
        th = ths[b]
        c = cc[b]
        s = ss[b]
        for i in range(ax.shape[0]):
            row[i] = keep[i] & _flat_index(
                x + c * ax[i] - s * ay[i], y + s * ax[i] + c * ay[i],
                (th + aa[i]) * bins, ny, nx, n_bins, x0, y0, inv_res,
            )  # fmt: skip


def _move_and_read(
    particles, normals, motion, sensors, table, where, skip, out_p, cs, mm
):  # fmt: skip
    """Move every particle, then read its sensors' cone-table entries.

    Passes one and two of a fused step. Pass one moves particle ``j`` into
    ``out_p[j]`` (as `sample_odometry`), keeps the cosine and sine of its new
    heading in ``cs[j]`` (N, 2) and its sensors' flat table indexes (the cell
    and bin of `table_bin`; 0 where ``skip[i]``: not read) in ``mm[j]`` (N, S)
    int32 (`ConeTable` keeps below 2^31 entries), `BLOCK` rows at a time
    (`move_columns`). Pass two replaces each index by the table's entry
    (mm): independent reads the processor overlaps, the table being larger
    than its caches. Every helper is inlined: a call per particle inside the
    threaded loop costs more than the particle's arithmetic. The sensors'
    loop has no branch (`_flat_index`), so the compiler runs it on vector
    lanes.
    """
    columns = _sensor_columns(sensors, skip)
    n = particles.shape[0]
    for blk in nb.prange((n + BLOCK - 1) // BLOCK):
        lo = blk * BLOCK
        m = min(BLOCK, n - lo)
        xs, ys, ths = np.empty(m), np.empty(m), np.empty(m)
        n1, nt, n2 = np.empty(m), np.empty(m), np.empty(m)
        for b in range(m):
            n1[b] = normals[lo + b, 0]
            nt[b] = normals[lo + b, 1]
            n2[b] = normals[lo + b, 2]
        move_columns(lo, m, particles, xs, ys, ths, n1, nt, n2, motion, out_p, cs)
        _index_rows(lo, m, xs, ys, ths, n1, nt, columns, table, where, mm)
    flat = table.reshape(table.size)
    for j in nb.prange(n):
        for i in range(mm.shape[1]):
            mm[j, i] = flat[mm[j, i]]


move_and_read, move_and_read_parallel = serial_and_parallel(_move_and_read, inner=True)


@nb.njit(**JIT_PARALLEL)
def move_and_read_keyed_parallel(
    particles, key, rows, motion, sensors, table, where, skip, out_p, cs, mm
):  # fmt: skip
    """`move_and_read_parallel` drawing its own motion noise, chunk by chunk.

    The noise of rows ``c * rows`` on is chunk ``c`` of the step keyed
    ``key`` (`normals.fill_chunks`: `motion.standard_normals`' numbers),
    drawn by the thread that uses it instead of stored for the step: the
    threads take whole chunks, each drawn into a buffer of its own in one
    loop (`normals.fill`) and then used, `BLOCK` rows at a time. The same
    numbers as `move_and_read_parallel` on `normals.fill_chunks`' noise.
    """
    columns = _sensor_columns(sensors, skip)
    n = particles.shape[0]
    n_chunks = (n + rows - 1) // rows
    for ch in nb.prange(n_chunks):
        st = np.empty(4, dtype=np.uint64)
        sfc64_state(key, ch, st)
        lo = ch * rows
        hi = min(lo + rows, n)
        draws = np.empty(3 * (hi - lo))  # the chunk's noise, drawn in one loop
        fill(st, draws)
        xs, ys, ths = np.empty(BLOCK), np.empty(BLOCK), np.empty(BLOCK)
        n1, nt, n2 = np.empty(BLOCK), np.empty(BLOCK), np.empty(BLOCK)
        for start in range(lo, hi, BLOCK):
            m = min(BLOCK, hi - start)
            d = 3 * (start - lo)
            for b in range(m):
                n1[b] = draws[d + 3 * b]
                nt[b] = draws[d + 3 * b + 1]
                n2[b] = draws[d + 3 * b + 2]
            move_columns(
                start, m, particles, xs, ys, ths, n1, nt, n2, motion, out_p, cs
            )
            _index_rows(start, m, xs, ys, ths, n1, nt, columns, table, where, mm)
    flat = table.reshape(table.size)
    for j in nb.prange(n):
        for i in range(mm.shape[1]):
            mm[j, i] = flat[mm[j, i]]


@nb.njit(**JIT, inline="always")
def lut_products(lut, mm, lo, m, ll, out_w):
    """Rows ``lo:lo + m``' products of ``lut[i, mm[j, i]]``, 16 factors at a time.

    ``out_w[j]`` receives the last product and ``ll[j - lo]`` the sum of
    the logs of the others (0 below 16 readings): the log-likelihood is
    then ``ll + log(out_w)`` (`log_rows`), in one loop of logs the compiler
    runs on vector lanes.
    """
    for b in range(m):
        j = lo + b
        acc = 0.0
        prod = 1.0
        for i in range(mm.shape[1]):
            if i % 16 == 15:
                acc += log(prod)
                prod = 1.0
            prod *= lut[i, mm[j, i]]
        ll[b] = acc
        out_w[j] = prod


@nb.njit(**JIT, inline="always")
def log_rows(lo, m, ll, exponent, out_w):
    """``out_w[j] = (ll[j - lo] + log(out_w[j])) * exponent`` for rows ``lo:lo + m``."""
    for b in range(m):
        out_w[lo + b] = (ll[b] + log(out_w[lo + b])) * exponent


@nb.njit(**JIT_PARALLEL)
def _lut_weigh_parallel(lut, mm, exponent, out_w):
    """Each particle's beam log-likelihood from its table entries, over threads.

    ``out_w[j]`` for row ``mm[j]`` (N, S) int32 of millimetres: the logs of
    products of 16 of ``lut[i, mm]``, times ``exponent`` (`lut_products`,
    `log_rows`), `BLOCK` rows at a time.
    """
    n = mm.shape[0]
    for blk in nb.prange((n + BLOCK - 1) // BLOCK):
        lo = blk * BLOCK
        m = min(BLOCK, n - lo)
        ll = np.empty(m)
        lut_products(lut, mm, lo, m, ll, out_w)
        log_rows(lo, m, ll, exponent, out_w)


@nb.njit(**JIT, inline="always")
def paper_rows_log(terms, mm, lo, m, inv_n, out_w):
    """Rows ``lo:lo + m`` of ``out_w``: ``log(exp(-mean_i terms[i, mm_ji]) + inv_n)``.

    The sums first (table reads), then the exponentials and logs in a loop
    of their own, which the compiler runs on vector lanes.
    """
    s_count = mm.shape[1]
    for b in range(m):
        d = 0.0
        for i in range(s_count):
            d += terms[i, mm[lo + b, i]]
        out_w[lo + b] = d
    for b in range(m):
        out_w[lo + b] = log(exp(-out_w[lo + b] / s_count) + inv_n)


@nb.njit(**JIT_PARALLEL)
def _paper_weigh_parallel(terms, mm, inv_n, out_w):
    """Each particle's paper log-weight from its table entries, over threads.

    ``out_w[j]`` is ``log(exp(-mean_i terms[i, mm[j, i]]) + inv_n)``, as
    `by_reading.paper_table_step` weighs a particle (``terms``:
    `paper_lut_step_parallel`'s), `BLOCK` rows at a time.
    """
    n = mm.shape[0]
    for blk in nb.prange((n + BLOCK - 1) // BLOCK):
        lo = blk * BLOCK
        paper_rows_log(terms, mm, lo, min(BLOCK, n - lo), inv_n, out_w)


@nb.njit(**JIT)  # its passes are threaded kernels
def paper_lut_step_parallel(
    particles, normals, motion, sensors, table, where, terms, inv_n, weights, out_p,
    out_w, cs, mm,
):  # fmt: skip
    """`paper_table_step` over threads, each term read from a table (same result).

    ``terms[i, k]`` is ``|(z_i - k / 1000) / z_i|`` for every millimetre ``k``
    a table entry can hold (as `beam_scan_lut` for the beam model): a lookup
    instead of a division per beam. Sums serial. ``cs`` (N, 2) and ``mm``
    (N, S) int32 are scratch (`move_and_read`), kept by the caller.
    """
    s_count = sensors.shape[0]
    skip = np.zeros(s_count, dtype=np.bool_)
    move_and_read_parallel(
        particles, normals, motion, sensors, table, where, skip, out_p, cs, mm
    )
    _paper_weigh_parallel(terms, mm, inv_n, out_w)
    return _weigh_estimate_parallel(weights, out_p, cs, out_w)


@nb.njit(**JIT)  # its passes are threaded kernels
def lut_table_step_parallel(
    particles, normals, motion, sensors, table, where, lut, skip, exponent, weights,
    out_p, out_w, cs, mm,
):  # fmt: skip
    """Fused step with the beam model read from `beam_scan_lut`'s table, over threads.

    The same numbers as `beam_table_step`; ``skip`` marks the max readings
    (``lut[i]`` is constant there: the table is not read). ``cs`` and ``mm``
    are scratch, as for `paper_lut_step_parallel`.
    """
    move_and_read_parallel(
        particles, normals, motion, sensors, table, where, skip, out_p, cs, mm
    )
    _lut_weigh_parallel(lut, mm, exponent, out_w)
    return _weigh_estimate_parallel(weights, out_p, cs, out_w)


@nb.njit(**JIT)  # its passes are threaded kernels
def lut_table_step_keyed_parallel(
    particles, key, rows, motion, sensors, table, where, lut, skip, exponent,
    weights, out_p, out_w, cs, mm,
):  # fmt: skip
    """`lut_table_step_parallel` drawing its noise (`move_and_read_keyed_parallel`).

    The same numbers as `lut_table_step_parallel` on the noise of
    `normals.fill_chunks` (``key``, chunks of ``rows`` rows), which is not
    stored: one pass less over memory and no threaded pass of its own.
    """
    move_and_read_keyed_parallel(
        particles, key, rows, motion, sensors, table, where, skip, out_p, cs, mm
    )
    _lut_weigh_parallel(lut, mm, exponent, out_w)
    return _weigh_estimate_parallel(weights, out_p, cs, out_w)


@nb.njit(**JIT)  # its passes are threaded kernels
def paper_lut_step_keyed_parallel(
    particles, key, rows, motion, sensors, table, where, terms, inv_n, weights,
    out_p, out_w, cs, mm,
):  # fmt: skip
    """`paper_lut_step_parallel` drawing its noise (see the beam one's)."""
    s_count = sensors.shape[0]
    skip = np.zeros(s_count, dtype=np.bool_)
    move_and_read_keyed_parallel(
        particles, key, rows, motion, sensors, table, where, skip, out_p, cs, mm
    )
    _paper_weigh_parallel(terms, mm, inv_n, out_w)
    return _weigh_estimate_parallel(weights, out_p, cs, out_w)
