"""Plain NumPy/Python references for the avoidance kernels (no numba)."""

from __future__ import annotations

import math

import numpy as np


def wrap(a):
    """Wrap to (-pi, pi]."""
    w = np.remainder(np.asarray(a, dtype=float) + np.pi, 2 * np.pi) - np.pi
    return np.where(w <= -np.pi, w + 2 * np.pi, w)


def sector_centres(n):
    """Robot-frame centres of n sectors, rad."""
    return -np.pi + (np.arange(n) + 0.5) * 2 * np.pi / n


def histogram_points(points, certainty, pose, n, window, enlarge):
    """VFH+ polar density, vectorised over points and sectors."""
    d = np.hypot(points[:, 0] - pose[0], points[:, 1] - pose[1])
    beta = wrap(np.arctan2(points[:, 1] - pose[1], points[:, 0] - pose[0]) - pose[2])
    gamma = np.where(
        d <= enlarge,
        np.pi / 2,
        np.arcsin(np.minimum(1.0, enlarge / np.maximum(d, 1e-12))),
    )
    mag = certainty**2 * (1 - d / window)
    keep = (d < window) & (certainty > 0)
    off = np.abs(wrap(sector_centres(n)[None, :] - beta[:, None]))
    inside = off <= gamma[:, None] + 1e-12
    return (np.where(inside & keep[:, None], mag[:, None], 0.0)).sum(axis=0)


def smooth(h, half):
    """Circular weighted average with weights 1..half+1..1 over 2 half + 1."""
    out = np.zeros(len(h))
    for m in range(-half, half + 1):
        out += (half + 1 - abs(m)) * np.roll(h, -m)
    return out / (2 * half + 1)


def certainty_update(grid, x0, y0, res, pose, sensors, ranges, max_range, half, clear,
                     inc, dec, cmax):  # fmt: skip
    """The certainty update, cell by cell over the whole grid."""
    grid = grid.copy()
    ny, nx = grid.shape
    jj, ii = np.meshgrid(np.arange(nx), np.arange(ny))
    cx, cy = x0 + (jj + 0.5) * res, y0 + (ii + 0.5) * res
    c, s = math.cos(pose[2]), math.sin(pose[2])
    for k, r in enumerate(ranges):
        if not r < max_range:
            continue
        sx = pose[0] + c * sensors[k, 0] - s * sensors[k, 1]
        sy = pose[1] + s * sensors[k, 0] + c * sensors[k, 1]
        a = pose[2] + sensors[k, 2]
        reach = min(r - res, clear)
        if reach > 0:
            px, py = cx - sx, cy - sy
            d = np.hypot(px, py)
            cone = (d < reach) & (
                px * math.cos(a) + py * math.sin(a) >= d * math.cos(half)
            )
            grid[cone & (grid > 0)] = np.maximum(grid[cone & (grid > 0)] - dec, 0.0)
        hj = math.floor((sx + r * math.cos(a) - x0) / res)
        hi = math.floor((sy + r * math.sin(a) - y0) / res)
        if 0 <= hi < ny and 0 <= hj < nx:
            grid[hi, hj] = min(grid[hi, hj] + inc, cmax)
    return grid


def valleys(blocked):
    """Circular free runs as lists of unwrapped sector indexes."""
    n = len(blocked)
    if not blocked.any():
        return [list(range(n))]
    first = int(np.argmax(blocked))
    runs, cur = [], []
    for m in range(n):
        k = first + m
        if blocked[k % n]:
            if cur:
                runs.append(cur)
            cur = []
        else:
            cur.append(k)
    if cur:
        runs.append(cur)
    return runs


def plus_direction(blocked, target, previous, wide, mu):
    """VFH+ candidate directions and cost, by enumeration."""
    n = len(blocked)
    if not blocked.any():
        return float(wrap(target))
    alpha = 2 * np.pi / n
    kt = int(np.floor((float(wrap(target)) + np.pi) / alpha)) % n

    def angle(k):
        return float(wrap((k + 0.5) * alpha - np.pi))

    cands = []
    for run in valleys(blocked):
        if len(run) >= wide:
            cands += [angle(run[0] + wide // 2), angle(run[-1] - wide // 2)]
            if kt in [k % n for k in run[wide // 2 : len(run) - wide // 2]]:
                cands.append(float(wrap(target)))
        else:
            cands.append(angle(run[0] + (len(run) - 1) / 2))
    if not cands:
        return math.nan

    def cost(a):
        return (
            mu[0] * abs(wrap(a - target))
            + mu[1] * abs(a)
            + mu[2] * abs(wrap(a - previous))
        )

    return min(cands, key=cost)


def potential_force(ranges, sensors, max_range, gx, gy, k_att, k_rep, d0):
    """Attraction plus Khatib repulsion, vectorised over the sonars."""
    dg = math.hypot(gx, gy)
    f = np.zeros(2)
    if dg > 0:
        f += k_att * min(dg, 1.0) * np.array([gx, gy]) / dg
    r = np.asarray(ranges, dtype=float)
    e = sensors[:, :2] + r[:, None] * np.column_stack(
        [np.cos(sensors[:, 2]), np.sin(sensors[:, 2])]
    )
    rho = np.hypot(e[:, 0], e[:, 1])
    push = (r < max_range) & (rho < d0) & (rho > 0)
    mag = np.where(push, k_rep * (1 / rho - 1 / d0) / rho**2, 0.0)
    f -= (mag[:, None] * e / rho[:, None]).sum(axis=0)
    return f


def dwa_evaluate(points, vs, ws, steps, dt, radius, look, goal):
    """The dynamic window's roll-out, vectorised over samples, steps and points.

    Returns ``free, heading, togo, gap`` of shape (V, W) as the kernel defines them.
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    v = np.asarray(vs, dtype=float)[:, None, None]
    w = np.asarray(ws, dtype=float)[None, :, None]
    t = np.arange(0, steps + 1)[None, None, :] * dt
    turning = np.abs(w) > 1e-9
    safe_w = np.where(turning, w, 1.0)
    th = w * t
    x = np.where(turning, v / safe_w * np.sin(th), v * t)
    y = np.where(turning, v / safe_w * (1 - np.cos(th)), 0.0)
    d = np.hypot(pts[:, 0] - x[..., None], pts[:, 1] - y[..., None]) - radius
    d0 = np.hypot(pts[:, 0], pts[:, 1]) - radius
    hit = ((d <= 0) & (d < d0 - 1e-3)).any(axis=-1)  # (V, W, K+1)
    hit[..., 0] = False
    first = np.where(hit.any(axis=-1), hit.argmax(axis=-1), steps + 1)
    last = first - 1  # the last pose driven
    free = np.where(first <= steps, np.broadcast_to(v[..., 0], first.shape) * last * dt,
                    np.inf)  # fmt: skip
    xs = np.take_along_axis(np.broadcast_to(x, hit.shape), last[..., None], -1)[..., 0]
    ys = np.take_along_axis(np.broadcast_to(y, hit.shape), last[..., None], -1)[..., 0]
    ths = np.take_along_axis(np.broadcast_to(th, hit.shape), last[..., None], -1)[
        ..., 0
    ]
    heading = np.abs(wrap(np.arctan2(goal[1] - ys, goal[0] - xs) - ths))
    togo = np.hypot(goal[0] - xs, goal[1] - ys)
    # the poses from step 1 to the one that touched (or the last)
    upto = np.arange(steps + 1) <= np.minimum(first, steps)[..., None]
    near = np.where(upto[..., None], d, np.inf)[..., 1:, :]
    gap = np.minimum(near.min(axis=(-1, -2), initial=np.inf), look)
    return free, heading, togo, gap
