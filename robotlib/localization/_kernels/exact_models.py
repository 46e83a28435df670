"""The exact path's weighing fused with its cone casts: one pass over the particles.

`exact_beam` / `exact_paper` cast a particle's cones (`exact.expected_scan_blocks`)
and weigh its scan (`models.beam_one` / `models.paper_one`) in the same loop,
so the threaded versions wake the threads once per step instead of twice.
The same numbers as the two kernels one after the other.

Numba kernels: contiguous arrays and scalars in, no Python objects; they
import nothing of robotlib but the JIT options and other kernels.
"""

import numba as nb
import numpy as np

from ..._config import serial_and_parallel
from .exact import _EXACT_CHUNK, _expected_pose_blocks, _lanes, _offsets, _turns
from .models import beam_one, paper_one


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
