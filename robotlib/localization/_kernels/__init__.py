"""Numba kernels for Monte Carlo localization, one module per concern.

- `common`: the angle wrap and shared constants
- `elementary`: ``exp``, ``log``, ``sin`` and ``cos`` as inlined arithmetic
  (vector lanes; the same bits on every machine)
- `motion`: particles moved by an odometry increment plus drawn noise
- `tables`: cone tables (expected ranges per cell and heading bin), built and read
- `table_strips`: the cone-table builder for dense maps (rays through strips)
- `strip_lists`: the walls of each direction's strips, for `table_strips`
- `exact`: expected ranges by cone casts against the walls near each sensor
- `exact_models`: those casts fused with the weighing, and the whole exact-path step
- `models`: the paper's, the beam and the likelihood-field models on expected ranges
- `table_models`: the paper's and the beam model read straight from a cone table
- `weights`: the Bayes update, normalisation, effective sample size, the estimate
- `resample`: cumulative weights, index searches, KLD-sampling, gathering
- `fused`: predict, read the table, weigh, normalise and estimate in one call
- `by_reading`: the serial fused steps, entries laid out reading by reading
- `chunked`: the fused step in chunks for a pool of Python threads, and in
  one call with the resampling for a few particles
- `normals`: NumPy's keyed motion noise (SeedSequence, SFC64, ziggurat)
  in compiled code, for the threaded steps that draw their own
- `pcg64`: NumPy's PCG64 and its normals on a generator's own state, for
  the one-call step of a few particles (`chunked.beam_small`) that draws
  its noise and resampling draw itself

Every kernel takes contiguous arrays and scalars only; random numbers are
drawn by the caller's ``numpy.random.Generator`` and passed in, or (the
threaded steps from 65,536 particles) drawn in the kernel from a key the
caller's generator drew, or (the one-call step below 4,096) drawn from the
caller's PCG64 state itself, as NumPy would draw them, so a seed
reproduces a run bit for bit. A kernel wanted both serially and over threads
is written once, looping with ``numba.prange``, and compiled twice
(`robotlib._config.serial_and_parallel`): its iterations write only their
own slots and its sums run serially, so both forms give identical results.
The kernels import nothing of robotlib but the JIT options and the world's
and sensing's kernels. Units: metres, radians; tables hold millimetres
(uint16).
"""

from .by_reading import beam_table_step, paper_table_step
from .common import wrap
from .exact import expected_scan_blocks, expected_scan_blocks_parallel, wall_blocks
from .fused import (
    lut_table_step_keyed_parallel,
    lut_table_step_parallel,
    paper_lut_step_keyed_parallel,
    paper_lut_step_parallel,
)
from .models import (
    beam_loglik,
    beam_loglik_parallel,
    field_loglik,
    field_loglik_parallel,
    paper_loglik,
)
from .motion import sample_odometry, sample_odometry_parallel
from .resample import (
    cumulative,
    gather,
    kld_bound,
    kld_resample,
    outside,
    search_indexes,
    sorted_indexes,
    systematic_gather,
)
from .table_models import (
    beam_norms,
    beam_scan_lut,
    beam_skip,
    beam_table_loglik,
    beam_table_loglik_parallel,
    lut_table_loglik_parallel,
    paper_table_loglik,
    paper_table_loglik_parallel,
)
from .tables import (
    build_cone_table,
    build_cone_table_indexed,
    build_cone_table_strips,
    compile_sweep_helpers,
    cone_table_cells,
    expected_table,
    expected_table_parallel,
)
from .weights import (
    position_spread,
    update_weights,
    update_weights_parallel,
    weighted_pose_mean,
    weighted_pose_mean_parallel,
)

__all__ = [
    "beam_loglik",
    "beam_loglik_parallel",
    "beam_norms",
    "beam_scan_lut",
    "beam_skip",
    "beam_table_loglik",
    "beam_table_loglik_parallel",
    "beam_table_step",
    "build_cone_table",
    "build_cone_table_indexed",
    "build_cone_table_strips",
    "compile_sweep_helpers",
    "cone_table_cells",
    "cumulative",
    "expected_scan_blocks",
    "expected_scan_blocks_parallel",
    "expected_table",
    "expected_table_parallel",
    "field_loglik",
    "field_loglik_parallel",
    "gather",
    "kld_bound",
    "kld_resample",
    "lut_table_loglik_parallel",
    "lut_table_step_keyed_parallel",
    "lut_table_step_parallel",
    "outside",
    "paper_loglik",
    "paper_lut_step_keyed_parallel",
    "paper_lut_step_parallel",
    "paper_table_loglik",
    "paper_table_loglik_parallel",
    "paper_table_step",
    "position_spread",
    "sample_odometry",
    "sample_odometry_parallel",
    "search_indexes",
    "sorted_indexes",
    "systematic_gather",
    "update_weights",
    "update_weights_parallel",
    "wall_blocks",
    "weighted_pose_mean",
    "weighted_pose_mean_parallel",
    "wrap",
]
