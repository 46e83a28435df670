"""Numba kernels for Monte Carlo localization.

Every kernel takes contiguous arrays and scalars only; random numbers are
drawn by the caller's ``numpy.random.Generator`` and passed in, so a seed
reproduces a run bit for bit. Kernels that come in a serial and a parallel
form share a per-particle body; the parallel loops write only their own slot,
and every sum is taken serially, so both forms give identical results.

Units: metres, radians; lookup tables hold millimetres (uint16).
"""

import math

import numba as nb
import numpy as np

from .._config import JIT, JIT_PARALLEL
from ..sensing._kernels import cone_echo, cone_walls, indexed_cone_echo, sonar_cone
from ..world._kernels import point_segment_distance

_TWO_PI = 2.0 * math.pi
_LOG_SQRT_2PI = 0.5 * math.log(2.0 * math.pi)


@nb.njit(**JIT)
def wrap(a):
    """Wrap an angle to (-pi, pi]."""
    w = a - _TWO_PI * math.floor((a + math.pi) / _TWO_PI)
    if w <= -math.pi:
        w += _TWO_PI
    elif w > math.pi:
        w -= _TWO_PI
    return w


# -- motion ---------------------------------------------------------------------


@nb.njit(**JIT)
def _odometry_one(j, particles, rot1, trans, rot2, sd1, sdt, sd2, normals, out):
    r1 = rot1 + sd1 * normals[j, 0]
    t = trans + sdt * normals[j, 1]
    r2 = rot2 + sd2 * normals[j, 2]
    th = particles[j, 2]
    out[j, 0] = particles[j, 0] + t * math.cos(th + r1)
    out[j, 1] = particles[j, 1] + t * math.sin(th + r1)
    out[j, 2] = wrap(th + r1 + r2)


@nb.njit(**JIT)
def sample_odometry(particles, rot1, trans, rot2, sd1, sdt, sd2, normals, out):
    """Move particles (N, 3) by ``rot1, trans, rot2`` plus noise into ``out``.

    Each increment gets its standard deviation (``sd1, sdt, sd2``) times the
    caller's standard normals ``normals`` (N, 3).
    """
    for j in range(particles.shape[0]):
        _odometry_one(j, particles, rot1, trans, rot2, sd1, sdt, sd2, normals, out)


@nb.njit(**JIT_PARALLEL)
def sample_odometry_parallel(particles, rot1, trans, rot2, sd1, sdt, sd2, normals, out):
    """`sample_odometry` over threads."""
    for j in nb.prange(particles.shape[0]):
        _odometry_one(j, particles, rot1, trans, rot2, sd1, sdt, sd2, normals, out)


# Expected readings by cone casts (the exact path) are `robotlib.sensing._kernels`'s
# `expected_scan` and `expected_scan_parallel`, shared with `robotlib.sensing.sonar`.


# -- expected sonar readings: fast (cone table lookup) -----------------------


@nb.njit(**JIT)
def _cone_cell(
    cx,
    cy,
    segments,
    n_bins,
    ray_step,
    n_rays,
    cone,
    max_range,
    min_range,
    cos_specular,
    rays,
    table,
    i,
    j,
):
    """Fill ``table[i, j, :]`` for a sonar at ``(cx, cy)`` (see `build_cone_table`)."""
    half = (n_rays - 1) // 2 if n_rays > 1 else 0
    if ray_step > 0:
        for b in range(n_bins):
            echo, _ = sonar_cone(
                cx, cy, b * _TWO_PI / n_bins, segments, 1, 0.0, max_range, cos_specular
            )
            rays[b] = echo
    for b in range(n_bins):
        if ray_step > 0:
            echo = np.inf
            for k in range(-half, half + 1):
                r = rays[(b + k * ray_step) % n_bins]
                if r < echo:
                    echo = r
        else:
            echo, _ = sonar_cone(
                cx,
                cy,
                b * _TWO_PI / n_bins,
                segments,
                n_rays,
                cone,
                max_range,
                cos_specular,
            )
        z = max_range if echo >= max_range else echo
        z = min(max(z, min_range), max_range)
        table[i, j, b] = np.uint16(round(z * 1000.0))


@nb.njit(**JIT_PARALLEL)
def build_cone_table(
    segments,
    x0,
    y0,
    resolution,
    n_bins,
    ray_step,
    n_rays,
    cone,
    max_range,
    min_range,
    cos_specular,
    block,
    table,
):
    """Fill ``table`` (ny, nx, n_bins) uint16 with cone ranges in mm.

    ``table[i, j, b]`` is the expected range of a sonar at the centre of cell
    ``(i, j)`` pointing along ``b * 2 pi / n_bins``. When the cone's rays are
    ``ray_step`` bins apart (``ray_step > 0``) each direction's single ray is
    cast once and a cone is the nearest echo of its ``n_rays`` rays, which is
    what `sonar_cone` computes; otherwise (``ray_step == 0``) every cone is
    cast with `sonar_cone`.

    Cells are filled in square blocks of ``block`` cells (in parallel), each
    against only the walls that come within ``max_range`` of the block: a
    wall further away cannot echo, so the table is the same as with all
    walls.
    """
    ny, nx, _ = table.shape
    nbx = (nx + block - 1) // block
    nby = (ny + block - 1) // block
    reach = max_range + 0.75 * block * resolution  # > max_range + half diagonal
    for q in nb.prange(nbx * nby):
        bi = q // nbx
        bj = q % nbx
        bx = x0 + (bj + 0.5) * block * resolution
        by = y0 + (bi + 0.5) * block * resolution
        keep = np.zeros(segments.shape[0], dtype=np.bool_)
        count = 0
        for m in range(segments.shape[0]):
            d = point_segment_distance(
                bx, by, segments[m, 0], segments[m, 1], segments[m, 2], segments[m, 3]
            )
            if d <= reach:
                keep[m] = True
                count += 1
        near = np.empty((count, 4))
        c = 0
        for m in range(segments.shape[0]):
            if keep[m]:
                for t in range(4):
                    near[c, t] = segments[m, t]
                c += 1
        rays = np.empty(n_bins)
        for i in range(bi * block, min((bi + 1) * block, ny)):
            cy = y0 + (i + 0.5) * resolution
            for j in range(bj * block, min((bj + 1) * block, nx)):
                cx = x0 + (j + 0.5) * resolution
                _cone_cell(
                    cx,
                    cy,
                    near,
                    n_bins,
                    ray_step,
                    n_rays,
                    cone,
                    max_range,
                    min_range,
                    cos_specular,
                    rays,
                    table,
                    i,
                    j,
                )


@nb.njit(**JIT_PARALLEL)
def build_cone_table_indexed(
    segments, x0, y0, resolution, n_bins, ray_step, n_rays, cone, max_range,
    min_range, cos_specular, bx0, by0, bsize, nbx, nby, start, items, field,
    table,
):  # fmt: skip
    """`build_cone_table` with every ray cast through a bucket index of the walls.

    The same table (each ray finds the same nearest wall, see
    `robotlib.sensing._kernels.indexed_ray`), in time that grows with the
    walls near each ray rather than with all of them: for maps of many
    walls or points. ``field`` is the distance field on the table's own
    cells (rays jump over clear space with it). Rows are filled in parallel.
    """
    ny, nx, _ = table.shape
    half = (n_rays - 1) // 2 if n_rays > 1 else 0
    for i in nb.prange(ny):
        rays = np.empty(n_bins)
        cy = y0 + (i + 0.5) * resolution
        for j in range(nx):
            cx = x0 + (j + 0.5) * resolution
            if ray_step > 0:
                for b in range(n_bins):
                    rays[b] = indexed_cone_echo(
                        cx, cy, b * _TWO_PI / n_bins, segments, 1, 0.0, max_range,
                        cos_specular, bx0, by0, bsize, nbx, nby, start, items,
                        field, x0, y0, resolution,
                    )  # fmt: skip
            for b in range(n_bins):
                if ray_step > 0:
                    echo = np.inf
                    for k in range(-half, half + 1):
                        r = rays[(b + k * ray_step) % n_bins]
                        if r < echo:
                            echo = r
                else:
                    echo = indexed_cone_echo(
                        cx, cy, b * _TWO_PI / n_bins, segments, n_rays, cone,
                        max_range, cos_specular, bx0, by0, bsize, nbx, nby, start,
                        items, field, x0, y0, resolution,
                    )  # fmt: skip
                z = max_range if echo >= max_range else echo
                z = min(max(z, min_range), max_range)
                table[i, j, b] = np.uint16(round(z * 1000.0))


@nb.njit(**JIT, inline="always")
def _table_mm(particles, j, c, s, sensors, i, table, x0, y0, inv_res):
    """Table entry (mm) for sensor ``i`` of particle ``j`` (heading cos, sin)."""
    ny, nx, n_bins = table.shape
    sx = particles[j, 0] + c * sensors[i, 0] - s * sensors[i, 1]
    sy = particles[j, 1] + s * sensors[i, 0] + c * sensors[i, 1]
    col = int(math.floor((sx - x0) * inv_res))
    row = int(math.floor((sy - y0) * inv_res))
    col = min(max(col, 0), nx - 1)
    row = min(max(row, 0), ny - 1)
    b = int(math.floor((particles[j, 2] + sensors[i, 2]) * (n_bins / _TWO_PI) + 0.5))
    # b % n_bins, without an integer division for headings in (-2 pi, 4 pi)
    if b < 0:
        b += n_bins
        if b < 0:
            b %= n_bins
    elif b >= n_bins:
        b -= n_bins
        if b >= n_bins:
            b %= n_bins
    return table[row, col, b]


@nb.njit(**JIT)
def _lookup_one(j, particles, sensors, table, x0, y0, inv_res, out):
    c = math.cos(particles[j, 2])
    s = math.sin(particles[j, 2])
    for i in range(sensors.shape[0]):
        out[j, i] = (
            _table_mm(particles, j, c, s, sensors, i, table, x0, y0, inv_res) * 0.001
        )


@nb.njit(**JIT)
def expected_table(particles, sensors, table, x0, y0, inv_res, out):
    """Sonar ranges ``out`` (N, S) looked up in a cone table (see `build_cone_table`).

    Each sensor's position selects the cell (clamped to the grid) and its
    heading the nearest direction bin.
    """
    for j in range(particles.shape[0]):
        _lookup_one(j, particles, sensors, table, x0, y0, inv_res, out)


@nb.njit(**JIT_PARALLEL)
def expected_table_parallel(particles, sensors, table, x0, y0, inv_res, out):
    """`expected_table` over threads."""
    for j in nb.prange(particles.shape[0]):
        _lookup_one(j, particles, sensors, table, x0, y0, inv_res, out)


# -- sensor models: log-likelihood per particle from expected readings --------


@nb.njit(**JIT)
def paper_loglik(z, zhat, n, out):
    """Compute the paper's innovation weight as a log: ``log(exp(-d_j) + 1/n)``.

    ``d_j = mean_i |(z_i - zhat_ji) / z_i|``; ``z`` (S,), ``zhat`` (N, S).
    """
    s_count = z.shape[0]
    for j in range(zhat.shape[0]):
        d = 0.0
        for i in range(s_count):
            d += abs((z[i] - zhat[j, i]) / z[i])
        out[j] = math.log(math.exp(-d / s_count) + 1.0 / n)


@nb.njit(**JIT)
def _beam_prob(z, zhat, max_range, z_hit, z_short, z_max, z_rand, sigma, lam_short):
    """Thrun's beam model mixture ``p(z | zhat)`` for one beam."""
    p = 0.0
    if z < max_range:
        # hit: Gaussian around zhat, normalised over [0, max_range]
        u = (z - zhat) / sigma
        mass = 0.5 * (
            math.erf((max_range - zhat) / (sigma * math.sqrt(2.0)))
            - math.erf(-zhat / (sigma * math.sqrt(2.0)))
        )
        if mass > 0.0:
            p += z_hit * math.exp(-0.5 * u * u - _LOG_SQRT_2PI) / sigma / mass
        # short: exponential up to zhat, normalised over [0, zhat]
        if z <= zhat and zhat > 0.0:
            p += (
                z_short
                * lam_short
                * math.exp(-lam_short * z)
                / (1.0 - math.exp(-lam_short * zhat))
            )
        p += z_rand / max_range
    else:
        p += z_max
    return p


@nb.njit(**JIT)
def _beam_one(j, z, zhat, max_range, z_hit, z_short, z_max, z_rand, sigma, lam, out):
    ll = 0.0
    for i in range(z.shape[0]):
        zi = z[i] if z[i] < max_range - 1e-3 else max_range
        ll += math.log(
            _beam_prob(
                zi, zhat[j, i], max_range, z_hit, z_short, z_max, z_rand, sigma, lam
            )
        )
    out[j] = ll


@nb.njit(**JIT)
def beam_loglik(
    z, zhat, max_range, z_hit, z_short, z_max, z_rand, sigma, lam_short, out
):
    """Beam model log-likelihood ``out[j] = sum_i log p(z_i | zhat_ji)``.

    A reading at or beyond ``max_range`` (to 1 mm) is a "max" reading.
    """
    for j in range(zhat.shape[0]):
        _beam_one(
            j, z, zhat, max_range, z_hit, z_short, z_max, z_rand, sigma, lam_short, out
        )


@nb.njit(**JIT_PARALLEL)
def beam_loglik_parallel(
    z, zhat, max_range, z_hit, z_short, z_max, z_rand, sigma, lam_short, out
):
    """`beam_loglik` over threads."""
    for j in nb.prange(zhat.shape[0]):
        _beam_one(
            j, z, zhat, max_range, z_hit, z_short, z_max, z_rand, sigma, lam_short, out
        )


# -- fused fast path: table lookup and sensor model in one pass -----------------


@nb.njit(**JIT)
def beam_norms(max_range, z_hit, z_short, sigma, lam_short, n):
    """Per expected range ``k`` mm (``k < n``): the beam model's hit and short factors.

    Returns ``(hit, short)`` (n,): ``z_hit / (sigma sqrt(2 pi) mass(zhat))``
    (``mass``: the hit Gaussian's share of ``[0, max_range]``; 0 if none) and
    ``z_short lambda / (1 - exp(-lambda zhat))`` (0 at ``zhat = 0``), so that
    `_beam_prob` is ``hit exp(-u^2 / 2) + short exp(-lambda z) [z <= zhat] +
    z_rand / max_range``.
    """
    hit = np.zeros(n)
    short = np.zeros(n)
    for k in range(n):
        zhat = k * 0.001
        mass = 0.5 * (
            math.erf((max_range - zhat) / (sigma * math.sqrt(2.0)))
            - math.erf(-zhat / (sigma * math.sqrt(2.0)))
        )
        if mass > 0.0:
            hit[k] = z_hit * math.exp(-_LOG_SQRT_2PI) / sigma / mass
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
    p = hit[mm] * math.exp(-0.5 * u * u) + p_rand
    if z[i] <= zhat:
        p += short[mm] * e_short[i]
    return p


@nb.njit(**JIT)
def _beam_table_one(
    j, particles, sensors, table, x0, y0, inv_res, z, e_short, is_max, hit, short,
    z_max, p_rand, inv_sigma, exponent, out,
):  # fmt: skip
    _beam_table_cs(
        j, particles, math.cos(particles[j, 2]), math.sin(particles[j, 2]), sensors,
        table, x0, y0, inv_res, z, e_short, is_max, hit, short, z_max, p_rand,
        inv_sigma, exponent, np.inf, out,
    )  # fmt: skip


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
            ll += math.log(prod)
            prod = 1.0
        if is_max[i]:
            prod *= z_max
            continue
        mm = _table_mm(particles, j, c, s, sensors, i, table, x0, y0, inv_res)
        zhat = mm * 0.001
        u = (z[i] - zhat) * inv_sigma
        if u * u < u2_skip:
            p = hit[mm] * math.exp(-0.5 * u * u) + p_rand
        else:
            p = p_rand
        if z[i] <= zhat:
            p += short[mm] * e_short[i]
        prod *= p
    out[j] = (ll + math.log(prod)) * exponent


def beam_skip(hit_max: float, p_rand: float) -> float:
    """Smallest ``u^2`` from which ``hit_max exp(-u^2 / 2) + p_rand == p_rand``.

    There the hit term is below ``2^-60 p_rand``, under half a unit in the
    last place of ``p_rand``, so the sum rounds to ``p_rand`` exactly; inf
    (never skip) when ``p_rand`` is 0.
    """
    if not (p_rand > 0.0 and hit_max > 0.0):
        return math.inf
    return 2.0 * (math.log(hit_max / p_rand) + 60.0 * math.log(2.0))


@nb.njit(**JIT)
def beam_table_loglik(
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
    for j in range(particles.shape[0]):
        _beam_table_one(
            j,
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
        )


@nb.njit(**JIT_PARALLEL)
def beam_table_loglik_parallel(
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
    """`beam_table_loglik` over threads."""
    for j in nb.prange(particles.shape[0]):
        _beam_table_one(
            j,
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
        )


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
def _lut_one(j, particles, sensors, table, x0, y0, inv_res, lut, exponent, out):
    c = math.cos(particles[j, 2])
    s = math.sin(particles[j, 2])
    _lut_cs(j, particles, c, s, sensors, table, x0, y0, inv_res, lut, exponent, out)


@nb.njit(**JIT)
def _lut_cs(j, particles, c, s, sensors, table, x0, y0, inv_res, lut, exponent, out):
    ll = 0.0
    prod = 1.0
    for i in range(sensors.shape[0]):
        if i % 16 == 15:
            ll += math.log(prod)
            prod = 1.0
        prod *= lut[
            i, _table_mm(particles, j, c, s, sensors, i, table, x0, y0, inv_res)
        ]
    out[j] = (ll + math.log(prod)) * exponent


@nb.njit(**JIT_PARALLEL)
def lut_table_loglik_parallel(
    particles, sensors, table, x0, y0, inv_res, lut, exponent, out
):
    """`beam_table_loglik` over threads, the model read from `beam_scan_lut`'s table.

    Gives the same numbers as `beam_table_loglik`.
    """
    for j in nb.prange(particles.shape[0]):
        _lut_one(j, particles, sensors, table, x0, y0, inv_res, lut, exponent, out)


@nb.njit(**JIT)
def _paper_table_one(j, particles, sensors, table, x0, y0, inv_res, z, inv_n, out):
    c = math.cos(particles[j, 2])
    s = math.sin(particles[j, 2])
    _paper_cs(j, particles, c, s, sensors, table, x0, y0, inv_res, z, inv_n, out)


@nb.njit(**JIT)
def _paper_cs(j, particles, c, s, sensors, table, x0, y0, inv_res, z, inv_n, out):
    d = 0.0
    for i in range(sensors.shape[0]):
        mm = _table_mm(particles, j, c, s, sensors, i, table, x0, y0, inv_res)
        d += abs((z[i] - mm * 0.001) / z[i])
    out[j] = math.log(math.exp(-d / sensors.shape[0]) + inv_n)


@nb.njit(**JIT)
def paper_table_loglik(particles, sensors, table, x0, y0, inv_res, z, inv_n, out):
    """`expected_table` then `paper_loglik` (``inv_n = 1/n``) in one pass."""
    for j in range(particles.shape[0]):
        _paper_table_one(j, particles, sensors, table, x0, y0, inv_res, z, inv_n, out)


@nb.njit(**JIT_PARALLEL)
def paper_table_loglik_parallel(
    particles, sensors, table, x0, y0, inv_res, z, inv_n, out
):
    """`paper_table_loglik` over threads."""
    for j in nb.prange(particles.shape[0]):
        _paper_table_one(j, particles, sensors, table, x0, y0, inv_res, z, inv_n, out)


@nb.njit(**JIT)
def _field_one(
    j,
    particles,
    sensors,
    z,
    max_range,
    z_hit,
    z_rand,
    sigma,
    field,
    segments,
    x0,
    y0,
    inv_res,
    far,
    out,
):
    c = math.cos(particles[j, 2])
    s = math.sin(particles[j, 2])
    ny, nx = field.shape
    ll = 0.0
    for i in range(sensors.shape[0]):
        if z[i] >= max_range - 1e-3:
            continue
        sx = particles[j, 0] + c * sensors[i, 0] - s * sensors[i, 1]
        sy = particles[j, 1] + s * sensors[i, 0] + c * sensors[i, 1]
        a = particles[j, 2] + sensors[i, 2]
        ex = sx + z[i] * math.cos(a)
        ey = sy + z[i] * math.sin(a)
        if segments.shape[0] > 0:
            d = np.inf
            for m in range(segments.shape[0]):
                dm = point_segment_distance(
                    ex,
                    ey,
                    segments[m, 0],
                    segments[m, 1],
                    segments[m, 2],
                    segments[m, 3],
                )
                if dm < d:
                    d = dm
        else:
            col = int(math.floor((ex - x0) * inv_res))
            row = int(math.floor((ey - y0) * inv_res))
            if 0 <= row < ny and 0 <= col < nx:
                d = field[row, col]
            else:
                d = far
        u = d / sigma
        ll += math.log(
            z_hit * math.exp(-0.5 * u * u - _LOG_SQRT_2PI) / sigma + z_rand / max_range
        )
    out[j] = ll


@nb.njit(**JIT)
def field_loglik(
    particles,
    sensors,
    z,
    max_range,
    z_hit,
    z_rand,
    sigma,
    field,
    segments,
    x0,
    y0,
    inv_res,
    far,
    out,
):
    """Likelihood-field log-likelihood of readings ``z`` (S,) for particles (N, 3).

    Each reading below ``max_range`` puts an end point on its sensor's axis;
    ``p = z_hit N(d; 0, sigma) + z_rand / max_range`` with ``d`` the end
    point's distance to the nearest obstacle: exact to ``segments`` when
    there are any (M > 0), else looked up in ``field`` (ny, nx) float32, m
    (``far`` outside the grid). Max readings are skipped.
    """
    for j in range(particles.shape[0]):
        _field_one(
            j,
            particles,
            sensors,
            z,
            max_range,
            z_hit,
            z_rand,
            sigma,
            field,
            segments,
            x0,
            y0,
            inv_res,
            far,
            out,
        )


@nb.njit(**JIT_PARALLEL)
def field_loglik_parallel(
    particles,
    sensors,
    z,
    max_range,
    z_hit,
    z_rand,
    sigma,
    field,
    segments,
    x0,
    y0,
    inv_res,
    far,
    out,
):
    """`field_loglik` over threads."""
    for j in nb.prange(particles.shape[0]):
        _field_one(
            j,
            particles,
            sensors,
            z,
            max_range,
            z_hit,
            z_rand,
            sigma,
            field,
            segments,
            x0,
            y0,
            inv_res,
            far,
            out,
        )


# -- weights, estimate ------------------------------------------------------------


@nb.njit(**JIT)
def _finish_weights(weights, top, out):
    n = weights.shape[0]
    total = 0.0
    for j in range(n):
        total += out[j]
    wsum = 0.0
    for j in range(n):
        wsum += weights[j]
    sq = 0.0
    for j in range(n):
        out[j] /= total
        sq += out[j] * out[j]
    return top + math.log(total / wsum), 1.0 / sq


@nb.njit(**JIT)
def update_weights(weights, loglik, out):
    """Bayes update ``out ∝ weights * exp(loglik)``, normalised in place.

    Returns ``(log_mean, ess)``: the log of ``sum_j weights_j exp(loglik_j)``
    (``weights`` summing to 1, so the mean likelihood) and the effective
    sample size ``1 / sum out_j^2`` of the result.
    """
    n = weights.shape[0]
    top = -np.inf
    for j in range(n):
        if loglik[j] > top:
            top = loglik[j]
    for j in range(n):
        out[j] = weights[j] * math.exp(loglik[j] - top)
    return _finish_weights(weights, top, out)


@nb.njit(**JIT_PARALLEL)
def update_weights_parallel(weights, loglik, out):
    """`update_weights`, exponentials over threads (sums serial: same result)."""
    n = weights.shape[0]
    top = -np.inf
    for j in range(n):
        if loglik[j] > top:
            top = loglik[j]
    for j in nb.prange(n):
        out[j] = weights[j] * math.exp(loglik[j] - top)
    return _finish_weights(weights, top, out)


@nb.njit(**JIT)
def _pose_mean(particles, weights, cs):
    sx = 0.0
    sy = 0.0
    sc = 0.0
    ss = 0.0
    sw = 0.0
    for j in range(particles.shape[0]):
        w = weights[j]
        sx += w * particles[j, 0]
        sy += w * particles[j, 1]
        sc += w * cs[j, 0]
        ss += w * cs[j, 1]
        sw += w
    out = np.empty(3)
    out[0] = sx / sw
    out[1] = sy / sw
    out[2] = math.atan2(ss, sc)
    return out


@nb.njit(**JIT)
def weighted_pose_mean(particles, weights):
    """Weighted mean of ``x, y`` and circular mean of ``theta``; returns (3,)."""
    cs = np.empty((particles.shape[0], 2))
    for j in range(particles.shape[0]):
        cs[j, 0] = math.cos(particles[j, 2])
        cs[j, 1] = math.sin(particles[j, 2])
    return _pose_mean(particles, weights, cs)


@nb.njit(**JIT_PARALLEL)
def weighted_pose_mean_parallel(particles, weights):
    """`weighted_pose_mean` with the cosines and sines over threads (same result)."""
    cs = np.empty((particles.shape[0], 2))
    for j in nb.prange(particles.shape[0]):
        cs[j, 0] = math.cos(particles[j, 2])
        cs[j, 1] = math.sin(particles[j, 2])
    return _pose_mean(particles, weights, cs)


@nb.njit(**JIT)
def position_spread(particles, idx):
    """``sqrt(var_x + var_y)`` of the particles ``particles[idx]`` (unweighted)."""
    n = idx.shape[0]
    mx = 0.0
    my = 0.0
    for k in range(n):
        mx += particles[idx[k], 0]
        my += particles[idx[k], 1]
    mx /= n
    my /= n
    v = 0.0
    for k in range(n):
        dx = particles[idx[k], 0] - mx
        dy = particles[idx[k], 1] - my
        v += dx * dx + dy * dy
    return math.sqrt(v / n)


# -- resampling ---------------------------------------------------------------------


@nb.njit(**JIT)
def cumulative(weights):
    """Cumulative sum of weights with the last entry forced to exactly 1."""
    n = weights.shape[0]
    c = np.empty(n)
    total = 0.0
    for j in range(n):
        total += weights[j]
        c[j] = total
    for j in range(n):
        c[j] /= total
    c[n - 1] = 1.0
    return c


@nb.njit(**JIT)
def search_indexes(cum, positions, out):
    """``out[k]`` = first ``j`` with ``cum[j] > positions[k]`` (binary search)."""
    n = cum.shape[0]
    for k in range(positions.shape[0]):
        u = positions[k]
        lo = 0
        hi = n - 1
        while lo < hi:
            mid = (lo + hi) // 2
            if cum[mid] > u:
                hi = mid
            else:
                lo = mid + 1
        out[k] = lo


@nb.njit(**JIT)
def sorted_indexes(cum, positions, out):
    """As `search_indexes` for increasing ``positions``, by one merge pass."""
    n = cum.shape[0]
    j = 0
    for k in range(positions.shape[0]):
        while j < n - 1 and cum[j] <= positions[k]:
            j += 1
        out[k] = j


@nb.njit(**JIT)
def kld_bound(k, epsilon, z):
    """Fox's KLD bound: particles needed for ``k`` occupied bins.

    ``n = (k-1)/(2 eps) * (1 - 2/(9(k-1)) + sqrt(2/(9(k-1))) z)^3``, with
    ``z`` the upper ``1 - delta`` quantile of the standard normal.
    """
    if k <= 1:
        return 1.0
    a = 2.0 / (9.0 * (k - 1))
    b = 1.0 - a + math.sqrt(a) * z
    return (k - 1) / (2.0 * epsilon) * b * b * b


@nb.njit(**JIT)
def kld_resample(
    particles,
    cum,
    uniforms,
    x0,
    y0,
    bin_xy,
    bin_theta,
    nbx,
    nby,
    nbt,
    epsilon,
    z,
    n_min,
    occupied,
    out,
):
    """KLD-sampling: draw by ``uniforms`` until the bound for the bins is met.

    Draws particle indexes one at a time (``uniforms`` (n_max,) in [0, 1),
    searched in ``cum``), counts the distinct ``(x, y, theta)`` bins of the
    drawn particles in ``occupied`` (nby * nbx * nbt bools, all False on
    entry and on exit), and stops at ``n >= max(n_min, kld_bound(k))`` or
    when the uniforms run out. Writes indexes into ``out`` and returns the
    count.
    """
    n_max = uniforms.shape[0]
    n_cum = cum.shape[0]
    k = 0
    n = 0
    while n < n_max:
        u = uniforms[n]
        lo = 0
        hi = n_cum - 1
        while lo < hi:
            mid = (lo + hi) // 2
            if cum[mid] > u:
                hi = mid
            else:
                lo = mid + 1
        out[n] = lo
        bx = int(math.floor((particles[lo, 0] - x0) / bin_xy))
        by = int(math.floor((particles[lo, 1] - y0) / bin_xy))
        bt = int(math.floor((particles[lo, 2] + math.pi) / bin_theta))
        bx = min(max(bx, 0), nbx - 1)
        by = min(max(by, 0), nby - 1)
        bt = min(max(bt, 0), nbt - 1)
        cell = (by * nbx + bx) * nbt + bt
        if not occupied[cell]:
            occupied[cell] = True
            k += 1
        n += 1
        if n >= n_min and n >= kld_bound(k, epsilon, z):
            break
    for m in range(n):
        lo = out[m]
        bx = int(math.floor((particles[lo, 0] - x0) / bin_xy))
        by = int(math.floor((particles[lo, 1] - y0) / bin_xy))
        bt = int(math.floor((particles[lo, 2] + math.pi) / bin_theta))
        bx = min(max(bx, 0), nbx - 1)
        by = min(max(by, 0), nby - 1)
        bt = min(max(bt, 0), nbt - 1)
        occupied[(by * nbx + bx) * nbt + bt] = False
    return n


@nb.njit(**JIT)
def gather(particles, idx, out):
    """``out[k] = particles[idx[k]]`` for (N, 3) particles."""
    for k in range(idx.shape[0]):
        j = idx[k]
        out[k, 0] = particles[j, 0]
        out[k, 1] = particles[j, 1]
        out[k, 2] = particles[j, 2]


@nb.njit(**JIT)
def outside(particles, admissible, x0, y0, inv_res, out):
    """``out[j]`` True where particle ``j`` is not on an admissible cell."""
    ny, nx = admissible.shape
    count = 0
    for j in range(particles.shape[0]):
        col = int(math.floor((particles[j, 0] - x0) * inv_res))
        row = int(math.floor((particles[j, 1] - y0) * inv_res))
        bad = not (0 <= row < ny and 0 <= col < nx and admissible[row, col])
        out[j] = bad
        if bad:
            count += 1
    return count


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
def _move(j, particles, motion, normals, out, cs):
    """Move particle ``j`` into ``out``; return (and keep) its heading's cos, sin."""
    rot1, trans, rot2, sd1, sdt, sd2 = motion
    _odometry_one(j, particles, rot1, trans, rot2, sd1, sdt, sd2, normals, out)
    c = math.cos(out[j, 2])
    s = math.sin(out[j, 2])
    cs[j, 0] = c
    cs[j, 1] = s
    return c, s


@nb.njit(**JIT)
def _top(loglik):
    top = -np.inf
    for j in range(loglik.shape[0]):
        if loglik[j] > top:
            top = loglik[j]
    return top


@nb.njit(**JIT)
def _weigh_estimate(weights, particles, cs, out_w):
    """`update_weights` with ``out_w`` holding log-likelihoods, then the estimate."""
    top = _top(out_w)
    for j in range(out_w.shape[0]):
        out_w[j] = weights[j] * math.exp(out_w[j] - top)
    log_mean, ess = _finish_weights(weights, top, out_w)
    return log_mean, ess, _pose_mean(particles, out_w, cs)


@nb.njit(**JIT_PARALLEL)
def _weigh_estimate_parallel(weights, particles, cs, out_w):
    """`_weigh_estimate`, exponentials over threads (sums serial: same result)."""
    top = _top(out_w)
    for j in nb.prange(out_w.shape[0]):
        out_w[j] = weights[j] * math.exp(out_w[j] - top)
    log_mean, ess = _finish_weights(weights, top, out_w)
    return log_mean, ess, _pose_mean(particles, out_w, cs)


@nb.njit(**JIT)
def _move_cells(
    j, particles, motion, normals, sensors, table, where, skip, out, cs, cells
):
    """Move particle ``j``; its sensors' flat table indexes into ``cells[j]``.

    The same cell and bin as `_table_mm` (0 where ``skip[i]``: not read);
    ``cells`` is int32 (`ConeTable` keeps below 2^31 entries).
    """
    x0, y0, inv_res = where
    ny, nx, n_bins = table.shape
    c, s = _move(j, particles, motion, normals, out, cs)
    for i in range(sensors.shape[0]):
        if skip[i]:
            cells[j, i] = 0
            continue
        sx = out[j, 0] + c * sensors[i, 0] - s * sensors[i, 1]
        sy = out[j, 1] + s * sensors[i, 0] + c * sensors[i, 1]
        col = int(math.floor((sx - x0) * inv_res))
        row = int(math.floor((sy - y0) * inv_res))
        col = min(max(col, 0), nx - 1)
        row = min(max(row, 0), ny - 1)
        b = int(math.floor((out[j, 2] + sensors[i, 2]) * (n_bins / _TWO_PI) + 0.5))
        if b < 0:
            b += n_bins
            if b < 0:
                b %= n_bins
        elif b >= n_bins:
            b -= n_bins
            if b >= n_bins:
                b %= n_bins
        cells[j, i] = (row * nx + col) * n_bins + b


@nb.njit(**JIT)
def _gather_mm(j, flat, cells):
    """Replace particle ``j``'s flat indexes by the table's entries (mm)."""
    for i in range(cells.shape[1]):
        cells[j, i] = flat[cells[j, i]]


@nb.njit(**JIT)
def _paper_mm(j, mm, z, inv_n, out):
    """`_paper_cs` on looked-up entries ``mm[j]``."""
    d = 0.0
    for i in range(mm.shape[1]):
        d += abs((z[i] - mm[j, i] * 0.001) / z[i])
    out[j] = math.log(math.exp(-d / mm.shape[1]) + inv_n)


@nb.njit(**JIT)
def _beam_mm_row(
    j, mm, z, e_short, is_max, hit, short, z_max, p_rand, inv_sigma, exponent,
    u2_skip, out,
):  # fmt: skip
    """`_beam_table_cs` on looked-up entries ``mm[j]``."""
    ll = 0.0
    prod = 1.0
    for i in range(mm.shape[1]):
        if i % 16 == 15:
            ll += math.log(prod)
            prod = 1.0
        if is_max[i]:
            prod *= z_max
            continue
        k = mm[j, i]
        zhat = k * 0.001
        u = (z[i] - zhat) * inv_sigma
        if u * u < u2_skip:
            p = hit[k] * math.exp(-0.5 * u * u) + p_rand
        else:
            p = p_rand
        if z[i] <= zhat:
            p += short[k] * e_short[i]
        prod *= p
    out[j] = (ll + math.log(prod)) * exponent


@nb.njit(**JIT)
def _lut_mm_row(j, mm, lut, exponent, out):
    """`_lut_cs` on looked-up entries ``mm[j]``."""
    ll = 0.0
    prod = 1.0
    for i in range(mm.shape[1]):
        if i % 16 == 15:
            ll += math.log(prod)
            prod = 1.0
        prod *= lut[i, mm[j, i]]
    out[j] = (ll + math.log(prod)) * exponent


# The fused steps run in three passes: move and compute every table index,
# read the table (independent reads the processor overlaps: the table is
# larger than its caches), then the model. The same arithmetic as one pass.


@nb.njit(**JIT)
def paper_table_step(
    particles, normals, motion, sensors, table, where, z, inv_n, weights, out_p, out_w
):
    """Fused step with the paper's model (`paper_table_loglik`)."""
    n = particles.shape[0]
    cs = np.empty((n, 2))
    mm = np.empty((n, sensors.shape[0]), dtype=np.int32)
    skip = np.zeros(sensors.shape[0], dtype=np.bool_)
    for j in range(n):
        _move_cells(j, particles, motion, normals, sensors, table, where, skip,
                    out_p, cs, mm)  # fmt: skip
    flat = table.reshape(table.size)
    for j in range(n):
        _gather_mm(j, flat, mm)
    for j in range(n):
        _paper_mm(j, mm, z, inv_n, out_w)
    return _weigh_estimate(weights, out_p, cs, out_w)


@nb.njit(**JIT_PARALLEL)
def paper_lut_step_parallel(
    particles, normals, motion, sensors, table, where, terms, inv_n, weights, out_p,
    out_w,
):  # fmt: skip
    """`paper_table_step` over threads, each term read from a table (same result).

    ``terms[i, k]`` is ``|(z_i - k / 1000) / z_i|`` for every millimetre ``k``
    a table entry can hold (as `beam_scan_lut` for the beam model): a lookup
    instead of a division per beam. Sums serial.
    """
    n = particles.shape[0]
    s_count = sensors.shape[0]
    cs = np.empty((n, 2))
    mm = np.empty((n, s_count), dtype=np.int32)
    skip = np.zeros(s_count, dtype=np.bool_)
    for j in nb.prange(n):
        _move_cells(j, particles, motion, normals, sensors, table, where, skip,
                    out_p, cs, mm)  # fmt: skip
    flat = table.reshape(table.size)
    for j in nb.prange(n):
        _gather_mm(j, flat, mm)
    for j in nb.prange(n):
        d = 0.0
        for i in range(s_count):
            d += terms[i, mm[j, i]]
        out_w[j] = math.log(math.exp(-d / s_count) + inv_n)
    return _weigh_estimate_parallel(weights, out_p, cs, out_w)


@nb.njit(**JIT)
def beam_table_step(
    particles, normals, motion, sensors, table, where, z, e_short, is_max, hit,
    short, beam, weights, out_p, out_w,
):  # fmt: skip
    """Fused step with the beam model (`beam_table_loglik`).

    ``beam`` is ``(z_max, p_rand, inv_sigma, exponent, u2_skip)`` (`beam_skip`).
    """
    z_max, p_rand, inv_sigma, exponent, u2_skip = beam
    n = particles.shape[0]
    cs = np.empty((n, 2))
    mm = np.empty((n, sensors.shape[0]), dtype=np.int32)
    for j in range(n):
        _move_cells(j, particles, motion, normals, sensors, table, where, is_max,
                    out_p, cs, mm)  # fmt: skip
    flat = table.reshape(table.size)
    for j in range(n):
        _gather_mm(j, flat, mm)
    for j in range(n):
        _beam_mm_row(
            j, mm, z, e_short, is_max, hit, short, z_max, p_rand, inv_sigma,
            exponent, u2_skip, out_w,
        )  # fmt: skip
    return _weigh_estimate(weights, out_p, cs, out_w)


@nb.njit(**JIT_PARALLEL)
def lut_table_step_parallel(
    particles, normals, motion, sensors, table, where, lut, skip, exponent, weights,
    out_p, out_w,
):  # fmt: skip
    """Fused step with the beam model read from `beam_scan_lut`'s table, over threads.

    The same numbers as `beam_table_step`; ``skip`` marks the max readings
    (``lut[i]`` is constant there: the table is not read).
    """
    n = particles.shape[0]
    cs = np.empty((n, 2))
    mm = np.empty((n, sensors.shape[0]), dtype=np.int32)
    for j in nb.prange(n):
        _move_cells(j, particles, motion, normals, sensors, table, where, skip,
                    out_p, cs, mm)  # fmt: skip
    flat = table.reshape(table.size)
    for j in nb.prange(n):
        _gather_mm(j, flat, mm)
    for j in nb.prange(n):
        _lut_mm_row(j, mm, lut, exponent, out_w)
    return _weigh_estimate_parallel(weights, out_p, cs, out_w)


@nb.njit(**JIT)
def systematic_gather(particles, weights, u, out):
    """Low-variance resampling of ``particles`` (N, 3) into ``out`` (n, 3).

    Positions ``(k + u) / n`` in the cumulative weights, as
    `robotlib.localization.resampling.systematic_resample` then `gather`.
    """
    cum = cumulative(weights)
    n_cum = cum.shape[0]
    n = out.shape[0]
    j = 0
    for k in range(n):
        position = (k + u) / n
        while j < n_cum - 1 and cum[j] <= position:
            j += 1
        out[k, 0] = particles[j, 0]
        out[k, 1] = particles[j, 1]
        out[k, 2] = particles[j, 2]


# -- expected sonar readings: exact, against the walls near each sensor ---------------

_CULL_MARGIN = 1e-6
"""Widening of each cone for `robotlib.sensing._kernels.cone_walls`, rad."""


@nb.njit(**JIT)
def _expected_pose_blocks(
    k, poses, sensors, segments, start, block_segs, grid, n_rays, cone, max_range,
    min_range, cos_specular, near, out,
):  # fmt: skip
    x0, y0, inv_block, nbx, nby = grid
    half = 0.5 * cone + _CULL_MARGIN
    ch = math.cos(half) if half < 0.5 * math.pi else 0.0
    sh = math.sin(half)
    c = math.cos(poses[k, 2])
    s = math.sin(poses[k, 2])
    for i in range(sensors.shape[0]):
        sx = poses[k, 0] + c * sensors[i, 0] - s * sensors[i, 1]
        sy = poses[k, 1] + s * sensors[i, 0] + c * sensors[i, 1]
        bx = math.floor((sx - x0) * inv_block)
        by = math.floor((sy - y0) * inv_block)
        if 0 <= bx < nbx and 0 <= by < nby:
            b = int(by) * int(nbx) + int(bx)
            walls = block_segs[start[b] : start[b + 1]]
        else:
            walls = segments
        ci = math.cos(sensors[i, 2])
        si = math.sin(sensors[i, 2])
        count = cone_walls(
            sx, sy, c * ci - s * si, s * ci + c * si, ch, sh, walls, max_range, near
        )
        echo = cone_echo(
            sx, sy, poses[k, 2] + sensors[i, 2], near[:count], n_rays, cone,
            max_range, cos_specular,
        )  # fmt: skip
        z = echo if echo < max_range else max_range
        out[k, i] = min(max(z, min_range), max_range)


@nb.njit(**JIT)
def expected_scan_blocks(
    poses, sensors, segments, start, block_segs, grid, n_rays, cone, max_range,
    min_range, cos_specular, out,
):  # fmt: skip
    """`expected_scan` (of `robotlib.sensing._kernels`), each cone against nearby walls.

    ``grid`` ``(x0, y0, 1 / side, nbx, nby)`` cuts the plane into square
    blocks; the walls a sensor in block ``b`` may reach within ``max_range``
    are ``block_segs[start[b]:start[b + 1]]`` (`wall_blocks`), and of those
    the ones in its cone (`robotlib.sensing._kernels.cone_walls`). A sensor outside
    the blocks tests all ``segments``. The same readings as `expected_scan`.
    """
    near = np.empty_like(segments)
    for k in range(poses.shape[0]):
        _expected_pose_blocks(
            k, poses, sensors, segments, start, block_segs, grid, n_rays, cone,
            max_range, min_range, cos_specular, near, out,
        )  # fmt: skip


@nb.njit(**JIT_PARALLEL)
def expected_scan_blocks_parallel(
    poses, sensors, segments, start, block_segs, grid, n_rays, cone, max_range,
    min_range, cos_specular, out,
):  # fmt: skip
    """`expected_scan_blocks` with the poses spread over threads."""
    for k in nb.prange(poses.shape[0]):
        near = np.empty_like(segments)
        _expected_pose_blocks(
            k, poses, sensors, segments, start, block_segs, grid, n_rays, cone,
            max_range, min_range, cos_specular, near, out,
        )  # fmt: skip


def wall_blocks(segments, bounds, max_range, side=1.0):
    """List the walls each block of ``side`` m may reach (`expected_scan_blocks`).

    A wall is listed for a block when its bounding box, grown by
    ``max_range`` (and 1e-6 m), overlaps the block: then and only then can a
    sensor in the block pass `robotlib.sensing._kernels.cone_walls`'s range test for
    it. Walls keep their order.

    Returns
    -------
    tuple
        ``(start, block_segs, grid)``: offsets (nby * nbx + 1,) int64, the
        walls of each block in turn (K, 4), and ``(x0, y0, 1 / side, nbx, nby)``.
    """
    seg = np.ascontiguousarray(segments, dtype=np.float64).reshape(-1, 4)
    xmin, ymin, xmax, ymax = (float(v) for v in bounds)
    nbx = max(1, math.ceil((xmax - xmin) / side))
    nby = max(1, math.ceil((ymax - ymin) / side))
    grow = float(max_range) + 1e-6
    lo_x = np.minimum(seg[:, 0], seg[:, 2]) - grow
    hi_x = np.maximum(seg[:, 0], seg[:, 2]) + grow
    lo_y = np.minimum(seg[:, 1], seg[:, 3]) - grow
    hi_y = np.maximum(seg[:, 1], seg[:, 3]) + grow
    bx0 = xmin + side * np.arange(nbx)
    by0 = ymin + side * np.arange(nby)
    in_x = (lo_x[None, :] <= bx0[:, None] + side) & (hi_x[None, :] >= bx0[:, None])
    in_y = (lo_y[None, :] <= by0[:, None] + side) & (hi_y[None, :] >= by0[:, None])
    keep = in_y[:, None, :] & in_x[None, :, :]  # (nby, nbx, M)
    counts = keep.reshape(nby * nbx, -1).sum(axis=1)
    start = np.zeros(nby * nbx + 1, dtype=np.int64)
    np.cumsum(counts, out=start[1:])
    idx = np.nonzero(keep.reshape(nby * nbx, -1))[1]
    block_segs = np.ascontiguousarray(seg[idx]).reshape(-1, 4)
    return start, block_segs, (xmin, ymin, 1.0 / side, nbx, nby)
