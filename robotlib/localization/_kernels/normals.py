"""Keyed standard normals in numba: NumPy's numbers, without NumPy's objects.

`robotlib.localization.motion.standard_normals` draws the motion noise of
many particles in chunks: chunk ``c`` of a step keyed ``key`` is
``Generator(SFC64(SeedSequence([key, c]))).standard_normal``. Making those
three objects costs tens of microseconds a chunk in Python, and NumPy's
fill calls its generator through a pointer for every number. These kernels
compute the same numbers bit for bit, in compiled code: `SeedSequence`'s
hashing of ``[key, c]`` (NumPy's ``bit_generator.pyx``), SFC64's seeding
and steps (``sfc64.h``) and NumPy's ziggurat (``random_standard_normal`` in
``distributions.c``, as numba's own port, whose tables this module uses).
``tests/localization/test_localization_normals.py`` checks them against NumPy.

The threaded kernels of `fused` from 65,536 particles draw their noise
with them (`fused.move_and_read_keyed_parallel`). Below, the steps keep
NumPy's generators: these kernels take about two seconds to compile, which
a cold start of a smaller filter would pay.

Numba kernels: contiguous arrays and scalars in, no Python objects; they
import nothing of robotlib but the JIT options.
"""

import numba as nb
import numpy as np
from numba.np.random import _constants as _zig

from ..._config import JIT

_WI = _zig.wi_double
_KI = _zig.ki_double
_FI = _zig.fi_double
_R = _zig.ziggurat_nor_r
_INV_R = _zig.ziggurat_nor_inv_r

_M32 = np.uint64(0xFFFFFFFF)
_INIT_A = np.uint64(0x43B0D7E5)
_MULT_A = np.uint64(0x931E8875)
_INIT_B = np.uint64(0x8B51F9DD)
_MULT_B = np.uint64(0x58F38DED)
_MIX_L = np.uint64(0xCA01F9DD)
_MIX_R = np.uint64(0x4973F715)
_U16 = np.uint64(16)
_U32 = np.uint64(32)


@nb.njit(**JIT)
def sfc64_state(key, chunk, s):
    """``SFC64(SeedSequence([key, chunk]))``'s state into ``s`` (4,) uint64.

    ``key`` in [0, 2^63), ``chunk`` in [0, 2^32). SeedSequence's hashing on
    32-bit words held in uint64 (masked after each product), written out
    without helpers (a third less compile time).
    """
    k = np.uint64(key)
    ent = np.zeros(4, dtype=np.uint64)  # `_coerce_to_uint32_array([key, chunk])`
    ent[0] = k & _M32
    m = 1
    if (k >> _U32) != np.uint64(0):
        ent[1] = k >> _U32
        m = 2
    ent[m] = np.uint64(chunk) & _M32
    m += 1
    pool = np.zeros(4, dtype=np.uint64)  # `mix_entropy`, pool size 4
    hc = _INIT_A
    for i in range(4):
        v = ent[i] if i < m else np.uint64(0)
        v = (v ^ hc) & _M32  # `hashmix`
        hc = (hc * _MULT_A) & _M32
        v = (v * hc) & _M32
        pool[i] = v ^ (v >> _U16)
    for i_src in range(4):
        for i_dst in range(4):
            if i_src != i_dst:
                v = (pool[i_src] ^ hc) & _M32
                hc = (hc * _MULT_A) & _M32
                v = (v * hc) & _M32
                v = v ^ (v >> _U16)
                r = (_MIX_L * pool[i_dst] - _MIX_R * v) & _M32  # `mix`
                pool[i_dst] = r ^ (r >> _U16)
    hb = _INIT_B  # `generate_state(3, uint64)`: six words, paired little-endian
    for i in range(3):
        lo = (pool[(2 * i) % 4] ^ hb) & _M32
        hb = (hb * _MULT_B) & _M32
        lo = (lo * hb) & _M32
        lo = lo ^ (lo >> _U16)
        hi = (pool[(2 * i + 1) % 4] ^ hb) & _M32
        hb = (hb * _MULT_B) & _M32
        hi = (hi * hb) & _M32
        hi = hi ^ (hi >> _U16)
        s[i] = lo | (hi << _U32)
    s[3] = np.uint64(1)
    for _ in range(12):  # `sfc64_set_seed`
        _next(s)


@nb.njit(**JIT, inline="always")
def _next(s):
    """SFC64's next 64 bits; advances the state ``s`` (4,) uint64."""
    tmp = s[0] + s[1] + s[3]
    s[3] += np.uint64(1)
    s[0] = s[1] ^ (s[1] >> np.uint64(11))
    s[1] = s[2] + (s[2] << np.uint64(3))
    s[2] = ((s[2] << np.uint64(24)) | (s[2] >> np.uint64(40))) + tmp
    return tmp


@nb.njit(**JIT, inline="always")
def _next_double(s):
    return np.float64(_next(s) >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@nb.njit(**JIT)
def fill(s, flat):
    """``flat`` (m,) := the SFC64 state ``s``'s next normals (NumPy's ziggurat).

    The state lives in registers through the loop and is written back at
    the end; the rare draws that miss the ziggurat's boxes (about one in a
    hundred) call `_rest`. The same numbers as NumPy's
    ``Generator(SFC64).standard_normal``, in order.
    """
    a = s[0]
    b = s[1]
    c = s[2]
    w = s[3]
    for k in range(flat.shape[0]):
        while True:
            r = a + b + w  # `_next`
            w += np.uint64(1)
            a = b ^ (b >> np.uint64(11))
            b = c + (c << np.uint64(3))
            c = ((c << np.uint64(24)) | (c >> np.uint64(40))) + r
            idx = r & np.uint64(0xFF)
            r = r >> np.uint64(8)
            sign = r & np.uint64(1)
            rabs = (r >> np.uint64(1)) & np.uint64(0x000FFFFFFFFFFFFF)
            x = np.float64(rabs) * _WI[idx]
            if sign & np.uint64(1):
                x = -x
            if rabs < _KI[idx]:
                break
            s[0] = a
            s[1] = b
            s[2] = c
            s[3] = w
            x, done = _rest(s, idx, rabs, x)
            a = s[0]
            b = s[1]
            c = s[2]
            w = s[3]
            if done:
                break
        flat[k] = x
    s[0] = a
    s[1] = b
    s[2] = c
    s[3] = w


@nb.njit(**JIT)
def _rest(s, idx, rabs, x):
    """Finish a draw past the ziggurat's box ``idx``: ``(x, done)`` (else draw again).

    A call, not inlined into `fill`: it is rare, and a second copy of the
    tail in a threaded kernel costs compile time.
    """
    if idx == np.uint64(0):
        while True:
            xx = -_INV_R * np.log1p(-_next_double(s))
            yy = -np.log1p(-_next_double(s))
            if yy + yy > xx * xx:
                if (rabs >> np.uint64(8)) & np.uint64(1):
                    return -(_R + xx), True
                return _R + xx, True
    done = (_FI[idx - np.uint64(1)] - _FI[idx]) * _next_double(s) + _FI[idx] < np.exp(
        -0.5 * x * x
    )
    return x, done


@nb.njit(**JIT)
def fill_chunk(key, chunk, out):
    """``out`` (m, 3) := chunk ``chunk`` of the step keyed ``key``'s normals."""
    s = np.empty(4, dtype=np.uint64)
    sfc64_state(key, chunk, s)
    fill(s, out.reshape(out.size))


@nb.njit(**JIT)
def fill_chunks(key, rows, out):
    """``out`` (n, 3) := every chunk of ``rows`` rows of the step keyed ``key``."""
    n = out.shape[0]
    for c in range((n + rows - 1) // rows):
        fill_chunk(key, c, out[c * rows : min(c * rows + rows, n)])
