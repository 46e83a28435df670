"""NumPy's PCG64 and its standard normals in numba, on the generator's own state.

A filter of a few particles draws 3 N standard normals and one uniform per
step from its ``numpy.random.Generator`` (PCG64). NumPy's call costs about
a microsecond and then a call through a pointer per number (13 ns each
here); numba's own support for a ``Generator`` argument costs 8 us to
unbox. These kernels compute the same numbers bit for bit on the four
64-bit words of the generator's state (`robotlib.localization.motion.pcg64_words`
lends them: an array over the generator's own memory, so a draw here
advances the Python generator exactly as NumPy's would):

- ``pcg64.h``'s step (state times the 128-bit multiplier plus the
  increment) and output (XSL-RR of the new state);
- ``next_double``: the top 53 bits times 2^-53 (``Generator.random``);
- NumPy's ziggurat (``random_standard_normal`` in ``distributions.c``,
  numba's tables, as `normals.fill`), filled in C order as
  ``Generator.standard_normal(out=...)`` fills.

``tests/localization/test_localization_normals.py`` checks them against NumPy.

Numba kernels: contiguous arrays and scalars in, no Python objects; they
import nothing of robotlib but the JIT options and `normals` (the tables).
"""

import numba as nb
import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

from ..._config import JIT
from .normals import _FI, _INV_R, _KI, _R, _WI  # the ziggurat's tables, one home

MULTIPLIER = 0x2360ED051FC65DA44385DF649FCCF645
"""PCG's default 128-bit multiplier (``PCG_DEFAULT_MULTIPLIER_128``)."""

_U64 = types.uint64


@intrinsic
def _step(typingctx, lo, hi, inc_lo, inc_hi):
    """``state * MULTIPLIER + inc`` mod 2^128, the words ``(lo, hi)``: LLVM's i128."""
    ret = types.UniTuple(_U64, 2)
    sig = ret(_U64, _U64, _U64, _U64)

    def codegen(context, builder, signature, args):
        i128 = ir.IntType(128)
        i64 = ir.IntType(64)
        shift = ir.Constant(i128, 64)

        def wide(a, b):
            return builder.or_(
                builder.zext(a, i128), builder.shl(builder.zext(b, i128), shift)
            )

        s = wide(args[0], args[1])
        r = builder.add(builder.mul(s, ir.Constant(i128, MULTIPLIER)), wide(*args[2:]))
        out = (builder.trunc(r, i64), builder.trunc(builder.lshr(r, shift), i64))
        return context.make_tuple(builder, ret, out)

    return sig, codegen


@nb.njit(**JIT, inline="always")
def _output(lo, hi):
    """XSL-RR: ``rotr64(hi ^ lo, hi >> 58)``."""
    x = hi ^ lo
    rot = hi >> np.uint64(58)
    return (x >> rot) | (x << ((np.uint64(64) - rot) & np.uint64(63)))


@nb.njit(**JIT, inline="always")
def _double(lo, hi):
    return np.float64(_output(lo, hi) >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@nb.njit(**JIT)
def fill_normals(words, out):
    """``out`` := standard normals, as ``Generator.standard_normal(out=out)``.

    ``words`` (4,) uint64: the state's low and high words, then the
    increment's; the state is written back. ``out`` is contiguous, any shape.
    """
    lo = words[0]
    hi = words[1]
    inc_lo = words[2]
    inc_hi = words[3]
    flat = out.reshape(out.size)
    for k in range(flat.shape[0]):
        while True:
            lo, hi = _step(lo, hi, inc_lo, inc_hi)
            r = _output(lo, hi)
            idx = r & np.uint64(0xFF)
            r = r >> np.uint64(8)
            sign = r & np.uint64(1)
            rabs = (r >> np.uint64(1)) & np.uint64(0x000FFFFFFFFFFFFF)
            x = np.float64(rabs) * _WI[idx]
            if sign & np.uint64(1):
                x = -x
            if rabs < _KI[idx]:
                break
            if idx == np.uint64(0):  # the tail
                while True:
                    lo, hi = _step(lo, hi, inc_lo, inc_hi)
                    xx = -_INV_R * np.log1p(-_double(lo, hi))
                    lo, hi = _step(lo, hi, inc_lo, inc_hi)
                    yy = -np.log1p(-_double(lo, hi))
                    if yy + yy > xx * xx:
                        break
                x = -(_R + xx) if (rabs >> np.uint64(8)) & np.uint64(1) else _R + xx
                break
            lo, hi = _step(lo, hi, inc_lo, inc_hi)
            if (_FI[idx - np.uint64(1)] - _FI[idx]) * _double(lo, hi) + _FI[
                idx
            ] < np.exp(-0.5 * x * x):
                break
        flat[k] = x
    words[0] = lo
    words[1] = hi


@nb.njit(**JIT)
def next_double(words):
    """One uniform in [0, 1), as ``Generator.random()``; advances ``words``."""
    lo, hi = _step(words[0], words[1], words[2], words[3])
    words[0] = lo
    words[1] = hi
    return _double(lo, hi)
