"""Sensor models read straight from a cone table: the paper's and the beam model.

No (N, S) array of expected ranges is made; with many particles the beam
model is tabulated once per scan (`beam_scan_lut`) and then read.

Numba kernels: contiguous arrays and scalars in, no Python objects; they
import nothing of robotlib but the JIT options and other kernels.
"""

import math

import numba as nb
import numpy as np

from ..._config import JIT, JIT_PARALLEL, serial_and_parallel
from .common import _LOG_SQRT_2PI
from .elementary import exp, log, sincos
from .tables import _table_mm


@nb.njit(**JIT)
def beam_norms(max_range, z_hit, z_short, sigma, lam_short, n):
    """Per expected range ``k`` mm (``k < n``): the beam model's hit and short factors.

    Returns ``(hit, short)`` (n,): ``z_hit / (sigma sqrt(2 pi) mass(zhat))``
    (``mass``: the hit Gaussian's share of ``[0, max_range]``; 0 if none) and
    ``z_short lambda / (1 - exp(-lambda zhat))`` (0 at ``zhat = 0``), so that
    `_beam_prob` is ``hit exp(-u^2 / 2) + short exp(-lambda z) [z <= zhat] +
    z_rand / max_range``.
    """
    # np.empty as the cone table's builder calls it, every entry written: no
    # np.zeros for numba to compile on a cold start
    hit = np.empty(n)
    short = np.empty(n)
    for k in range(n):
        zhat = k * 0.001
        mass = 0.5 * (
            math.erf((max_range - zhat) / (sigma * math.sqrt(2.0)))
            - math.erf(-zhat / (sigma * math.sqrt(2.0)))
        )
        hit[k] = 0.0
        if mass > 0.0:
            hit[k] = z_hit * math.exp(-_LOG_SQRT_2PI) / sigma / mass
        short[k] = 0.0
        if zhat > 0.0:
            short[k] = z_short * lam_short / (1.0 - math.exp(-lam_short * zhat))
    return hit, short


@nb.njit(**JIT)
def _beam_mm(i, mm, z, e_short, is_max, hit, short, z_max, p_rand, inv_sigma):
    """Beam model ``p(z_i | zhat)`` for an expected range of ``mm`` millimetres."""
    if is_max[i]:
        return z_max
    zhat = mm * 0.001
    u = (z[i] - zhat) * inv_sigma
    p = hit[mm] * exp(-0.5 * u * u) + p_rand
    if z[i] <= zhat:
        p += short[mm] * e_short[i]
    return p


@nb.njit(**JIT)
def _beam_table_cs(
    j, particles, c, s, sensors, table, x0, y0, inv_res, z, e_short, is_max, hit,
    short, z_max, p_rand, inv_sigma, exponent, u2_skip, out,
):  # fmt: skip
    """`_beam_table_one` given the heading's cosine ``c`` and sine ``s``.

    Where ``u^2 >= u2_skip`` the hit term is left out: `beam_skip` makes it
    too small to change ``p_rand`` plus it, so the result is the same.
    """
    # `_beam_mm` written out: as a call it runs twice as slow
    ll = 0.0
    prod = 1.0  # factors in (1e-3, 10): one log per 16 sensors, not one each
    for i in range(sensors.shape[0]):
        if i % 16 == 15:
            ll += log(prod)
            prod = 1.0
        if is_max[i]:
            prod *= z_max
            continue
        mm = _table_mm(particles, j, c, s, sensors, i, table, x0, y0, inv_res)
        zhat = mm * 0.001
        u = (z[i] - zhat) * inv_sigma
        if u * u < u2_skip:
            p = hit[mm] * exp(-0.5 * u * u) + p_rand
        else:
            p = p_rand
        if z[i] <= zhat:
            p += short[mm] * e_short[i]
        prod *= p
    out[j] = (ll + log(prod)) * exponent


def beam_skip(hit_max: float, p_rand: float) -> float:
    """Smallest ``u^2`` from which ``hit_max exp(-u^2 / 2) + p_rand == p_rand``.

    There the hit term is below ``2^-60 p_rand``, under half a unit in the
    last place of ``p_rand``, so the sum rounds to ``p_rand`` exactly; inf
    (never skip) when ``p_rand`` is 0.
    """
    if not (p_rand > 0.0 and hit_max > 0.0):
        return math.inf
    return 2.0 * (math.log(hit_max / p_rand) + 60.0 * math.log(2.0))


def _beam_table_loglik(
    particles,
    sensors,
    table,
    x0,
    y0,
    inv_res,
    z,
    e_short,
    is_max,
    hit,
    short,
    z_max,
    p_rand,
    inv_sigma,
    exponent,
    out,
):
    """Beam log-likelihood of particles (N, 3), expected ranges from a cone table.

    The same as `expected_table` then `beam_loglik` (times ``exponent``), in
    one pass with no (N, S) array: ``hit``, ``short`` from `beam_norms`;
    per reading ``e_short[i] = exp(-lambda z_i)`` and ``is_max[i]`` (a max
    reading); ``p_rand = z_rand / max_range``.
    """
    for j in nb.prange(particles.shape[0]):
        s, c = sincos(particles[j, 2])
        _beam_table_cs(
            j, particles, c, s, sensors, table, x0, y0, inv_res, z, e_short, is_max,
            hit, short, z_max, p_rand, inv_sigma, exponent, np.inf, out,
        )  # fmt: skip


beam_table_loglik, beam_table_loglik_parallel = serial_and_parallel(_beam_table_loglik)


@nb.njit(**JIT_PARALLEL)
def beam_scan_lut(z, e_short, is_max, hit, short, z_max, p_rand, inv_sigma, lut):
    """``lut[i, mm]``: the beam model's ``p(z_i | zhat = mm / 1000)``, (S, n).

    The same numbers `beam_table_loglik` computes per beam; with many
    particles, one table per scan is cheaper than a model per beam.
    """
    for i in range(lut.shape[0]):
        for mm in nb.prange(lut.shape[1]):
            lut[i, mm] = _beam_mm(
                i, mm, z, e_short, is_max, hit, short, z_max, p_rand, inv_sigma
            )


@nb.njit(**JIT)
def _lut_cs(j, particles, c, s, sensors, table, x0, y0, inv_res, lut, exponent, out):
    ll = 0.0
    prod = 1.0
    for i in range(sensors.shape[0]):
        if i % 16 == 15:
            ll += log(prod)
            prod = 1.0
        prod *= lut[
            i, _table_mm(particles, j, c, s, sensors, i, table, x0, y0, inv_res)
        ]
    out[j] = (ll + log(prod)) * exponent


@nb.njit(**JIT_PARALLEL)
def lut_table_loglik_parallel(
    particles, sensors, table, x0, y0, inv_res, lut, exponent, out
):
    """`beam_table_loglik` over threads, the model read from `beam_scan_lut`'s table.

    Gives the same numbers as `beam_table_loglik`.
    """
    for j in nb.prange(particles.shape[0]):
        s, c = sincos(particles[j, 2])
        _lut_cs(j, particles, c, s, sensors, table, x0, y0, inv_res, lut, exponent, out)


@nb.njit(**JIT)
def _paper_cs(j, particles, c, s, sensors, table, x0, y0, inv_res, z, inv_n, out):
    d = 0.0
    for i in range(sensors.shape[0]):
        mm = _table_mm(particles, j, c, s, sensors, i, table, x0, y0, inv_res)
        d += abs((z[i] - mm * 0.001) / z[i])
    out[j] = log(exp(-d / sensors.shape[0]) + inv_n)


def _paper_table_loglik(particles, sensors, table, x0, y0, inv_res, z, inv_n, out):
    """`expected_table` then `paper_loglik` (``inv_n = 1/n``) in one pass."""
    for j in nb.prange(particles.shape[0]):
        s, c = sincos(particles[j, 2])
        _paper_cs(j, particles, c, s, sensors, table, x0, y0, inv_res, z, inv_n, out)


paper_table_loglik, paper_table_loglik_parallel = serial_and_parallel(
    _paper_table_loglik
)
