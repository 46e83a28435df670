"""Numba options shared by every kernel in robotlib (one place to change them)."""

JIT = {"cache": True, "nogil": True, "fastmath": False, "error_model": "numpy"}
"""Options for ``numba.njit`` on serial kernels."""

JIT_PARALLEL = {**JIT, "parallel": True}
"""Options for ``numba.njit`` on kernels that loop with ``prange``."""
