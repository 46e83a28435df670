"""The exact path's weighing fused with its cone casts: one pass over the particles.

`exact_beam` / `exact_paper` cast a particle's cones (`exact.expected_scan_blocks`)
and weigh its scan (`models.beam_one` / `models.paper_one`) in the same loop,
so the threaded versions wake the threads once per step instead of twice.
The same numbers as the two kernels one after the other. `exact_step` is
the whole filter step on that path in one call (`MCL.step`'s fused call).

Numba kernels: contiguous arrays and scalars in, no Python objects; they
import nothing of robotlib but the JIT options and other kernels.
"""

import numba as nb
import numpy as np

from ..._config import serial_and_parallel
from .chunked import _draw, _weigh_into
from .elementary import sincos
from .exact import _EXACT_CHUNK, _expected_pose_blocks, _lanes, _offsets, _turns
from .models import beam_one, paper_one
from .motion import _odometry_one


def _exact_beam(
    poses, sensors, walls, start, items, grid, n_rays, cone, max_range, min_range,
    cos_specular, zhat, z, z_hit, z_short, z_max, z_rand, sigma, lam_short, out,
):  # fmt: skip
    """`expected_scan_blocks` into ``zhat`` (N, S), then `beam_loglik` into ``out``.

    Pose by pose: ``out[k]`` is the beam model's log-likelihood of readings
    ``z`` (S,) given pose ``k``'s expected readings (``max_range`` is the
    sonar's, for both).
    """
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
                max_range, min_range, cos_specular, offs, ray, cand, pas, zhat,
            )  # fmt: skip
            beam_one(
                k, z, zhat, max_range, z_hit, z_short, z_max, z_rand, sigma,
                lam_short, out,
            )  # fmt: skip


exact_beam, exact_beam_parallel = serial_and_parallel(_exact_beam)


def _exact_paper(
    poses, sensors, walls, start, items, grid, n_rays, cone, max_range, min_range,
    cos_specular, zhat, z, n_weight, out,
):  # fmt: skip
    """`expected_scan_blocks` into ``zhat`` (N, S), then `paper_loglik` into ``out``.

    ``n_weight`` is the ``n`` of the ``1 / n`` term.
    """
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
                max_range, min_range, cos_specular, offs, ray, cand, pas, zhat,
            )  # fmt: skip
            paper_one(k, z, zhat, n_weight, out)


exact_paper, exact_paper_parallel = serial_and_parallel(_exact_paper)


# -- the whole step: move, cast, weigh, estimate (and resample) in one call ----------


def _exact_step(
    words, draw, particles, weights, noise, rot1, trans, rot2, sd1, sdt, sd2,
    sensors, walls, start, items, grid, n_rays, cone, max_range, min_range,
    cos_specular, z, beam, z_hit, z_short, z_max, z_rand, sigma, lam_short, exponent,
    n_weight, u, out_p, out_w, new_p, new_w, est, cs, zhat,
):  # fmt: skip
    """`MCL.step` on the exact path in one call: the numbers of its four stages.

    Moves ``particles`` (N, 3) by the odometry ``rot1, trans, rot2`` plus
    ``sd1, sdt, sd2`` times ``noise`` (N, 3) into ``out_p``
    (`motion.sample_odometry`), casts each moved particle's cones into
    ``zhat`` (N, S) and weighs its scan ``z`` into ``out_w``: the beam model
    (``beam``, `models.beam_one`, times ``exponent`` unless 1) or the
    paper's (`models.paper_one` with ``n_weight``); then updates
    ``weights`` (`weights.update_weights`), estimates the pose into ``est``
    (3,) and, when ``u >= 0``, resamples systematically with the draw ``u``
    into ``new_p``, ``new_w`` (`chunked`'s `_weigh_into`, the same sums in
    the same order). ``cs`` (N, 2) is scratch (the headings' cosines and
    sines). With ``draw``, ``noise`` and ``u`` are first drawn from the
    PCG64 state ``words`` (`chunked._draw`, as the filter's generator would).
    Returns ``(log_mean, ess)``.
    """
    u = _draw(words, draw, noise, u)
    turns = _turns(sensors)
    offs = _offsets(n_rays, cone)
    n = particles.shape[0]
    for q in nb.prange((n + _EXACT_CHUNK - 1) // _EXACT_CHUNK):
        ray = np.empty((3, _lanes(n_rays)))
        cand = np.empty(((walls.shape[0] + 63) // 64, _lanes(n_rays)), dtype=np.uint64)
        pas = np.empty(walls.shape[0], dtype=np.uint64)
        for k in range(q * _EXACT_CHUNK, min(n, (q + 1) * _EXACT_CHUNK)):
            _, _, th = _odometry_one(
                k, particles, rot1, trans, rot2, sd1, sdt, sd2, noise, out_p
            )
            cs[k, 1], cs[k, 0] = sincos(th)
            _expected_pose_blocks(
                k, out_p, sensors, turns, walls, start, items, grid, n_rays, cone,
                max_range, min_range, cos_specular, offs, ray, cand, pas, zhat,
            )  # fmt: skip
            if beam:
                beam_one(
                    k, z, zhat, max_range, z_hit, z_short, z_max, z_rand, sigma,
                    lam_short, out_w,
                )  # fmt: skip
                if exponent != 1.0:
                    out_w[k] *= exponent
            else:
                paper_one(k, z, zhat, n_weight, out_w)
    return _weigh_into(weights, out_p, cs, out_w, u, new_p, new_w, est)


exact_step, exact_step_parallel = serial_and_parallel(_exact_step)
