"""Numba options shared by every kernel in robotlib (one place to change them).

Also `serial_and_parallel`, which compiles one kernel body both ways. Only
kernels import this module, and the package's ``__init__`` (first, so that
numba is imported lean: `_import_numba`); it imports nothing of robotlib's but
`robotlib._kernel_cache`, which it runs once: cached kernels whose sources
changed are deleted before any is loaded. Everything here uses numba's
public API only (``numba.njit`` and its options).

Threads wait passively: unless the environment says otherwise
(``OMP_WAIT_POLICY`` or ``GOMP_SPINCOUNT`` set), importing this module sets
``OMP_WAIT_POLICY=PASSIVE`` before numba starts its OpenMP threads, so a
thread with no work sleeps instead of spinning. On a machine shared with
other work the spinning default made the median step of 10,000 particles
over a hundred times its fastest; ``bench/bench_threads.py`` compares the
layers and policies.
"""

import os
import sys
import types

if "OMP_WAIT_POLICY" not in os.environ and "GOMP_SPINCOUNT" not in os.environ:
    os.environ["OMP_WAIT_POLICY"] = "PASSIVE"


def _import_numba():
    """Import numba without the two optional packages it has no use for here.

    When installed, numba imports ``coverage`` (to report lines of compiled
    code to a measurement already running: none is when coverage is not
    imported yet) and ``yaml`` (to read a ``.numba_config.yaml`` in the
    working folder: none there). Skipping them saves a tenth of the warm
    start's imports. Either is imported as usual when already imported or
    needed; once numba is in, both import normally again.
    """
    skipped = []
    if "numba" not in sys.modules:
        if "coverage" not in sys.modules:
            skipped.append("coverage")
        if "yaml" not in sys.modules and not os.path.exists(".numba_config.yaml"):
            skipped.append("yaml")
    for name in skipped:
        sys.modules[name] = None  # makes `import name` raise ImportError
    try:
        import numba
    finally:
        for name in skipped:
            if name in sys.modules and sys.modules[name] is None:
                del sys.modules[name]
    return numba


nb = _import_numba()  # after the wait policy: libgomp reads it once

from . import _kernel_cache  # noqa: E402  (numba first)

_kernel_cache.check()

JIT = {
    "cache": True,
    "nogil": True,
    "fastmath": False,
    "error_model": "numpy",
}
"""Options for ``numba.njit`` on serial kernels (all documented ``njit`` options).

Helpers that only kernels call take the same options, plus
``inline="always"`` where inlining pays (small per-particle pieces).
"""

JIT_PARALLEL = {**JIT, "parallel": True}
"""Options for ``numba.njit`` on kernels that loop with ``prange``."""


def serial_and_parallel(body):
    """Compile one kernel body twice: serially, and over threads.

    ``body`` loops over its particles (or poses) with ``numba.prange``, which
    numba runs as ``range`` when it compiles without ``parallel``. Each
    iteration must write only its own slots and every sum must run in a
    plain ``range`` loop, so the two compilations give the same bits.

    Parameters
    ----------
    body : function
        The plain Python function (not yet compiled).

    Returns
    -------
    tuple of numba dispatchers
        ``(serial, parallel)``. The parallel one compiles a copy of ``body``
        named ``<name>_parallel``, so numba caches the two apart.
    """
    twin = types.FunctionType(
        body.__code__, body.__globals__, body.__name__ + "_parallel",
        body.__defaults__, body.__closure__,
    )  # fmt: skip
    twin.__qualname__ = body.__qualname__ + "_parallel"
    twin.__doc__ = body.__doc__
    return nb.njit(**JIT)(body), nb.njit(**JIT_PARALLEL)(twin)
