"""Plain NumPy references for robotlib.mapping's numba kernels (slow, obvious)."""

import math

import numpy as np


def cell_centres(shape, origin, res):
    ny, nx = shape
    xs = origin[0] + (np.arange(nx) + 0.5) * res
    ys = origin[1] + (np.arange(ny) + 0.5) * res
    return np.meshgrid(xs, ys)


def sonar_cone_increments(
    shape,
    origin,
    res,
    sx,
    sy,
    sth,
    z,
    half_cone,
    max_range,
    thickness,
    l_occ,
    l_free,
    sigma,
    max_weight,
):
    """Every cell centre tested by its polar coordinates about the sensor."""
    gx, gy = cell_centres(shape, origin, res)
    dx, dy = gx - sx, gy - sy
    r = np.hypot(dx, dy)
    phi = np.arctan2(dy, dx) - sth
    phi = np.arctan2(np.sin(phi), np.cos(phi))
    echo = z < max_range
    reach = z + thickness / 2 if echo else max_range
    inside = (np.abs(phi) <= half_cone) & (r <= reach) & (np.abs(phi) < math.pi / 2)
    w = 1.0 if echo else max_weight
    weight = w * (np.exp(-(phi**2) / (2 * sigma**2)) if sigma > 0 else 1.0)
    occ = echo & (r >= z - thickness / 2)
    return np.where(inside, np.where(occ, l_occ, l_free) * weight, 0.0)


def sonar_scan(
    L,
    origin,
    res,
    pose,
    sensors,
    ranges,
    half_cone,
    max_range,
    thickness,
    l_occ,
    l_free,
    sigma,
    max_weight,
    l_min,
    l_max,
):
    L = L.astype(np.float64).copy()
    x, y, th = pose
    for (ax, ay, ah), z in zip(sensors, ranges, strict=True):
        sx = x + math.cos(th) * ax - math.sin(th) * ay
        sy = y + math.sin(th) * ax + math.cos(th) * ay
        inc = sonar_cone_increments(
            L.shape,
            origin,
            res,
            sx,
            sy,
            th + ah,
            z,
            half_cone,
            max_range,
            thickness,
            l_occ,
            l_free,
            sigma,
            max_weight,
        )
        L = np.clip(L + inc, l_min, l_max)
    return L


def beam_cells(shape, origin, res, ox, oy, a, z, max_range):
    """Cells a beam crosses, in order: every crossing of a grid line, sorted by
    distance, and the cell at the middle of each piece between crossings."""
    length = z if z < max_range else max_range
    dx, dy = math.cos(a), math.sin(a)
    gx, gy = (ox - origin[0]) / res, (oy - origin[1]) / res
    ex, ey = gx + dx * length / res, gy + dy * length / res
    ts = [0.0, length]
    for g, e, d in ((gx, ex, dx), (gy, ey, dy)):
        if d != 0.0:
            lo, hi = sorted((g, e))
            lines = np.arange(math.floor(lo) + 1, math.ceil(hi))
            ts.extend(((lines - g) * res / d).tolist())
    ts = np.unique(np.clip(ts, 0.0, length))
    mids = np.append(0.5 * (ts[:-1] + ts[1:]), length)
    j = np.floor(gx + mids * dx / res).astype(int)
    i = np.floor(gy + mids * dy / res).astype(int)
    cells = []
    for c in zip(i.tolist(), j.tolist(), strict=True):
        if not cells or cells[-1] != c:
            cells.append(c)
    return cells


def laser_scan(
    L, origin, res, lpose, angles, ranges, max_range, l_occ, l_free, l_min, l_max
):
    L = L.astype(np.float64).copy()
    ny, nx = L.shape
    for a, z in zip(angles, ranges, strict=True):
        cells = beam_cells(
            L.shape, origin, res, lpose[0], lpose[1], lpose[2] + a, z, max_range
        )
        for k, (i, j) in enumerate(cells):
            if 0 <= i < ny and 0 <= j < nx:
                last = k == len(cells) - 1
                inc = l_occ if (last and z < max_range) else l_free
                L[i, j] = min(max(L[i, j] + inc, l_min), l_max)
    return L


def best_near(L, origin, res, px, py):
    j = math.floor((px - origin[0]) / res)
    i = math.floor((py - origin[1]) / res)
    p = np.full((3, 3), 0.5)  # off the grid: unknown
    for di in range(-1, 2):
        for dj in range(-1, 2):
            if 0 <= i + di < L.shape[0] and 0 <= j + dj < L.shape[1]:
                p[di + 1, dj + 1] = 1 / (1 + math.exp(-float(L[i + di, j + dj])))
    return p.max()


def laser_loglik(L, origin, res, lpose, angles, ranges, max_range, p_rand):
    total = 0.0
    for a, z in zip(angles, ranges, strict=True):
        if z >= max_range:
            continue
        px = lpose[0] + z * math.cos(lpose[2] + a)
        py = lpose[1] + z * math.sin(lpose[2] + a)
        total += math.log(p_rand + (1 - p_rand) * best_near(L, origin, res, px, py))
    return total


def sonar_loglik(
    L, origin, res, pose, sensors, ranges, half_cone, max_range, n_rays, p_rand
):
    total = 0.0
    x, y, th = pose
    for (ax, ay, ah), z in zip(sensors, ranges, strict=True):
        if z >= max_range:
            continue
        sx = x + math.cos(th) * ax - math.sin(th) * ay
        sy = y + math.sin(th) * ax + math.cos(th) * ay
        offs = np.linspace(-half_cone, half_cone, n_rays) if n_rays > 1 else [0.0]
        best = max(
            best_near(
                L,
                origin,
                res,
                sx + z * math.cos(th + ah + o),
                sy + z * math.sin(th + ah + o),
            )
            for o in offs
        )
        total += math.log(p_rand + (1 - p_rand) * best)
    return total


def sonar_beam_loglik(
    L, origin, res, pose, sensors, ranges, half_cone, max_range, n_rays, sigma,
    p_rand, occ, c_unknown, centre=False,
):  # fmt: skip
    """The sonar beam model, one ray point at a time (see the kernel's docstring).

    ``centre``: each ray marches to its first wall cell (up to ``z + 3
    sigma``) and reports the distance to that cell's centre; the nearest
    over the rays is the expected range.
    """
    ny, nx = L.shape

    def cell(px, py):
        return int(math.floor((py - origin[1]) / res)), int(
            math.floor((px - origin[0]) / res)
        )

    total = 0.0
    x, y, th = pose
    for (ax, ay, ah), z in zip(sensors, ranges, strict=True):
        if z >= max_range:
            continue
        sx = x + math.cos(th) * ax - math.sin(th) * ay
        sy = y + math.sin(th) * ax + math.cos(th) * ay
        zhat, q = math.inf, 0.0
        offs = np.linspace(-half_cone, half_cone, n_rays) if n_rays > 1 else [0.0]
        for k, o in enumerate(offs):
            a = (
                th
                + ah
                + (half_cone * (2.0 * k / (n_rays - 1) - 1.0) if n_rays > 1 else o)
            )
            d = 0.5 * res
            while d < z + 3 * sigma and (centre or d < zhat):
                i, j = cell(sx + d * math.cos(a), sy + d * math.sin(a))
                if 0 <= i < ny and 0 <= j < nx and L[i, j] > occ:
                    if centre:
                        cx = origin[0] + (j + 0.5) * res
                        cy = origin[1] + (i + 0.5) * res
                        zhat = min(zhat, math.hypot(cx - sx, cy - sy))
                    else:
                        zhat = d
                    break
                d += 0.5 * res
            i, j = cell(sx + z * math.cos(a), sy + z * math.sin(a))
            v = float(L[i, j]) if 0 <= i < ny and 0 <= j < nx else 0.0
            q = max(q, 1.0 - 1.0 / (1.0 + math.exp(v)))
        p = 0.0
        if zhat < math.inf:
            p = math.exp(-0.5 * ((z - zhat) / sigma) ** 2)
            if zhat < z - 3 * sigma:
                q = 0.0
        p = max(p, c_unknown * q)
        total += math.log(p_rand + (1 - p_rand) * p)
    return total


def bilinear_evidence(L, origin, res, px, py):
    """Positive log-odds at a point, bilinear between cell centres (0 off the grid)."""
    gx, gy = (px - origin[0]) / res - 0.5, (py - origin[1]) / res - 0.5
    j, i = math.floor(gx), math.floor(gy)
    fx, fy = gx - j, gy - i

    def ev(ii, jj):
        ok = 0 <= ii < L.shape[0] and 0 <= jj < L.shape[1]
        return max(float(L[ii, jj]), 0.0) if ok else 0.0

    return (1 - fy) * ((1 - fx) * ev(i, j) + fx * ev(i, j + 1)) + fy * (
        (1 - fx) * ev(i + 1, j) + fx * ev(i + 1, j + 1)
    )


def scan_fit(L, origin, res, pose, mount, angles, ranges, max_range):
    """The fit's score: `bilinear_evidence` summed at the returns' end points.

    Returns (``ranges < max_range``) seen by the laser at ``mount`` on a robot
    at ``pose`` (x, y, theta), in map ``L``.
    """
    x, y, th = pose
    lx = x + math.cos(th) * mount[0] - math.sin(th) * mount[1]
    ly = y + math.sin(th) * mount[0] + math.cos(th) * mount[1]
    return sum(
        bilinear_evidence(
            L,
            origin,
            res,
            lx + z * math.cos(th + mount[2] + a),
            ly + z * math.sin(th + mount[2] + a),
        )  # fmt: skip
        for a, z in zip(angles, ranges, strict=True)
        if z < max_range
    )


def match_laser(
    L, origin, res, pose, mount, angles, ranges, max_range, steps, levels, prior=(0, 0)
):
    """Hill-climb a pose to fit the scan's end points to the map (the kernel's rule).

    ``prior = (w_xy, w_th)``: the score less ``w_xy d^2 + w_th a^2`` from ``pose``.
    """

    def score(p):
        return (
            fit(p)
            - prior[0] * ((p[0] - pose[0]) ** 2 + (p[1] - pose[1]) ** 2)
            - (prior[1] * (p[2] - pose[2]) ** 2)
        )

    def fit(p):
        return scan_fit(L, origin, res, p, mount, angles, ranges, max_range)

    p = [float(v) for v in pose]
    best = score(p)
    return _hill_climb(score, p, best, steps, levels)


def points_box(xs, ys, origin, res, shape):
    """Cells of the points' bounding box, one more all round, clipped."""
    ny, nx = shape
    i = np.floor((np.asarray(ys) - origin[1]) / res)
    j = np.floor((np.asarray(xs) - origin[0]) / res)
    return (
        max(0, int(i.min()) - 1),
        min(ny - 1, int(i.max()) + 1),
        max(0, int(j.min()) - 1),
        min(nx - 1, int(j.max()) + 1),
    )


def laser_box(lpose, angles, ranges, max_range, origin, res, shape):
    z = np.minimum(ranges, max_range)
    a = lpose[2] + np.asarray(angles)
    xs = np.append(lpose[0] + z * np.cos(a), lpose[0])
    ys = np.append(lpose[1] + z * np.sin(a), lpose[1])
    return points_box(xs, ys, origin, res, shape)


def fit_curvature(L, origin, res, pose, mount, angles, ranges, max_range, h):
    """``(cxx, cxy, cyy)``: minus the second differences of the fit's score, per m^2.

    The score is the sum of `bilinear_evidence` at the returns' end points
    (``ranges < max_range``) seen from robot ``pose``; steps of ``h`` m in x
    and y, the heading held.
    """

    def score(x, y):
        p = (x, y, pose[2])
        return scan_fit(L, origin, res, p, mount, angles, ranges, max_range)

    x, y = pose[0], pose[1]
    f0 = score(x, y)
    cxx = (2 * f0 - score(x + h, y) - score(x - h, y)) / h**2
    cyy = (2 * f0 - score(x, y + h) - score(x, y - h)) / h**2
    cxy = -(
        score(x + h, y + h) - score(x + h, y - h) - score(x - h, y + h)
        + score(x - h, y - h)
    ) / (4 * h**2)  # fmt: skip
    return np.array([cxx, cxy, cyy])


def field_score(L, origin, res, pose, points, normals, occ, sigma, p_rand):
    """Likelihood-field log-likelihood of robot-frame end points (B, 2) at pose.

    Each end point: the nearest occupied cell centre (log-odds above ``occ``)
    among the whole grid's cells whose row and column are within one of the
    end point's; the distance along the end point's normal (B, 2; robot
    frame), or whole where the normal is (0, 0).
    """
    gx, gy = cell_centres(L.shape, origin, res)
    rows, cols = np.indices(L.shape)
    x, y, th = pose
    c, s = math.cos(th), math.sin(th)
    total = 0.0
    for (bx, by), (nx, ny) in zip(points, normals, strict=True):
        px, py = x + c * bx - s * by, y + s * bx + c * by
        i = math.floor((py - origin[1]) / res)
        j = math.floor((px - origin[0]) / res)
        near = (abs(rows - i) <= 1) & (abs(cols - j) <= 1) & (L > occ)
        if nx == 0 and ny == 0:
            d2 = (gx - px) ** 2 + (gy - py) ** 2
        else:
            d2 = ((gx - px) * (c * nx - s * ny) + (gy - py) * (s * nx + c * ny)) ** 2
        d2 = d2[near]
        p = math.exp(-d2.min() / (2 * sigma**2)) if d2.size else 0.0
        total += math.log(p_rand + (1 - p_rand) * p)
    return total


def scan_normals(mount, angles, ranges, max_range, bend):
    """Each return's end point and normal (robot frame), one beam at a time."""
    pts, nrm = [], []
    ends = [
        (
            mount[0] + z * math.cos(mount[2] + a),
            mount[1] + z * math.sin(mount[2] + a),
        )
        for a, z in zip(angles, ranges, strict=True)
    ]
    for r, z in enumerate(ranges):
        if z >= max_range:
            continue
        pts.append(ends[r])
        n = (0.0, 0.0)
        if 0 < r < len(ranges) - 1 and max(ranges[r - 1], ranges[r + 1]) < max_range:
            (ax, ay), (bx, by) = ends[r - 1], ends[r + 1]
            length = math.hypot(bx - ax, by - ay)
            if 0 < length < 2.0:
                cand = (-(by - ay) / length, (bx - ax) / length)
                px, py = ends[r]
                if abs((px - ax) * cand[0] + (py - ay) * cand[1]) <= bend:
                    n = cand
        nrm.append(n)
    return np.array(pts), np.array(nrm)


def motion_log_prior(q, u, sig):
    """Gaussian log-density (less its constant) of pose q about u, u's frame."""
    dx, dy = q[0] - u[0], q[1] - u[1]
    along = math.cos(u[2]) * dx + math.sin(u[2]) * dy
    across = -math.sin(u[2]) * dx + math.cos(u[2]) * dy
    turn = math.atan2(math.sin(q[2] - u[2]), math.cos(q[2] - u[2]))
    z = np.array([along, across, turn]) / np.asarray(sig)
    return -0.5 * float(z @ z)


def fit_pose(
    L, origin, res, pred, points, normals, field, temperature, sig, steps, levels
):
    """Hill-climb ``pred`` on ``temperature * field_score + motion_log_prior``.

    ``field = (occ, sigma, p_rand)``; the kernel's rule: the best of six
    moves while one raises the objective (at most 20), then halve the steps.
    """

    def objective(p):
        ll = field_score(L, origin, res, p, points, normals, *field)
        return temperature * ll + motion_log_prior(p, pred, sig)

    p = [float(v) for v in pred]
    best = temperature * field_score(L, origin, res, p, points, normals, *field)
    return _hill_climb(objective, p, best, steps, levels)


def _hill_climb(objective, p, best, steps, levels):
    """Return the pose the kernels' hill climb reaches from ``p``, angle wrapped.

    The best of six moves while one raises ``objective`` above ``best`` (at
    most 20), then halve ``steps = (xy, theta)``; ``levels`` times.
    """
    sxy, sth = steps
    for _ in range(levels):
        for _ in range(20):
            moves = [(sxy, 0, 0), (-sxy, 0, 0), (0, sxy, 0), (0, -sxy, 0)]
            moves += [(0, 0, sth), (0, 0, -sth)]
            cands = [[p[0] + dx, p[1] + dy, p[2] + dt] for dx, dy, dt in moves]
            vals = [objective(q) for q in cands]
            k = int(np.argmax(vals))
            if vals[k] <= best:
                break
            best, p = vals[k], cands[k]
        sxy, sth = sxy / 2, sth / 2
    return np.array([p[0], p[1], math.atan2(math.sin(p[2]), math.cos(p[2]))])
