"""``exp``, ``sin`` and ``cos`` for the localization kernels, as plain arithmetic.

The C library's functions are calls the compiler cannot look into: a loop
over particles calls them one number at a time (4 ns an ``exp``, 11-14 ns
a sine and cosine here). Written as arithmetic, they are inlined, and a
loop of them runs on the processor's vector lanes: about four times
quicker for ``exp`` and eight for ``sincos``. They are also the same
numbers on every machine: only additions, multiplications, divisions,
``floor`` and exact scalings by powers of two, in IEEE 754 double (the
kernels compile without fast-math, so nothing is contracted or
reordered), where the C library's results may change with its version or
with the processor it picks a variant for.

The methods are the classic ones (as in Sun's fdlibm, whose published
coefficients these are): ``exp`` reduces ``x = k ln 2 + r`` with ``ln 2``
in two parts and corrects a rational approximation of ``exp(r)``
(|r| <= ln 2 / 2); ``sincos`` reduces ``x = k pi/2 + r`` with ``pi/2`` in
three parts and evaluates the minimax polynomials of sine and cosine on
|r| <= pi/4, the quadrant choosing which and with what sign.
``tests/localization/test_localization_elementary.py`` measures them against the
C library: ``exp`` within 1 ulp; ``sin`` and ``cos`` within 1 ulp on
headings, with the absolute error near their zeros below 1e-31 (1 + |x|).

Numba functions, inlined where called: float64 scalars in and out.
"""

import numba as nb
import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

from ..._config import JIT

__all__ = ["exp", "log", "sincos"]


@intrinsic
def _to_bits(typingctx, x):
    """Return the int64 whose bit pattern is the float64 ``x``'s (IEEE 754)."""
    sig = types.int64(types.float64)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(64))

    return sig, codegen


@intrinsic
def _from_bits(typingctx, bits):
    """Return the float64 whose IEEE 754 bit pattern is the int64 ``bits``."""
    sig = types.float64(types.int64)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.DoubleType())

    return sig, codegen


_INV_LN2 = 1.44269504088896338700e00
_LN2_HI = 6.93147180369123816490e-01  # ln 2's first 32 bits: k * _LN2_HI is exact
_LN2_LO = 1.90821492927058770002e-10
_P1 = 1.66666666666666019037e-01
_P2 = -2.77777777770155933842e-03
_P3 = 6.61375632143793436117e-05
_P4 = -1.65339022054652515390e-06
_P5 = 4.13813679705723846039e-08
_X_REACH = 1400.0  # beyond +-1400, exp is 0 or inf: k stays within two scalings


@nb.njit(**JIT, inline="always")
def exp(x):
    """``e ** x`` within 1 ulp (0 below about -745.1, inf above 709.78; NaN kept).

    No branch: the clamps and the choice of ``k`` are selects, so a loop
    of it is vectorized. ``2 ** k`` is applied as two exact powers of two
    (each of whose exponent field stays in range for |k| <= 2020), so
    results in the subnormal range are rounded once, at the second.
    """
    x = x if not (x < -_X_REACH) else -_X_REACH  # NaN passes
    x = x if not (x > _X_REACH) else _X_REACH
    fk = np.floor(x * _INV_LN2 + 0.5)
    hi = x - fk * _LN2_HI
    lo = fk * _LN2_LO
    r = hi - lo
    t = r * r
    c = r - t * (_P1 + t * (_P2 + t * (_P3 + t * (_P4 + t * _P5))))
    y = 1.0 - ((lo - (r * c) / (2.0 - c)) - hi)
    k = np.int64(fk) if fk == fk else np.int64(0)
    k1 = k >> 1
    return y * _from_bits((k1 + 1023) << 52) * _from_bits((k - k1 + 1023) << 52)


_S1 = -1.66666666666666324348e-01
_S2 = 8.33333333332248946124e-03
_S3 = -1.98412698298579493134e-04
_S4 = 2.75573137070700676789e-06
_S5 = -2.50507602534068634195e-08
_S6 = 1.58969099521155010221e-10
_C1 = 4.16666666666666019037e-02
_C2 = -1.38888888888741095749e-03
_C3 = 2.48015872894767294178e-05
_C4 = -2.75573143513906633035e-07
_C5 = 2.08757232129817482790e-09
_C6 = -1.13596475577881948265e-11
_INV_PIO2 = 6.36619772367581382433e-01
_PIO2_1 = 1.57079632673412561417e00  # pi/2 in three 33-bit parts:
_PIO2_2 = 6.07710050630396597660e-11  # k times each is exact for |k| < 2^20
_PIO2_3 = 2.02226624871116645580e-21


@nb.njit(**JIT, inline="always")
def sincos(x):
    """``(sin x, cos x)`` for an angle ``x``, rad.

    Within 1 ulp of the C library's for |x| up to a few turns (headings:
    the kernels' use), apart from arguments near a multiple of pi/2 where
    the result is near 0: there the error is below 1e-31 (1 + |x|)
    absolute (pi/2's fourth part, left out). The
    reduction is exact for |x| < 2^20 pi/2 (about 1.6e6 rad); beyond it the
    error grows with |x|. Infinite or NaN ``x`` gives NaNs. No branch (the
    quadrant is a float and its choices selects), so a loop of it is
    vectorized.
    """
    fk = np.floor(x * _INV_PIO2 + 0.5)
    r = ((x - fk * _PIO2_1) - fk * _PIO2_2) - fk * _PIO2_3
    z = r * r
    s = r + (z * r) * (_S1 + z * (_S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))))
    p = z * (_C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * (_C5 + z * _C6)))))
    hz = 0.5 * z
    w = 1.0 - hz
    c = w + (((1.0 - w) - hz) + z * p)
    q = fk - 4.0 * np.floor(fk * 0.25)  # the quadrant, 0..3
    odd = q == 1.0 or q == 3.0
    sn = c if odd else s
    cn = s if odd else c
    sn = -sn if q >= 2.0 else sn
    cn = -cn if (q == 1.0 or q == 2.0) else cn
    return sn, cn


_LG1 = 6.666666666666735130e-01
_LG2 = 3.999999999940941908e-01
_LG3 = 2.857142874366239149e-01
_LG4 = 2.222219843214978396e-01
_LG5 = 1.818357216161805012e-01
_LG6 = 1.531383769920937332e-01
_LG7 = 1.479819860511658591e-01
_SQRT2 = 1.4142135623730951
_TINY = 2.2250738585072014e-308  # the least normal float64
_TWO54 = 1.8014398509481984e16
_MANTISSA = (1 << 52) - 1
_ONE_BITS = 1023 << 52


@nb.njit(**JIT, inline="always")
def log(x):
    """Natural log of ``x`` within 1 ulp (-inf at 0, NaN below, inf and NaN kept).

    ``x = 2^k m`` with ``m`` in [sqrt(2)/2, sqrt(2)), ``f = m - 1`` exact,
    then ``log(1 + f)`` from a polynomial in ``s = f / (2 + f)``. No branch
    (subnormal ``x`` is scaled by 2^54 first, the special values are
    selects), so a loop of it is vectorized.
    """
    sub = x < _TINY
    xs = x * _TWO54 if sub else x
    hx = _to_bits(xs)
    k = (hx >> 52) - 1023 - (54 if sub else 0)
    m = _from_bits((hx & _MANTISSA) | _ONE_BITS)  # in [1, 2)
    big = m > _SQRT2
    m = m * 0.5 if big else m
    fk = float(k + (1 if big else 0))
    f = m - 1.0
    hfsq = 0.5 * f * f
    s = f / (2.0 + f)
    z = s * s
    w = z * z
    t1 = w * (_LG2 + w * (_LG4 + w * _LG6))
    t2 = z * (_LG1 + w * (_LG3 + w * (_LG5 + w * _LG7)))
    r = t2 + t1
    y = fk * _LN2_HI - ((hfsq - (s * (hfsq + r) + fk * _LN2_LO)) - f)
    y = y if x < np.inf else x  # inf, and NaN (compares false)
    y = -np.inf if x == 0.0 else y
    return np.nan if x < 0.0 else y
