"""The serial fused steps' passes, laid out reading by reading for vector lanes.

`fused.move_and_read` keeps each particle's table entries in a row (N, S),
as the threaded steps want them. A serial step over a few hundred
particles runs quicker with the entries of one reading side by side
(S, N): each pass is then a long loop over the particles, with no branch
and contiguous operands, which the compiler runs on vector lanes (a loop
over a particle's eight readings is too short for them). The numbers are
the same as `fused`'s row by row: each particle's arithmetic is the same,
in the same order (the products and sums over a particle's readings run
in reading order).

Numba kernels: contiguous arrays and scalars in, no Python objects; they
import nothing of robotlib but the JIT options and other kernels.
"""

import numba as nb
import numpy as np

from ..._config import JIT
from .common import _TWO_PI
from .elementary import exp, log
from .fused import _flat_index, _sensor_columns, _weigh_estimate, move_columns


@nb.njit(**JIT)
def move_and_read_by_reading(
    particles, normals, motion, sensors, table, where, skip, out_p, cs
):  # fmt: skip
    """`fused.move_and_read`, returning the entries as ``kt`` (S, N) int32.

    The same moved particles ``out_p`` (N, 3), heading cosines and sines
    ``cs`` (N, 2) and table entries (``kt[i, j]`` is `fused.move_and_read`'s
    ``mm[j, i]``: 0 where ``skip[i]``), in three passes over the particles:
    move, then each reading's flat table index, then the table reads.
    """
    x0, y0, inv_res = where
    ny, nx, n_bins = table.shape
    s_count = sensors.shape[0]
    n = particles.shape[0]
    ax, ay, aa, keep = _sensor_columns(sensors, skip)
    bins = n_bins / _TWO_PI
    xs, ys, ths = np.empty(n), np.empty(n), np.empty(n)
    cc, ss, n2 = np.empty(n), np.empty(n), np.empty(n)
    for j in range(n):  # the noise as columns; cc and ss receive cos and sin
        cc[j] = normals[j, 0]
        ss[j] = normals[j, 1]
        n2[j] = normals[j, 2]
    move_columns(0, n, particles, xs, ys, ths, cc, ss, n2, motion, out_p, cs)
    kt = np.empty((s_count, n), dtype=np.int32)
    for i in range(s_count):
        ki = kt[i]
        axi = ax[i]
        ayi = ay[i]
        aai = aa[i]
        kpi = keep[i]
        for j in range(n):
            ki[j] = kpi & _flat_index(
                xs[j] + cc[j] * axi - ss[j] * ayi, ys[j] + ss[j] * axi + cc[j] * ayi,
                (ths[j] + aai) * bins, ny, nx, n_bins, x0, y0, inv_res,
            )  # fmt: skip
    flat = table.reshape(table.size)
    for i in range(s_count):
        ki = kt[i]
        for j in range(n):
            ki[j] = flat[ki[j]]
    return kt


@nb.njit(**JIT)
def beam_loglik_by_reading(
    kt, z, e_short, is_max, hit, short, z_max, p_rand, inv_sigma, exponent, u2_skip,
    out,
):  # fmt: skip
    """`table_models._beam_table_cs` of each particle from its entries ``kt`` (S, N).

    Into ``out`` (N,). Each reading's exponentials first, in a loop with no
    table read (computed for every particle, and dropped where
    `_beam_table_cs` skips them), then the probabilities, then each
    particle's products and logs in `_beam_table_cs`'s order.
    """
    s_count, n = kt.shape
    p = np.empty((s_count, n))
    for i in range(s_count):
        pi = p[i]
        if is_max[i]:
            pi[:] = z_max
            continue
        ki = kt[i]
        zi = z[i]
        ei = e_short[i]
        for j in range(n):
            u = (zi - ki[j] * 0.001) * inv_sigma
            pi[j] = exp(-0.5 * u * u)
        for j in range(n):
            k = ki[j]
            zhat = k * 0.001
            u = (zi - zhat) * inv_sigma
            q = hit[k] * pi[j] + p_rand
            q = q if u * u < u2_skip else p_rand
            # q >= +0 and the short term finite, so adding 0.0 leaves q's bits
            sh = short[k] * ei
            pi[j] = q + (sh if zi <= zhat else 0.0)
    ll = np.zeros(n)
    prod = np.ones(n)
    for i in range(s_count):
        if i % 16 == 15:  # factors in (1e-3, 10): one log per 16 readings
            for j in range(n):
                ll[j] += log(prod[j])
                prod[j] = 1.0
        pi = p[i]
        for j in range(n):
            prod[j] *= pi[j]
    for j in range(n):
        out[j] = (ll[j] + log(prod[j])) * exponent


@nb.njit(**JIT)
def paper_loglik_by_reading(kt, z, inv_n, out):
    """`table_models._paper_cs` of each particle from its entries ``kt`` (S, N).

    Into ``out`` (N,): ``log(exp(-d) + inv_n)`` with ``d`` the mean of
    ``|(z_i - zhat_i) / z_i|``, summed in reading order.
    """
    s_count, n = kt.shape
    d = np.zeros(n)
    for i in range(s_count):
        ki = kt[i]
        zi = z[i]
        for j in range(n):
            d[j] += abs((zi - ki[j] * 0.001) / zi)
    for j in range(n):
        d[j] = exp(-d[j] / s_count)
    for j in range(n):
        out[j] = log(d[j] + inv_n)


@nb.njit(**JIT)
def paper_table_step(
    particles, normals, motion, sensors, table, where, z, inv_n, weights, out_p, out_w
):
    """Fused step with the paper's model (`paper_table_loglik`).

    Returns ``(log_mean, ess, estimate)``, as the steps of `fused`.
    """
    skip = np.zeros(sensors.shape[0], dtype=np.bool_)
    cs = np.empty((particles.shape[0], 2))
    kt = move_and_read_by_reading(
        particles, normals, motion, sensors, table, where, skip, out_p, cs
    )
    paper_loglik_by_reading(kt, z, inv_n, out_w)
    return _weigh_estimate(weights, out_p, cs, out_w)


@nb.njit(**JIT)
def beam_table_step(
    particles, normals, motion, sensors, table, where, z, e_short, is_max, hit,
    short, beam, weights, out_p, out_w,
):  # fmt: skip
    """Fused step with the beam model (`beam_table_loglik`).

    ``beam`` is ``(z_max, p_rand, inv_sigma, exponent, u2_skip)`` (`beam_skip`).
    Returns ``(log_mean, ess, estimate)``, as the steps of `fused`.
    """
    z_max, p_rand, inv_sigma, exponent, u2_skip = beam
    cs = np.empty((particles.shape[0], 2))
    kt = move_and_read_by_reading(
        particles, normals, motion, sensors, table, where, is_max, out_p, cs
    )
    beam_loglik_by_reading(
        kt, z, e_short, is_max, hit, short, z_max, p_rand, inv_sigma, exponent,
        u2_skip, out_w,
    )  # fmt: skip
    return _weigh_estimate(weights, out_p, cs, out_w)
