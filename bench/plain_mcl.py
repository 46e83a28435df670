"""A plain numba MCL pipeline: what `robotlib bench mcl` measures robotlib against.

What a competent numba user writes in an afternoon for the tempered beam
model on a cone table: one kernel per stage (predict, expected readings,
beam log-likelihood, weights and estimate, systematic resampling), each
looping over the particles with ``prange``, and the noise drawn by NumPy.
It shares nothing with robotlib but the cone table it reads and the
model's numbers, so the ratio measures robotlib's own overhead.
"""

import math

import numba as nb
import numpy as np

PAR = {"parallel": True, "cache": True, "fastmath": False}


@nb.njit(**PAR)
def predict(p, normals, rot1, trans, rot2, sd1, sd2, sd3, out):
    for j in nb.prange(p.shape[0]):
        r1 = rot1 + sd1 * normals[j, 0]
        t = trans + sd2 * normals[j, 1]
        a = p[j, 2] + r1
        out[j, 0] = p[j, 0] + t * math.cos(a)
        out[j, 1] = p[j, 1] + t * math.sin(a)
        h = a + rot2 + sd3 * normals[j, 2]
        out[j, 2] = (h + math.pi) % (2 * math.pi) - math.pi


@nb.njit(**PAR)
def expected(p, sensors, table, x0, y0, inv_res, out):
    ny, nx, nb_ = table.shape
    for j in nb.prange(p.shape[0]):
        c, s = math.cos(p[j, 2]), math.sin(p[j, 2])
        for i in range(sensors.shape[0]):
            sx = p[j, 0] + c * sensors[i, 0] - s * sensors[i, 1]
            sy = p[j, 1] + s * sensors[i, 0] + c * sensors[i, 1]
            col = min(max(int(math.floor((sx - x0) * inv_res)), 0), nx - 1)
            row = min(max(int(math.floor((sy - y0) * inv_res)), 0), ny - 1)
            b = int(math.floor((p[j, 2] + sensors[i, 2]) * nb_ / (2 * math.pi) + 0.5))
            out[j, i] = table[row, col, b % nb_]


@nb.njit(**PAR)
def beam_loglik(mm, z, hit, short, q, out):
    """``q``: sigma, lambda_short, z_max, p_rand, max_range, exponent."""
    sigma, lam, z_max, p_rand, max_range, exponent = q
    for j in nb.prange(mm.shape[0]):
        total = 0.0
        for i in range(z.shape[0]):
            if z[i] >= max_range - 1e-3:
                total += math.log(z_max)
                continue
            zhat = mm[j, i] * 0.001
            u = (z[i] - zhat) / sigma
            prob = hit[mm[j, i]] * math.exp(-0.5 * u * u) + p_rand
            if z[i] <= zhat:
                prob += short[mm[j, i]] * math.exp(-lam * z[i])
            total += math.log(prob)
        out[j] = exponent * total


@nb.njit(cache=True)
def weigh_and_estimate(p, w, ll, est):
    top = ll.max()
    total = 0.0
    for j in range(w.shape[0]):
        w[j] *= math.exp(ll[j] - top)
        total += w[j]
    x = y = c = s = 0.0
    for j in range(w.shape[0]):
        w[j] /= total
        x += w[j] * p[j, 0]
        y += w[j] * p[j, 1]
        c += w[j] * math.cos(p[j, 2])
        s += w[j] * math.sin(p[j, 2])
    est[0], est[1], est[2] = x, y, math.atan2(s, c)


@nb.njit(cache=True)
def systematic(p, w, u, out):
    n = w.shape[0]
    c = w[0]
    j = 0
    for k in range(n):
        pos = (k + u) / n
        while c < pos and j < n - 1:
            j += 1
            c += w[j]
        out[k] = p[j]


class PlainMCL:
    """The pipeline as a filter: ``step(increment, std, z)`` like robotlib's."""

    def __init__(self, particles, table, sensors, origin, inv_res, hit, short, q, rng):
        self.p = np.ascontiguousarray(particles)
        self.w = np.full(len(particles), 1.0 / len(particles))
        self.args = (sensors, table, origin[0], origin[1], inv_res)
        self.hit, self.short, self.q = hit, short, np.asarray(q, dtype=float)
        self.rng = rng

    def step(self, increment, std, z):
        n = len(self.p)
        normals = self.rng.standard_normal((n, 3))
        moved = np.empty_like(self.p)
        predict(self.p, normals, *increment, *std, moved)
        mm = np.empty((n, len(z)), dtype=np.int64)
        expected(moved, *self.args, mm)
        ll = np.empty(n)
        beam_loglik(mm, z, self.hit, self.short, self.q, ll)
        est = np.empty(3)
        weigh_and_estimate(moved, self.w, ll, est)
        systematic(moved, self.w, self.rng.random(), self.p)
        self.w.fill(1.0 / n)
        return est
