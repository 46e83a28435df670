"""Numba options shared by every kernel in robotlib (one place to change them).

Also `serial_and_parallel`, which compiles one kernel body both ways, and
`jit_inner` for helpers only kernels call (no Python wrapper). Only
kernels import this module, and the package's ``__init__`` (first, so that
numba is imported lean: `_import_numba`); it imports nothing of robotlib's but
`robotlib._kernel_cache`, which it runs once: cached kernels whose sources
changed are deleted before any is loaded, and the others load without
numba's full context refresh (`robotlib._kernel_cache.quick_loads`).

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
_kernel_cache.quick_loads()

JIT = {
    "cache": True,
    "nogil": True,
    "fastmath": False,
    "error_model": "numpy",
    "no_cfunc_wrapper": True,
}
"""Options for ``numba.njit`` on serial kernels.

``no_cfunc_wrapper``: numba otherwise builds, for every function it
compiles, a C-callable wrapper robotlib never calls (no kernel is passed as
a function pointer), about a tenth of a small kernel's compile time.
"""

JIT_INNER = {**JIT, "no_cpython_wrapper": True}
"""Options for ``numba.njit`` on helpers that only other kernels call (`jit_inner`).

``no_cpython_wrapper``: numba otherwise builds, for every function it
compiles, the wrapper that lets Python call it; a helper called only from
compiled code never uses it, and its callers link it again wherever they
call the helper. The helper's own machine code is the same, and so are its
callers'. Measured on an empty cache (`MCL.best`, one process, CPU): the
cone table's build 3.94 -> 3.41 s, the first step 3.31 -> 3.05 s.
"""


class _InnerDispatcher(nb.core.registry.CPUDispatcher):
    """A numba dispatcher that kernels call and Python cannot (`jit_inner`).

    numba would hand Python a function at address 0 for a helper compiled
    without its wrapper (a crash); this one keeps its compiled versions
    where kernels find them (``overloads``) and out of the table Python's
    calls look in, and refuses a call from Python with a `TypeError`.
    """

    def add_overload(self, cres):
        self.overloads[tuple(cres.signature.args)] = cres

    def _compile_for_args(self, *args, **kws):
        raise TypeError(
            f"{self.py_func.__qualname__} is a helper of robotlib's kernels: "
            "only compiled code calls it (robotlib._config.jit_inner)"
        )


def jit_inner(fn):
    """``numba.njit(**JIT_INNER)(fn)``, which a call from Python cannot crash."""
    dispatcher = nb.njit(**JIT_INNER)(fn)
    dispatcher.__class__ = _InnerDispatcher
    return dispatcher


JIT_PARALLEL = {**JIT, "parallel": True}
"""Options for ``numba.njit`` on kernels that loop with ``prange``."""


def serial_and_parallel(body, inner: bool = False):
    """Compile one kernel body twice: serially, and over threads.

    ``body`` loops over its particles (or poses) with ``numba.prange``, which
    numba runs as ``range`` when it compiles without ``parallel``. Each
    iteration must write only its own slots and every sum must run in a
    plain ``range`` loop, so the two compilations give the same bits.

    Parameters
    ----------
    body : function
        The plain Python function (not yet compiled).
    inner : bool
        Only other kernels call the serial one (`JIT_INNER`: no wrapper for
        Python's calls).

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
    serial = jit_inner(body) if inner else nb.njit(**JIT)(body)
    return serial, nb.njit(**JIT_PARALLEL)(twin)
