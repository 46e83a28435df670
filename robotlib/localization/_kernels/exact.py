"""Exact expected readings: each sonar cone cast against the walls near its sensor.

Numba kernels: contiguous arrays and scalars in, no Python objects; they
import nothing of robotlib but the JIT options and other kernels.
"""

import math

import numba as nb
import numpy as np

from ..._config import JIT, JIT_PARALLEL
from ...sensing._kernels import _EPS
from .common import _TWO_PI


@nb.njit(**JIT, inline="always")
def cone_echo_rays(
    sx, sy, sth, segments, count, n_rays, cone, max_range, cos_specular, ray
):  # fmt: skip
    """`robotlib.sensing._kernels.cone_echo`, walls in the outer loop, rays inner.

    The same number: each ray keeps its first nearest hit (the lowest index
    among equal distances) by `robotlib.sensing._kernels.ray_segments`'
    tests, step for step, written as selects so the compiler tests several
    rays per instruction; then the rays are taken in order as it does. The
    walls are the first ``count`` rows of ``segments``; ``ray`` (4,
    ``n_rays``) float64 is scratch (directions, nearest distance, wall index).
    """
    for r in range(n_rays):
        if n_rays == 1:
            a = sth
        else:
            a = sth - 0.5 * cone + cone * r / (n_rays - 1)
        ray[0, r] = math.cos(a)
        ray[1, r] = math.sin(a)
        ray[2, r] = np.inf
        ray[3, r] = -1.0
    for m in range(count):
        px = segments[m, 0]
        py = segments[m, 1]
        ex = segments[m, 2] - px
        ey = segments[m, 3] - py
        wx = px - sx
        wy = py - sy
        num = wx * ey - wy * ex
        fm = float(m)
        for r in range(n_rays):
            dx = ray[0, r]
            dy = ray[1, r]
            denom = dx * ey - dy * ex
            ok = not abs(denom) < _EPS
            d = denom if ok else 1.0  # no division by zero (nor its error)
            t = num / d
            s = (wx * dy - wy * dx) / d
            hit = ok & (not (t < 0.0 or t >= ray[2, r])) & (0.0 <= s) & (s <= 1.0)
            ray[2, r] = t if hit else ray[2, r]
            ray[3, r] = fm if hit else ray[3, r]
    echo = np.inf
    last = -1  # the wall whose normal is (nxn, nyn): rays often share it
    nxn = nyn = 0.0
    for r in range(n_rays):  # `_cone`'s echo test, without the bounce
        t = ray[2, r]
        m = int(ray[3, r])
        if m < 0 or t >= max_range or t >= echo:
            continue
        if m != last:
            ex = segments[m, 2] - segments[m, 0]
            ey = segments[m, 3] - segments[m, 1]
            length = math.sqrt(ex * ex + ey * ey)
            nxn = -ey / length
            nyn = ex / length
            last = m
        cos_inc = abs(ray[0, r] * nxn + ray[1, r] * nyn)
        if cos_inc >= cos_specular:
            echo = t
    return echo


_TOL = 1e-12
"""Margin of the pruning tests, relative to the coordinates' size (m)."""

_TOL_T = 1e-9
"""Relative margin of a ray's lower bound on its range."""


@nb.njit(**JIT, inline="always")
def cone_echo_pruned(
    sx, sy, sth, ux, uy, walls, items, every, lo, hi, n_rays, cone, max_range,
    cos_specular, offs, ray, cand, pas,
):  # fmt: skip
    """`robotlib.sensing._kernels.cone_echo` on some walls, casting few rays.

    The walls are rows ``items[lo:hi]`` of the `wall_table` ``walls`` (rows
    ``lo:hi`` if ``every``). The same number as
    `cone_echo` on those walls. A first pass, with each ray's direction
    approximated by turning the axis ``(ux, uy)`` (within 1e-14 of the
    cone's heading ``sth``) by the ray's offset (``offs`` (2, R): its cosine
    and sine), finds per ray the walls its line may cross (it cannot hit a
    wall whose end points both lie beyond one side of its line by more than
    `_TOL` times the coordinates' size, whatever the rounding of the exact
    test), and a lower bound on the range of any echo it can give: over the
    walls it may cross and may echo from (incidence within the specular
    angle, less 1e-9), the range to the wall's line less `_TOL_T` of it (no
    bound where the wall is almost parallel to the ray). The echo is the
    least range of the rays that echo, whatever their order: the rays are
    cast exactly (their own cosine and sine, `ray_segments`' tests against
    their walls in order) from the lowest bound up, until the next bound
    reaches the least echo so far or ``max_range``. Before the first pass,
    the walls beside both outermost rays' lines are dropped (the kept ones,
    in order, go to ``pas``, counted without a branch). ``ray`` (3, `_lanes`)
    float64, ``cand`` (ceil(M / 64), `_lanes`) uint64 (per ray, a bit per
    kept wall it may cross) and ``pas`` (M,) uint64 (the kept walls' rows)
    are scratch; the first pass is written as selects over whole vectors of
    rays (the last ray repeated).
    """
    lanes = ray.shape[1]
    for r in range(lanes):
        o = min(r, n_rays - 1)
        ray[0, r] = ux * offs[0, o] - uy * offs[1, o]
        ray[1, r] = uy * offs[0, o] + ux * offs[1, o]
        ray[2, r] = np.inf
    last = max(n_rays - 1, 0)
    d0x = ray[0, 0]
    d0y = ray[1, 0]
    d1x = ray[0, last]
    d1y = ray[1, last]
    npass = np.uint64(0)
    for q in range(lo, hi):
        m = np.uint64(q if every else items[np.uint64(q)])
        ax = walls[m, 0] - sx
        ay = walls[m, 1] - sy
        bx = walls[m, 2] - sx
        by = walls[m, 3] - sy
        tol = _TOL * (1.0 + abs(ax) + abs(ay) + abs(bx) + abs(by))
        c0 = d0x * ay - d0y * ax
        c1 = d0x * by - d0y * bx
        c2 = d1x * ay - d1y * ax
        c3 = d1x * by - d1y * bx
        # beside every ray's line when beside the two outermost rays' lines
        out = (min(min(c0, c1), min(c2, c3)) > 2.0 * tol) | (
            max(max(c0, c1), max(c2, c3)) < -2.0 * tol
        )
        pas[npass] = m
        npass += np.uint64(not out)
    for c in range((npass + np.uint64(63)) // np.uint64(64)):
        for r in range(lanes):
            cand[c, r] = 0
    for jj in range(npass):
        j = np.uint64(jj)
        m = pas[j]
        ax = walls[m, 0] - sx
        ay = walls[m, 1] - sy
        bx = walls[m, 2] - sx
        by = walls[m, 3] - sy
        tol = _TOL * (1.0 + abs(ax) + abs(ay) + abs(bx) + abs(by))
        ex = walls[m, 4]
        ey = walls[m, 5]
        nxn = walls[m, 6]
        nyn = walls[m, 7]
        flat = 1e-3 * (abs(ex) + abs(ey))
        num = ax * ey - ay * ex
        word = j >> np.uint64(6)
        bit = np.uint64(1) << (j & np.uint64(63))
        for r in range(lanes):  # as selects: several rays per instruction
            dxa = ray[0, r]
            dya = ray[1, r]
            ca = dxa * ay - dya * ax
            cb = dxa * by - dya * bx
            # the exact test cannot hit it (both ends beyond one side)
            miss = ((ca > tol) & (cb > tol)) | ((ca < -tol) & (cb < -tol))
            cand[word, r] |= np.uint64(0) if miss else bit
            den = dxa * ey - dya * ex
            bounded = (abs(den) >= flat) & (den != 0.0)  # else almost parallel
            ta = num / (den if bounded else 1.0)
            margin = _TOL_T * abs(ta) + _TOL
            lb = (ta - margin) if bounded else -np.inf
            take = (
                (not miss)
                & (abs(dxa * nxn + dya * nyn) >= cos_specular - 1e-9)  # may echo
                & (not (bounded & (ta + margin < 0.0)))  # not behind the sensor
                & (lb < ray[2, r])
            )
            ray[2, r] = lb if take else ray[2, r]
    echo = np.inf
    while True:
        first = -1
        low = min(echo, max_range)
        for r in range(n_rays):
            if ray[2, r] < low:
                low = ray[2, r]
                first = r
        if first < 0:
            return echo
        ray[2, first] = np.inf
        if n_rays == 1:
            a = sth
        else:
            a = sth - 0.5 * cone + cone * first / (n_rays - 1)
        dx = math.cos(a)
        dy = math.sin(a)
        best = np.inf
        best_m = np.uint64(0)
        found = False
        for c in range((npass + np.uint64(63)) // np.uint64(64)):
            bits = cand[c, first]
            q = np.uint64(64) * np.uint64(c)
            while bits:
                if bits & np.uint64(1):  # `ray_segments`' test, in order
                    m = pas[q]
                    ex = walls[m, 4]
                    ey = walls[m, 5]
                    denom = dx * ey - dy * ex
                    if not abs(denom) < _EPS:
                        wx = walls[m, 0] - sx
                        wy = walls[m, 1] - sy
                        t = (wx * ey - wy * ex) / denom
                        s = (wx * dy - wy * dx) / denom
                        if not (t < 0.0 or t >= best) and 0.0 <= s <= 1.0:
                            best = t
                            best_m = m
                            found = True
                bits >>= np.uint64(1)
                q += np.uint64(1)
        if not found or best >= max_range or best >= echo:
            continue
        if abs(dx * walls[best_m, 6] + dy * walls[best_m, 7]) >= cos_specular:
            echo = best


@nb.njit(**JIT)
def wall_table(segments):
    """Per wall ``x1, y1, x2, y2, ex, ey, nx, ny``, (M, 8): `cone_echo_pruned`'s.

    ``(ex, ey)`` the wall's vector and ``(nx, ny)`` its unit normal, each
    computed as `robotlib.sensing._kernels.cone_echo` computes them.
    """
    walls = np.empty((segments.shape[0], 8))
    for m in range(segments.shape[0]):
        ex = segments[m, 2] - segments[m, 0]
        ey = segments[m, 3] - segments[m, 1]
        length = math.sqrt(ex * ex + ey * ey)
        for t in range(4):
            walls[m, t] = segments[m, t]
        walls[m, 4] = ex
        walls[m, 5] = ey
        walls[m, 6] = -ey / length
        walls[m, 7] = ex / length
    return walls


@nb.njit(**JIT)
def _lanes(n_rays):
    """Scratch columns for ``n_rays`` rays: a whole number of 8-wide vectors."""
    return 8 * ((max(n_rays, 1) + 7) // 8)


@nb.njit(**JIT)
def _offsets(n_rays, cone):
    """Cosine and sine of each ray's offset from its cone's axis, (2, R)."""
    offs = np.empty((2, max(n_rays, 1)))
    offs[0, 0] = 1.0
    offs[1, 0] = 0.0
    for r in range(n_rays if n_rays > 1 else 0):
        off = -0.5 * cone + cone * r / (n_rays - 1)
        offs[0, r] = math.cos(off)
        offs[1, r] = math.sin(off)
    return offs


@nb.njit(**JIT)
def _expected_pose_blocks(
    k, poses, sensors, turns, walls, start, items, grid, n_rays, cone,
    max_range, min_range, cos_specular, offs, ray, cand, pas, out,
):  # fmt: skip
    x0, y0, inv_block, nbx, nby, n_sectors = grid
    inv_sector = n_sectors / _TWO_PI
    c = math.cos(poses[k, 2])
    s = math.sin(poses[k, 2])
    for i in range(sensors.shape[0]):
        ci = turns[i, 0]
        si = turns[i, 1]
        sx = poses[k, 0] + c * sensors[i, 0] - s * sensors[i, 1]
        sy = poses[k, 1] + s * sensors[i, 0] + c * sensors[i, 1]
        bx = math.floor((sx - x0) * inv_block)
        by = math.floor((sy - y0) * inv_block)
        every = True
        lo = 0
        hi = walls.shape[0]
        if 0 <= bx < nbx and 0 <= by < nby:
            a = poses[k, 2] + sensors[i, 2]
            sector = int((a - _TWO_PI * math.floor(a / _TWO_PI)) * inv_sector)
            b = (int(by) * int(nbx) + int(bx)) * n_sectors + min(sector, n_sectors - 1)
            every = False
            lo = start[b]
            hi = start[b + 1]
        echo = cone_echo_pruned(
            sx, sy, poses[k, 2] + sensors[i, 2], c * ci - s * si, s * ci + c * si,
            walls, items, every, lo, hi, n_rays, cone, max_range, cos_specular, offs,
            ray, cand, pas,
        )  # fmt: skip
        z = echo if echo < max_range else max_range
        out[k, i] = min(max(z, min_range), max_range)


@nb.njit(**JIT)
def _turns(sensors):
    """Cosine and sine of each sensor's heading on the robot, (S, 2)."""
    turns = np.empty((sensors.shape[0], 2))
    for i in range(sensors.shape[0]):
        turns[i, 0] = math.cos(sensors[i, 2])
        turns[i, 1] = math.sin(sensors[i, 2])
    return turns


@nb.njit(**JIT)
def expected_scan_blocks(
    poses, sensors, walls, start, items, grid, n_rays, cone, max_range, min_range,
    cos_specular, out,
):  # fmt: skip
    """`expected_scan` (of `robotlib.sensing._kernels`), each cone against nearby walls.

    ``walls`` is the `wall_table` of the segments. ``grid`` ``(x0, y0, 1 /
    side, nbx, nby, n_sectors)`` cuts the plane into square blocks and the
    sensor headings into sectors; the walls a sensor in block ``b`` heading
    into sector ``q`` may reach within ``max_range`` are the rows
    ``items[start[b * n_sectors + q]:start[b * n_sectors + q + 1]]`` of
    ``walls`` (`wall_blocks`). A sensor outside the blocks tests every wall.
    The same readings as `expected_scan` (`cone_echo_pruned`).
    """
    turns = _turns(sensors)
    offs = _offsets(n_rays, cone)
    ray = np.empty((3, _lanes(n_rays)))
    cand = np.empty(((walls.shape[0] + 63) // 64, _lanes(n_rays)), dtype=np.uint64)
    pas = np.empty(walls.shape[0], dtype=np.uint64)
    for k in range(poses.shape[0]):
        _expected_pose_blocks(
            k, poses, sensors, turns, walls, start, items, grid, n_rays, cone,
            max_range, min_range, cos_specular, offs, ray, cand, pas, out,
        )  # fmt: skip


_EXACT_CHUNK = 16
"""Poses one thread casts with one set of scratch arrays."""


@nb.njit(**JIT_PARALLEL)
def expected_scan_blocks_parallel(
    poses, sensors, walls, start, items, grid, n_rays, cone, max_range, min_range,
    cos_specular, out,
):  # fmt: skip
    """`expected_scan_blocks` with the poses spread over threads."""
    turns = _turns(sensors)
    offs = _offsets(n_rays, cone)
    n = poses.shape[0]
    for q in nb.prange((n + _EXACT_CHUNK - 1) // _EXACT_CHUNK):
        ray = np.empty((3, _lanes(n_rays)))
        cand = np.empty(((walls.shape[0] + 63) // 64, _lanes(n_rays)), dtype=np.uint64)
        pas = np.empty(walls.shape[0], dtype=np.uint64)
        for k in range(q * _EXACT_CHUNK, min(n, (q + 1) * _EXACT_CHUNK)):
            _expected_pose_blocks(
                k, poses, sensors, turns, walls, start, items, grid, n_rays, cone,
                max_range, min_range, cos_specular, offs, ray, cand, pas, out,
            )  # fmt: skip


@nb.njit(**JIT)
def _block_span(lo, hi, origin, side, count):
    """Blocks ``[first, last]`` of ``count`` whose span overlaps ``[lo, hi]``."""
    first = 0
    while first < count and origin + side * first + side < lo:
        first += 1
    last = first - 1
    while last + 1 < count and hi >= origin + side * (last + 1):
        last += 1
    return first, last


@nb.njit(**JIT)
def _outside_wedge(seg, k, bx0, by0, side, edges, q):
    """Whether wall ``k`` lies beyond every ray from the block into sector ``q``.

    The rays from the square block at ``(bx0, by0)`` of ``side`` m with
    directions in ``[a_lo, a_hi]`` (``a_hi - a_lo < pi``) sweep a region
    bounded by two lines: along ``a_hi`` through the block's corner furthest
    to its left, and along ``a_lo`` through the corner furthest to its right.
    A wall with both end points beyond one of them is outside. ``edges[q]``
    holds the two lines' outward normals, ``(-sin a_hi, cos a_hi, sin a_lo,
    -cos a_lo)`` (`_sector_edges`).
    """
    for edge in range(2):
        nx = edges[q, 2 * edge]
        ny = edges[q, 2 * edge + 1]
        bound = -np.inf
        for cx, cy in ((bx0, by0), (bx0 + side, by0), (bx0, by0 + side),
                       (bx0 + side, by0 + side)):  # fmt: skip
            bound = max(bound, nx * cx + ny * cy)
        bound += 1e-7
        if nx * seg[k, 0] + ny * seg[k, 1] > bound and (
            nx * seg[k, 2] + ny * seg[k, 3] > bound
        ):
            return True
    return False


@nb.njit(**JIT)
def _sector_edges(n_sectors, half):
    """Outward normals of each sector's two edge lines (`_outside_wedge`), (Q, 4)."""
    width = _TWO_PI / n_sectors
    edges = np.empty((n_sectors, 4))
    for q in range(n_sectors):
        a_lo = q * width - half
        a_hi = (q + 1) * width + half
        edges[q, 0] = -math.sin(a_hi)  # left of the a_hi edge
        edges[q, 1] = math.cos(a_hi)
        edges[q, 2] = math.sin(a_lo)  # right of the a_lo edge
        edges[q, 3] = -math.cos(a_lo)
    return edges


@nb.njit(**JIT)
def _wall_blocks(seg, xmin, ymin, side, nbx, nby, grow, n_sectors, half):
    """`wall_blocks` in two passes over the walls: count, then fill."""
    m = seg.shape[0]
    edges = _sector_edges(n_sectors, half)
    spans = np.empty((m, 4), dtype=np.int64)
    counts = np.zeros(nby * nbx * n_sectors + 1, dtype=np.int64)
    start = np.empty_like(counts)
    fill = np.empty(nby * nbx * n_sectors, dtype=np.int64)
    items = np.empty(0, dtype=np.int32)
    for fill_pass in range(2):
        if fill_pass == 1:
            total = 0
            for b in range(counts.shape[0]):  # cumulative counts
                total += counts[b]
                start[b] = total
            for b in range(fill.shape[0]):  # a loop: a slice copy compiles slowly
                fill[b] = start[b]
            items = np.empty(total, dtype=np.int32)
        for k in range(m):  # walls in order: each list keeps it
            if fill_pass == 0:
                bx0, bx1 = _block_span(
                    min(seg[k, 0], seg[k, 2]) - grow, max(seg[k, 0], seg[k, 2]) + grow,
                    xmin, side, nbx,
                )  # fmt: skip
                by0, by1 = _block_span(
                    min(seg[k, 1], seg[k, 3]) - grow, max(seg[k, 1], seg[k, 3]) + grow,
                    ymin, side, nby,
                )  # fmt: skip
                spans[k, 0], spans[k, 1], spans[k, 2], spans[k, 3] = bx0, bx1, by0, by1
            for by in range(spans[k, 2], spans[k, 3] + 1):
                for bx in range(spans[k, 0], spans[k, 1] + 1):
                    for q in range(n_sectors):
                        if n_sectors > 1 and _outside_wedge(
                            seg, k, xmin + side * bx, ymin + side * by, side, edges, q
                        ):
                            continue
                        b = (by * nbx + bx) * n_sectors + q
                        if fill_pass == 0:
                            counts[b + 1] += 1
                        else:
                            items[fill[b]] = k
                            fill[b] += 1
    return start, items


SECTORS = 16
"""Sensor-heading sectors per block of `wall_blocks` (fewer walls per cone)."""


def wall_blocks(segments, bounds, max_range, side=1.0, cone=None):
    """List the walls each block of ``side`` m may reach (`expected_scan_blocks`).

    A wall is listed for a block when its bounding box, grown by
    ``max_range`` (and 1e-6 m), overlaps the block: then and only then can a
    sensor in the block pass `robotlib.sensing._kernels.cone_walls`'s range test for
    it. With a ``cone`` (full width, rad) the lists are per block and per
    `SECTORS` sector of sensor heading, and a wall is left out of a sector's
    list when no ray of a cone from the block heading into the sector (its
    width widened by 1e-6 rad) can meet it; a cone of half a turn or more
    (or none given) gets one sector. Walls keep their order. Memory: the
    lists themselves, 4 bytes an entry (no block by wall table).

    Returns
    -------
    tuple
        ``(walls, start, items, grid)``: the segments' `wall_table` (M, 8),
        offsets (nby * nbx * n_sectors + 1,) int64, the walls of each list in
        turn (K,) int32 (rows of ``walls``), and ``(x0, y0, 1 / side, nbx,
        nby, n_sectors)``.
    """
    seg = np.ascontiguousarray(segments, dtype=np.float64).reshape(-1, 4)
    xmin, ymin, xmax, ymax = (float(v) for v in bounds)
    nbx = max(1, math.ceil((xmax - xmin) / side))
    nby = max(1, math.ceil((ymax - ymin) / side))
    n_sectors = 1
    half = 0.0
    if cone is not None:
        half = 0.5 * float(cone) + 1e-6
        if 2.0 * math.pi / SECTORS + 2.0 * half < math.pi - 1e-3:
            n_sectors = SECTORS
    start, items = _wall_blocks(
        seg, xmin, ymin, float(side), nbx, nby, float(max_range) + 1e-6,
        n_sectors, half,
    )  # fmt: skip
    grid = (xmin, ymin, 1.0 / side, nbx, nby, n_sectors)
    return wall_table(seg), start, items, grid
