"""Numba kernels of the avoidance controllers (VFH's grid and histogram).

Only contiguous float64 arrays and scalars go in; SI units (m, rad). These
kernels import nothing of robotlib's but the JIT options; their plain NumPy
references live in ``tests/naive_avoidance.py``.

- `certainty_update`: VFH's certainty grid from one sonar scan (an echo adds
  to the cell at the measured range on the sonar's axis and takes from the
  cells inside its cone nearer than that).
- `histogram_grid`: VFH+'s polar obstacle density from the grid cells in the
  active window around the robot (each cell enlarged by the robot's radius
  plus a safety distance), in the robot frame.
- `histogram_points`: the same density from a list of weighted points.
- `smooth`: the circular moving average of a histogram (weights 1..l+1..1).
- `hysteresis`, `plus_direction`, `follow_direction`: the binary histogram
  and VFH+'s choice of direction; boundary following on it.
- `vfh_step`: one whole cycle (grid, histogram, choice) in one call.
- `potential_force`: the potential field's force from sonar and a goal.
- `dwa_evaluate`: the dynamic window's roll-out of every velocity sample
  (free distance, goal alignment, distance left to the goal).
"""

import math

import numba as nb
import numpy as np

from .._config import JIT


@nb.njit(**JIT)
def _wrap(a):
    """Wrap an angle to (-pi, pi]."""
    w = a - 2.0 * math.pi * math.floor((a + math.pi) / (2.0 * math.pi))
    if w <= -math.pi:
        w += 2.0 * math.pi
    return w


@nb.njit(**JIT)
def certainty_update(
    grid,
    x0,
    y0,
    res,
    pose,
    sensors,
    ranges,
    max_range,
    half_cone,
    clear_range,
    inc,
    dec,
    cmax,
):
    """Add one scan to the certainty grid, in place.

    ``grid`` (ny, nx): certainty values in [0, cmax]; cell ``[i, j]`` covers
    ``x0 + j * res`` .. ``+ res`` and likewise in y. ``pose`` (3,): the
    robot's pose in the grid's frame. ``sensors`` (S, 3): sonar poses in the
    robot frame. ``ranges`` (S,), m. A reading ``r`` below ``max_range`` (an
    echo) takes ``dec`` from every cell whose centre lies inside the sonar's
    cone (within ``half_cone`` of its axis) nearer than
    ``min(r - res, clear_range)`` (the first echo came from ``r``: nothing is
    nearer), then adds ``inc`` to the cell at ``r`` on the sonar's axis. A
    reading at ``max_range`` (no echo: maybe a specular miss) changes nothing.
    """
    ny, nx = grid.shape
    c, s = math.cos(pose[2]), math.sin(pose[2])
    for k in range(sensors.shape[0]):
        r = ranges[k]
        if not r < max_range:
            continue
        sx = pose[0] + c * sensors[k, 0] - s * sensors[k, 1]
        sy = pose[1] + s * sensors[k, 0] + c * sensors[k, 1]
        a = pose[2] + sensors[k, 2]
        dx, dy = math.cos(a), math.sin(a)
        reach = min(r - res, clear_range)
        if reach > 0.0:
            # the cone's bounding box: its apex, its two edges' ends, its axis
            bx0, bx1, by0, by1 = sx, sx, sy, sy
            for e in (-1.0, 0.0, 1.0):
                ex = sx + reach * math.cos(a + e * half_cone)
                ey = sy + reach * math.sin(a + e * half_cone)
                bx0, bx1 = min(bx0, ex), max(bx1, ex)
                by0, by1 = min(by0, ey), max(by1, ey)
            j0 = max(int(math.floor((bx0 - x0) / res)), 0)
            j1 = min(int(math.floor((bx1 - x0) / res)), nx - 1)
            i0 = max(int(math.floor((by0 - y0) / res)), 0)
            i1 = min(int(math.floor((by1 - y0) / res)), ny - 1)
            cos_half = math.cos(half_cone)
            for i in range(i0, i1 + 1):
                py = y0 + (i + 0.5) * res - sy
                for j in range(j0, j1 + 1):
                    if grid[i, j] <= 0.0:
                        continue
                    px = x0 + (j + 0.5) * res - sx
                    d = math.sqrt(px * px + py * py)
                    if d < reach and px * dx + py * dy >= d * cos_half:
                        grid[i, j] = max(grid[i, j] - dec, 0.0)
        hj = int(math.floor((sx + r * dx - x0) / res))
        hi = int(math.floor((sy + r * dy - y0) / res))
        if 0 <= hi < ny and 0 <= hj < nx:
            grid[hi, hj] = min(grid[hi, hj] + inc, cmax)


@nb.njit(**JIT)
def fade(grid, x0, y0, res, px, py, radius, factor):
    """Multiply the cells within a square of half-side ``radius`` by ``factor``."""
    ny, nx = grid.shape
    j0 = max(int(math.floor((px - radius - x0) / res)), 0)
    j1 = min(int(math.floor((px + radius - x0) / res)), nx - 1)
    i0 = max(int(math.floor((py - radius - y0) / res)), 0)
    i1 = min(int(math.floor((py + radius - y0) / res)), ny - 1)
    for i in range(i0, i1 + 1):
        for j in range(j0, j1 + 1):
            grid[i, j] *= factor


@nb.njit(**JIT)
def _add(hist, dx, dy, cert, theta, window, enlarge):
    """Add one obstacle at ``(dx, dy)`` from the robot to the histogram."""
    d = math.sqrt(dx * dx + dy * dy)
    if d >= window or cert <= 0.0:
        return
    n = hist.shape[0]
    alpha = 2.0 * math.pi / n
    mag = cert * cert * (1.0 - d / window)
    beta = _wrap(math.atan2(dy, dx) - theta)
    gamma = math.pi / 2.0 if d <= enlarge else math.asin(enlarge / d)
    # sectors whose centre lies within [beta - gamma, beta + gamma]
    lo = int(math.ceil((beta - gamma + math.pi) / alpha - 0.5))
    hi = int(math.floor((beta + gamma + math.pi) / alpha - 0.5))
    for k in range(lo, hi + 1):
        hist[k % n] += mag


@nb.njit(**JIT)
def histogram_grid(grid, x0, y0, res, pose, window, enlarge, hist):
    """Polar obstacle density of the grid's cells within ``window`` of the robot.

    Fills ``hist`` (n,) in place (sector ``k`` is centred on the robot-frame
    direction ``-pi + (k + 0.5) * 2 pi / n``). A cell of certainty ``c`` at
    distance ``d`` weighs ``c**2 * (1 - d / window)`` and counts in every
    sector within ``asin(enlarge / d)`` of its direction (all within pi/2
    when ``d <= enlarge``).
    """
    ny, nx = grid.shape
    hist[:] = 0.0
    j0 = max(int(math.floor((pose[0] - window - x0) / res)), 0)
    j1 = min(int(math.floor((pose[0] + window - x0) / res)), nx - 1)
    i0 = max(int(math.floor((pose[1] - window - y0) / res)), 0)
    i1 = min(int(math.floor((pose[1] + window - y0) / res)), ny - 1)
    for i in range(i0, i1 + 1):
        cy = y0 + (i + 0.5) * res - pose[1]
        for j in range(j0, j1 + 1):
            c = grid[i, j]
            if c > 0.0:
                _add(
                    hist,
                    x0 + (j + 0.5) * res - pose[0],
                    cy,
                    c,
                    pose[2],
                    window,
                    enlarge,
                )


@nb.njit(**JIT)
def histogram_points(points, certainty, pose, window, enlarge, hist):
    """Polar obstacle density of weighted points (K, 2); as `histogram_grid`."""
    hist[:] = 0.0
    for k in range(points.shape[0]):
        _add(
            hist,
            points[k, 0] - pose[0],
            points[k, 1] - pose[1],
            certainty[k],
            pose[2],
            window,
            enlarge,
        )


@nb.njit(**JIT)
def smooth(hist, half, out):
    """Circular weighted average: ``out[k] = sum (half+1-|l|) h[k+l] / (2 half+1)``."""
    n = hist.shape[0]
    for k in range(n):
        acc = 0.0
        for m in range(-half, half + 1):
            acc += (half + 1 - abs(m)) * hist[(k + m) % n]
        out[k] = acc / (2 * half + 1)


@nb.njit(**JIT)
def potential_force(ranges, sensors, max_range, gx, gy, k_att, k_rep, d0, out):
    """Potential-field force in the robot frame from sonar and a goal.

    ``(gx, gy)``: the goal in the robot frame, m. Attraction: ``k_att`` times
    the unit vector to the goal, scaled down linearly within 1 m of it. Each
    echo (range below ``max_range``) whose endpoint lies at ``rho < d0`` from
    the robot's centre pushes away from it with
    ``k_rep * (1/rho - 1/d0) / rho**2``. Writes ``out[0], out[1]``.
    """
    dg = math.sqrt(gx * gx + gy * gy)
    fx, fy = 0.0, 0.0
    if dg > 0.0:
        scale = k_att * min(dg, 1.0) / dg
        fx, fy = scale * gx, scale * gy
    for k in range(sensors.shape[0]):
        r = ranges[k]
        if not r < max_range:
            continue
        ex = sensors[k, 0] + r * math.cos(sensors[k, 2])
        ey = sensors[k, 1] + r * math.sin(sensors[k, 2])
        rho = math.sqrt(ex * ex + ey * ey)
        if rho < d0 and rho > 0.0:
            mag = k_rep * (1.0 / rho - 1.0 / d0) / (rho * rho)
            fx -= mag * ex / rho
            fy -= mag * ey / rho
    out[0] = fx
    out[1] = fy


@nb.njit(**JIT)
def _sector_angle(k, n):
    """Centre of sector ``k`` (any integer or half-integer) of ``n``, rad."""
    return _wrap((k + 0.5) * 2.0 * math.pi / n - math.pi)


@nb.njit(**JIT)
def _cost(a, target, previous, mu_goal, mu_heading, mu_previous):
    return (
        mu_goal * abs(_wrap(a - target))
        + mu_heading * abs(a)
        + mu_previous * abs(_wrap(a - previous))
    )


@nb.njit(**JIT)
def plus_direction(blocked, target, previous, wide, mu_goal, mu_heading, mu_previous):
    """VFH+'s choice of direction among the free valleys' candidates.

    ``blocked`` (n,) bool, sector ``k`` centred on ``-pi + (k + 0.5) 2 pi / n``
    (robot frame). Candidates: for each valley (circular run of free
    sectors) of fewer than ``wide`` sectors its middle; for a wider one the
    sectors ``wide // 2`` in from each border, and the target itself if it
    lies between them. The candidate of least cost
    ``mu_goal |c - target| + mu_heading |c| + mu_previous |c - previous|``
    wins. Returns the direction, rad (nan if every sector is blocked).
    """
    n = blocked.shape[0]
    first = -1
    for k in range(n):
        if blocked[k]:
            first = k
            break
    if first < 0:
        return _wrap(target)
    alpha = 2.0 * math.pi / n
    kt = int(math.floor((_wrap(target) + math.pi) / alpha)) % n
    best = math.nan
    best_cost = math.inf
    k = 0
    while k < n:
        idx = (first + k) % n
        if blocked[idx]:
            k += 1
            continue
        start = first + k  # unwrapped index of the valley's first sector
        length = 0
        while k < n and not blocked[(first + k) % n]:
            length += 1
            k += 1
        stop = start + length - 1
        if length >= wide:
            half = wide // 2
            for c in (start + half, stop - half):
                a = _sector_angle(c, n)
                cost = _cost(a, target, previous, mu_goal, mu_heading, mu_previous)
                if cost < best_cost:
                    best, best_cost = a, cost
            # the target, if it lies between the two candidates
            off = (kt - start) % n
            if half <= off <= length - 1 - half:
                a = _wrap(target)
                cost = _cost(a, target, previous, mu_goal, mu_heading, mu_previous)
                if cost < best_cost:
                    best, best_cost = a, cost
        else:
            a = _sector_angle(start + (length - 1) / 2.0, n)
            cost = _cost(a, target, previous, mu_goal, mu_heading, mu_previous)
            if cost < best_cost:
                best, best_cost = a, cost
    return best


@nb.njit(**JIT)
def follow_direction(blocked, target, side, margin):
    """Boundary following on the binary histogram (the obstacle on one side).

    ``side = +1`` keeps the obstacle on the right: starting from the sector
    100 degrees to the right, walk counter-clockwise to the first free
    sector whose right-hand neighbour is blocked (a valley's right border)
    and steer ``margin`` sectors into the valley (at most to its middle).
    ``side = -1`` is the mirror image. Returns the direction, rad, robot
    frame; the target if no sector is blocked, nan if all are.
    """
    n = blocked.shape[0]
    alpha = 2.0 * math.pi / n
    n_blocked = 0
    for k in range(n):
        if blocked[k]:
            n_blocked += 1
    if n_blocked == 0:
        return _wrap(target)
    if n_blocked == n:
        return math.nan
    start = int(math.floor((-side * math.radians(100.0) + math.pi) / alpha))
    for m in range(n):
        k = start + side * m
        if not blocked[k % n] and blocked[(k - side) % n]:
            run = 0
            while run < n and not blocked[(k + side * run) % n]:
                run += 1
            step = min(margin, (run - 1) // 2)
            return _sector_angle(k + side * step, n)
    return math.nan


@nb.njit(**JIT)
def hysteresis(hist, low, high, blocked):
    """Make the histogram binary with hysteresis, in place.

    ``blocked[k]`` becomes True above ``high``, False below ``low``, and keeps
    its value in between.
    """
    for k in range(hist.shape[0]):
        if hist[k] > high:
            blocked[k] = True
        elif hist[k] < low:
            blocked[k] = False


@nb.njit(**JIT)
def vfh_step(
    grid, x0, y0, res, pose, sensors, ranges, max_range, half_cone, clear_range,
    inc, dec, cmax, fade_factor, window, enlarge, half, raw, hist, low, high,
    blocked, target, previous, wide, mu_goal, mu_heading, mu_previous,
):  # fmt: skip
    """Run one VFH+ cycle in one call (the same numbers as the calls one by one).

    `fade` (if ``fade_factor < 1``), `certainty_update`, `histogram_grid`
    into ``raw``, `smooth` into ``hist``, `hysteresis` on ``blocked``, then
    `plus_direction`. Returns the chosen direction (rad, robot frame).
    """
    if fade_factor < 1.0:
        fade(grid, x0, y0, res, pose[0], pose[1], max_range, fade_factor)
    certainty_update(
        grid, x0, y0, res, pose, sensors, ranges, max_range, half_cone,
        clear_range, inc, dec, cmax,
    )  # fmt: skip
    histogram_grid(grid, x0, y0, res, pose, window, enlarge, raw)
    smooth(raw, half, hist)
    hysteresis(hist, low, high, blocked)
    return plus_direction(
        blocked, target, previous, wide, mu_goal, mu_heading, mu_previous
    )


@nb.njit(**JIT)
def dwa_evaluate(
    points, vs, ws, steps, dt, radius, look, goal, free, heading, togo, gap
):
    """Roll out every velocity sample of the dynamic window against points.

    ``points`` (P, 2): obstacle points in the robot frame, m. ``vs`` (V,),
    ``ws`` (W,): the sampled translational (m/s) and rotational (rad/s)
    velocities; sample ``(i, j)`` drives the arc of ``(vs[i], ws[j])`` for
    ``steps`` steps of ``dt`` s from the origin, heading along x. A point
    stops the arc at the first step where it lies within ``radius`` m of
    the arc's pose and more than 1 mm nearer than at the start (a point already inside
    ``radius`` does not forbid moving away from it). Writes, per sample:
    ``free[i, j]``, the distance driven before that step, m (inf when
    nothing stops the arc, which is always so at ``v == 0``: turning on the
    spot moves no point nearer); ``heading[i, j]``, the absolute angle between
    the heading at the last pose driven and the direction from there to
    ``goal`` (2,), rad; ``togo[i, j]``, the distance from that pose to the
    goal, m; ``gap[i, j]``, the smallest distance between the disc and any
    point over the poses of steps 1 to the one that stopped the arc (or the
    last), m, at most ``look`` (points farther than the arc's reach plus
    ``look`` are not looked at).
    """
    n_pts = points.shape[0]
    d0 = np.empty(n_pts)
    near2 = np.empty(n_pts)  # squared distance a step must come under to stop
    r2 = radius * radius
    for p in range(n_pts):
        h = math.hypot(points[p, 0], points[p, 1])
        d0[p] = h - radius
        m = h - 1e-3
        near2[p] = min(r2, m * m) if m > 0.0 else -1.0
    idx = np.empty(n_pts, dtype=np.int64)
    for i in range(vs.shape[0]):
        v = vs[i]
        reach = v * steps * dt
        n_in = 0  # the points an arc of this speed can reach or pass near
        for p in range(n_pts):
            if d0[p] <= reach + look:
                idx[n_in] = p
                n_in += 1
        for j in range(ws.shape[0]):
            w = ws[j]
            f = math.inf
            g2 = (look + radius) ** 2  # the smallest squared distance seen
            x = 0.0
            y = 0.0
            th = 0.0
            for k in range(1, steps + 1):
                t = k * dt
                th_k = w * t
                if abs(w) > 1e-9:
                    xk = v / w * math.sin(th_k)
                    yk = v / w * (1.0 - math.cos(th_k))
                else:
                    xk = v * t
                    yk = 0.0
                hit = False
                for q in range(n_in):
                    p = idx[q]
                    ex = points[p, 0] - xk
                    ey = points[p, 1] - yk
                    e2 = ex * ex + ey * ey
                    g2 = min(g2, e2)
                    if e2 <= near2[p]:
                        hit = True
                if hit:
                    f = v * (t - dt)
                    break
                x = xk
                y = yk
                th = th_k
            free[i, j] = f
            gap[i, j] = math.sqrt(g2) - radius
            heading[i, j] = abs(_wrap(math.atan2(goal[1] - y, goal[0] - x) - th))
            togo[i, j] = math.hypot(goal[0] - x, goal[1] - y)
