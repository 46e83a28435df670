"""Constants and the angle wrap the localization kernels share.

Their ``exp``, ``sin`` and ``cos`` are `elementary`'s.
"""

import math

import numba as nb

from ..._config import JIT

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
