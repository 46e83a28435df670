"""The fused MCL step on a cone table: predict, weigh, normalise, estimate.

One kernel body per sensor model, each compiled serially and over threads
from the same source (`robotlib._config.serial_and_parallel`). A step is
three passes over the particles:

1. (``prange``) move each particle by the odometry increment plus its
   noise (`pieces.move`), look up what each of its sensors should read in
   the cone table (`pieces.table_mm`; all the lookups first, so that the
   processor can wait for them together) and add up the log-likelihood of
   the scan (`beam_log_prob`, the paper's innovation);
2. (serial) the largest log-likelihood, so that the exponentials below
   cannot overflow (`_largest`);
3. (``prange``) multiply each prior weight by its likelihood, then
   (serial) sum the weights, their squares and the pose components for the
   normalisation, the effective sample size and the estimate (`_normalise`).

Sums run in plain ``range`` loops, so the serial and the threaded kernel
give the same bits. The noise is drawn by the caller's NumPy generator and
handed in (``normals``, (N, 3)), as `robotlib.localization.motion` draws it
for the step in NumPy, so both paths use the same draws.
"""

import math

import numba as nb
import numpy as np

from ..._config import JIT, serial_and_parallel
from .pieces import move, sensor_pose, table_mm


@nb.njit(**JIT, inline="always")
def beam_log_prob(z, e_short, zhat_mm, hit_norm, short_norm, inv_sigma, p_max, p_rand,
                  max_range):  # fmt: skip
    """Log of the beam model's mixture for one reading (Thrun, table 6.1).

    ``z`` is the reading (m), ``e_short`` its ``exp(-lambda_short z)``,
    ``zhat_mm`` the expected range (mm), ``hit_norm`` and ``short_norm`` the
    mixtures' normalisers tabulated per millimetre of expected range
    (`robotlib.localization.sensors.BeamSensorModel`), ``p_max`` the point
    mass of a max-range reading and ``p_rand`` the uniform density.
    """
    if z >= max_range - 1e-3:
        return math.log(p_max)
    zhat = zhat_mm * 0.001
    d = (z - zhat) * inv_sigma
    p = hit_norm[zhat_mm] * math.exp(-0.5 * d * d) + p_rand
    if z <= zhat:
        p += short_norm[zhat_mm] * e_short
    return math.log(p)


@nb.njit(**JIT, inline="always")
def _move_and_look(j, particles, normals, rot1, trans, rot2, sd1, sd2, sd3,
                   sensors, table, x0, y0, inv_res, out_p, cs, zhat):  # fmt: skip
    """Move particle ``j`` into ``out_p[j]`` and look up its sensors' ranges.

    Writes the moved pose, its heading's cosine and sine into ``cs[j]`` and
    what each sensor should read (mm) into ``zhat[j]``; the arguments are
    the step's (`_beam_step`).
    """
    x, y, th = move(particles[j, 0], particles[j, 1], particles[j, 2],
                    rot1, trans, rot2, sd1, sd2, sd3,
                    normals[j, 0], normals[j, 1], normals[j, 2])  # fmt: skip
    c = math.cos(th)
    s = math.sin(th)
    for i in range(sensors.shape[0]):
        sx, sy, sth = sensor_pose(x, y, th, c, s, sensors, i)
        zhat[j, i] = table_mm(table, x0, y0, inv_res, sx, sy, sth)
    out_p[j, 0] = x
    out_p[j, 1] = y
    out_p[j, 2] = th
    cs[j, 0] = c
    cs[j, 1] = s


@nb.njit(**JIT, inline="always")
def _largest(ll):
    """Return the largest entry of ``ll`` (``-inf`` when no particle fits the scan)."""
    top = -np.inf
    for j in range(ll.shape[0]):
        top = max(top, ll[j])
    return top


@nb.njit(**JIT, inline="always")
def _normalise(weights, moved, cs, out_w, est):
    """Normalise ``out_w`` in place and write the estimate; return the sums.

    ``out_w`` holds ``weights * exp(ll - top)``; ``cs`` (N, 2) each moved
    particle's heading cosine and sine; ``est`` (3,) receives the weighted
    mean pose (circular mean heading). Returns ``(total / prior, ess)``.
    """
    n = out_w.shape[0]
    total = 0.0
    prior = 0.0
    for j in range(n):
        total += out_w[j]
        prior += weights[j]
    squares = 0.0
    x = y = c = s = 0.0
    for j in range(n):
        w = out_w[j] / total
        out_w[j] = w
        squares += w * w
        x += w * moved[j, 0]
        y += w * moved[j, 1]
        c += w * cs[j, 0]
        s += w * cs[j, 1]
    est[0] = x
    est[1] = y
    est[2] = math.atan2(s, c)
    return total / prior, 1.0 / squares


@nb.njit(**JIT, inline="always")
def _weigh(weights, ll, moved, cs, out_w, est):
    """Weigh the particles by ``exp(ll)``, normalise, estimate (steps 2 and 3).

    ``ll`` (N,) holds the particles' log-likelihoods; the other arguments
    are `_normalise`'s. Returns ``(log_mean, ess)`` as the steps do.
    """
    top = _largest(ll)
    for j in nb.prange(ll.shape[0]):  # no particle fits: the weights stay as they were
        out_w[j] = weights[j] * math.exp(ll[j] - top) if top > -np.inf else weights[j]
    ratio, ess = _normalise(weights, moved, cs, out_w, est)
    return (top + math.log(ratio) if top > -np.inf else top), ess


def _beam_step(particles, weights, normals, rot1, trans, rot2, sd1, sd2, sd3,
               sensors, table, x0, y0, inv_res, z, e_short, hit_norm, short_norm,
               inv_sigma, p_max, p_rand, max_range, exponent,
               out_p, out_w, est):  # fmt: skip
    """One fused step of MCL with the beam model on a cone table.

    Parameters: the particles (N, 3) and their weights (N,); the standard
    ``normals`` (N, 3) of the motion noise; the odometry increment and its
    noise's standard deviations (rad, m, rad); the sonar ``sensors`` (S, 3)
    in the robot's frame; the cone ``table`` (ny, nx, n_bins) uint16 mm
    with its lower-left corner ``x0, y0`` (m) and ``inv_res`` (1/m); the
    scan ``z`` (S,) m and per-scan and per-model terms of `beam_log_prob`;
    the tempering ``exponent``. Writes the moved particles ``out_p``, the
    new normalised weights ``out_w`` and the estimate ``est`` (3,); returns
    ``(log_mean, ess)``: the log of the scan's mean likelihood under the
    prior weights and the effective sample size.
    """
    n, n_sensors = particles.shape[0], sensors.shape[0]
    ll = np.empty(n)
    cs = np.empty((n, 2))
    zhat = np.empty((n, n_sensors), dtype=np.uint16)
    for j in nb.prange(n):
        _move_and_look(j, particles, normals, rot1, trans, rot2, sd1, sd2, sd3,
                       sensors, table, x0, y0, inv_res, out_p, cs, zhat)  # fmt: skip
        total = 0.0
        for i in range(n_sensors):  # how well the scan agrees
            total += beam_log_prob(z[i], e_short[i], zhat[j, i], hit_norm, short_norm,
                                   inv_sigma, p_max, p_rand, max_range)  # fmt: skip
        ll[j] = exponent * total
    return _weigh(weights, ll, out_p, cs, out_w, est)


def _paper_step(particles, weights, normals, rot1, trans, rot2, sd1, sd2, sd3,
                sensors, table, x0, y0, inv_res, z,
                out_p, out_w, est):  # fmt: skip
    """One fused step of the paper's MCL on a cone table.

    The weight of particle ``j`` is ``exp(-d_j) + 1/N`` with ``d_j`` the
    mean of ``|(z_i - zhat_ij) / z_i|`` over its sensors. Parameters and
    return as `_beam_step`, without the beam model's terms.
    """
    n, n_sensors = particles.shape[0], sensors.shape[0]
    ll = np.empty(n)
    cs = np.empty((n, 2))
    zhat = np.empty((n, n_sensors), dtype=np.uint16)
    for j in nb.prange(n):
        _move_and_look(j, particles, normals, rot1, trans, rot2, sd1, sd2, sd3,
                       sensors, table, x0, y0, inv_res, out_p, cs, zhat)  # fmt: skip
        d = 0.0
        for i in range(n_sensors):  # the mean relative innovation
            d += abs((z[i] - zhat[j, i] * 0.001) / z[i])
        ll[j] = math.log(math.exp(-d / n_sensors) + 1.0 / n)
    return _weigh(weights, ll, out_p, cs, out_w, est)


beam_step, beam_step_parallel = serial_and_parallel(_beam_step)
paper_step, paper_step_parallel = serial_and_parallel(_paper_step)
