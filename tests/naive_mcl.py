"""Plain NumPy references for the MCL kernels (slow, obvious, loop-free where easy)."""

import math

import numpy as np


def wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def sample_odometry(particles, rot1, trans, rot2, sd, normals):
    r1 = rot1 + sd[0] * normals[:, 0]
    t = trans + sd[1] * normals[:, 1]
    r2 = rot2 + sd[2] * normals[:, 2]
    th = particles[:, 2]
    out = np.empty_like(particles)
    out[:, 0] = particles[:, 0] + t * np.cos(th + r1)
    out[:, 1] = particles[:, 1] + t * np.sin(th + r1)
    out[:, 2] = wrap(th + r1 + r2)
    return out


def paper_weights(z, zhat):
    d = np.mean(np.abs((z - zhat) / z), axis=1)
    w = np.exp(-d) + 1.0 / len(zhat)
    return w / w.sum()


def beam_prob(z, zhat, zmax, z_hit, z_short, z_max, z_rand, sigma, lam):
    if z >= zmax - 1e-3:
        return z_max
    mass = 0.5 * (
        math.erf((zmax - zhat) / (sigma * math.sqrt(2)))
        - math.erf(-zhat / (sigma * math.sqrt(2)))
    )
    p_hit = math.exp(-0.5 * ((z - zhat) / sigma) ** 2) / (
        sigma * math.sqrt(2 * math.pi)
    )
    p = z_hit * p_hit / mass
    if z <= zhat:
        p += z_short * lam * math.exp(-lam * z) / (1 - math.exp(-lam * zhat))
    return p + z_rand / zmax


def beam_loglik(z, zhat, zmax, params):
    out = np.zeros(len(zhat))
    for j in range(len(zhat)):
        for i in range(len(z)):
            out[j] += math.log(beam_prob(z[i], zhat[j, i], zmax, *params))
    return out


def sensor_positions(particles, sensors):
    """World (x, y, heading) of every sensor of every particle, (N, S, 3)."""
    c, s = np.cos(particles[:, 2:3]), np.sin(particles[:, 2:3])
    x = particles[:, 0:1] + c * sensors[:, 0] - s * sensors[:, 1]
    y = particles[:, 1:2] + s * sensors[:, 0] + c * sensors[:, 1]
    return np.stack([x, y, particles[:, 2:3] + sensors[:, 2]], axis=-1)


def field_loglik(world, particles, sensors, z, zmax, z_hit, z_rand, sigma):
    sp = sensor_positions(particles, sensors)
    keep = z < zmax - 1e-3
    ex = sp[:, keep, 0] + z[keep] * np.cos(sp[:, keep, 2])
    ey = sp[:, keep, 1] + z[keep] * np.sin(sp[:, keep, 2])
    d = world.distance_to_walls(np.stack([ex, ey], axis=-1))
    p = z_hit * np.exp(-0.5 * (d / sigma) ** 2) / (sigma * math.sqrt(2 * math.pi))
    return np.log(p + z_rand / zmax).sum(axis=1)


def update_weights(weights, loglik):
    w = weights * np.exp(loglik - loglik.max())
    log_mean = loglik.max() + np.log(w.sum() / weights.sum())
    w = w / w.sum()
    return w, log_mean, 1.0 / np.sum(w**2)


def pose_mean(particles, weights):
    w = weights / weights.sum()
    return np.array(
        [
            w @ particles[:, 0],
            w @ particles[:, 1],
            math.atan2(w @ np.sin(particles[:, 2]), w @ np.cos(particles[:, 2])),
        ]
    )


def resample_positions(weights, positions):
    c = np.cumsum(weights) / np.sum(weights)
    c[-1] = 1.0
    return np.searchsorted(c, positions, side="right")


def kld_bound(k, epsilon, z):
    if k <= 1:
        return 1.0
    a = 2 / (9 * (k - 1))
    return (k - 1) / (2 * epsilon) * (1 - a + math.sqrt(a) * z) ** 3


def kld_draw(
    particles, weights, uniforms, bounds, bin_xy, bin_theta, epsilon, z, n_min
):
    """KLD-sampling as a plain loop: the drawn indexes, up to the bound."""
    c = np.cumsum(weights)
    xmin, ymin, xmax, ymax = bounds
    nbx = max(1, math.ceil((xmax - xmin) / bin_xy))
    nby = max(1, math.ceil((ymax - ymin) / bin_xy))
    nbt = max(1, math.ceil(2 * math.pi / bin_theta))
    seen, drawn = set(), []
    for u in uniforms:
        j = int(np.searchsorted(c, u * c[-1], side="right"))
        drawn.append(j)
        x, y, th = particles[j]
        seen.add((
            min(max(math.floor((x - xmin) / bin_xy), 0), nbx - 1),
            min(max(math.floor((y - ymin) / bin_xy), 0), nby - 1),
            min(max(math.floor((th + math.pi) / bin_theta), 0), nbt - 1),
        ))  # fmt: skip
        if len(drawn) >= n_min and len(drawn) >= kld_bound(len(seen), epsilon, z):
            break
    return np.array(drawn)


def fused_step(particles, weights, motion, normals, loglik):
    """Predict, weigh, normalise, estimate; ``loglik(moved) -> (N,)``."""
    rot1, trans, rot2, *sd = motion
    moved = sample_odometry(particles, rot1, trans, rot2, sd, normals)
    w, log_mean, ess = update_weights(weights, loglik(moved))
    return moved, w, log_mean, ess, pose_mean(moved, w)


def ray_hit(ox, oy, a, seg):
    """Distance along the ray at angle ``a`` to segment ``seg`` (inf if none)."""
    d = np.array([math.cos(a), math.sin(a)])
    p, e = np.array(seg[:2]), np.array(seg[2:]) - np.array(seg[:2])
    m = np.column_stack([d, -e])
    if abs(np.linalg.det(m)) < 1e-12:
        return math.inf
    t, s = np.linalg.solve(m, p - [ox, oy])
    return t if t >= 0 and 0 <= s <= 1 else math.inf


def cone_table_cell(walls, cx, cy, n_bins, offsets, max_range, min_range, specular):
    """A cone table's entries (n_bins,) uint16 mm for a sonar at ``(cx, cy)``.

    Every direction bin ``b`` casts one ray along ``b * 2 pi / n_bins``
    against every wall (M, 4): its nearest hit (the lowest index among equal
    hits; walls parallel to the ray within 1e-12 are not hit) echoes if it
    lies within ``max_range`` and the ray meets the wall within the specular
    cosine ``specular`` of its normal. The cone along ``b`` reads the nearest
    echo of its rays ``b + offsets`` (``max_range`` for none), clipped to
    ``[min_range, max_range]``, in mm. The arithmetic is the simulator's, step
    for step, so the numbers are the same bits.
    """
    w = np.asarray(walls, dtype=np.float64).reshape(-1, 4)
    ex, ey = w[:, 2] - w[:, 0], w[:, 3] - w[:, 1]
    wx, wy = w[:, 0] - cx, w[:, 1] - cy
    a = [b * (2.0 * math.pi) / n_bins for b in range(n_bins)]
    dx = np.array([math.cos(v) for v in a])[:, None]  # (n_bins, 1): one ray a row
    dy = np.array([math.sin(v) for v in a])[:, None]
    with np.errstate(invalid="ignore", divide="ignore"):
        length = np.sqrt(ex * ex + ey * ey)
        nx, ny = -ey / length, ex / length
        denom = dx * ey - dy * ex
        t = (wx * ey - wy * ex) / denom
        s = (wx * dy - wy * dx) / denom
    hit = (np.abs(denom) >= 1e-12) & (t >= 0) & (s >= 0) & (s <= 1)
    t = np.where(hit, t, np.inf)
    m = np.argmin(t, axis=1)  # the nearest hit, the lowest index among equals
    rows = np.arange(n_bins)
    first = t[rows, m]
    cos_inc = np.abs(dx[:, 0] * nx[m] + dy[:, 0] * ny[m])
    echo = np.where((first < max_range) & (cos_inc >= specular), first, np.inf)
    out = np.empty(n_bins, dtype=np.uint16)
    for b in range(n_bins):
        z = min(echo[(b + o) % n_bins] for o in offsets)
        z = min(max(min(z, max_range), min_range), max_range)
        out[b] = round(z * 1000.0)
    return out


def table_lookup(table, x0, y0, resolution, particles, sensors):
    """Expected readings (N, S), m: each sensor's cell (clamped) and nearest bin."""
    ny, nx, n_bins = table.shape
    out = np.empty((len(particles), len(sensors)))
    for n, (x, y, th) in enumerate(particles):
        for i, (sx, sy, sth) in enumerate(sensors):
            px = x + math.cos(th) * sx - math.sin(th) * sy
            py = y + math.sin(th) * sx + math.cos(th) * sy
            col = min(max(math.floor((px - x0) / resolution), 0), nx - 1)
            row = min(max(math.floor((py - y0) / resolution), 0), ny - 1)
            b = math.floor((th + sth) / (2 * math.pi) * n_bins + 0.5) % n_bins
            out[n, i] = table[row, col, b] * 0.001
    return out
