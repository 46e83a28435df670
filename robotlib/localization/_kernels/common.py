"""Constants, the angle wrap and ``exp`` the localization kernels share.

``exp`` is the C library's ``exp`` called directly: numba's ``math.exp``
goes through a helper of its own, linked against glibc's old compatibility
wrapper (``exp@GLIBC_2.2.5``, which only adds error reporting around the
same function), three jumps a call. With glibc 2.29 or later ``exp`` binds
``exp@GLIBC_2.29``, the function itself: the same numbers (glibc computes
both with one routine; ``tests/test_localization_normals.py`` compares
them), about a fifth quicker a call. Elsewhere it is numba's own helper.
"""

import ctypes
import math

import llvmlite.binding as ll
import numba as nb
from numba import _helperlib, types

from ..._config import JIT


def _exp_address() -> int:
    """Address of glibc's ``exp@GLIBC_2.29``, else of numba's ``math.exp`` helper."""
    try:
        dlvsym = ctypes.CDLL(None).dlvsym
        dlvsym.restype = ctypes.c_void_p
        dlvsym.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_char_p]
        address = dlvsym(ctypes.CDLL("libm.so.6")._handle, b"exp", b"GLIBC_2.29")
    except (OSError, AttributeError, TypeError):  # not glibc (Windows: no CDLL(None))
        address = None
    return address or _helperlib.c_helpers["exp"]


ll.add_symbol("robotlib_exp", _exp_address())
exp = types.ExternalFunction("robotlib_exp", types.float64(types.float64))
"""``math.exp`` for the kernels (see the module's docstring): float64 only."""

_TWO_PI = 2.0 * math.pi
_LOG_SQRT_2PI = 0.5 * math.log(2.0 * math.pi)


@nb.njit(**JIT, inline="always")
def wrap(a):
    """Wrap an angle to (-pi, pi]."""
    w = a - _TWO_PI * math.floor((a + math.pi) / _TWO_PI)
    if w <= -math.pi:
        w += _TWO_PI
    elif w > math.pi:
        w -= _TWO_PI
    return w
