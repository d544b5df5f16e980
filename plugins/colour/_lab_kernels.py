r"""numba kernels of RGB → L\*a\*b\* for a float32 output (imported on first use).

In one module, so that numba's cache of the whole conversion, keyed on this file, is
renewed when any part of it changes. ``rgb_to_lab_single`` takes 512 pixels at a time
through two SIMD loops: the sRGB linearisation (:func:`srgb_linear`), then XYZ and the
cube roots (:func:`_linear_to_lab`).

Each channel value :math:`c` becomes :math:`c / 12.92` up to 0.04045 and
:math:`((c + 0.055) / 1.055)^{2.4}` above (IEC 61966-2-1), in float64, with the same bits
as the kernels had before (``pow`` of the C library for every value off the 8-bit levels),
faster:

* a value that is one of the 256 levels of an 8-bit channel takes its linear value from a
  table made with the same ``pow`` (numpy's power, which made it before, has its own
  AVX-512 code that differs from ``pow`` in the last bit for a few levels: the table, and
  every result read from it, would then depend on the CPU that made it);
* off the levels, a float32 value's power is computed in SIMD lanes with an error far
  below 2⁻⁶ ulp: :math:`u^{2.4} = C_j (u r_j)^{2.4}`, :math:`j` the 7 bits of :math:`u`
  below its exponent, :math:`r_j` the reciprocal of that interval's centre,
  :math:`C_j = r_j^{-2.4}` a table in double-double (decimal arithmetic, 40 digits) and
  :math:`(1 + z)^{2.4} = 1 + 2.4 z + \binom{2.4}{2} z^2 + \dots` (degree 7,
  :math:`z = u r_j - 1`, :math:`|z| < 2^{-8}`), by fused multiply-adds: Horner's rule,
  and the first products exact (Dekker's two-product). Rounded, it is the correctly rounded power
  wherever the double-double value lies farther than ``GAMMA_MARGIN`` = 2⁻⁶ ulp from a
  midpoint between two doubles, and there glibc's ``pow`` (documented within 0.52 ulp;
  here it rounds otherwise only within 2⁻⁷ ulp of a midpoint) gives the same double. The
  3 % of values nearer a midpoint, and every float64 value, take ``pow`` itself.
  ``tests/plugins/colour/test_lab_kernels.py`` checks every float32 value from 0.0404
  to 2.06 (48 million, all that reach the fast path) against ``pow``. On a CPU without
  FMA, ``llvm.fma`` is the C library's ``fma``: exact still, slower.

Ziv's strategy (a fast path accurate enough to decide the rounding, the library
otherwise): Muller et al. (2018), *Handbook of Floating-Point Arithmetic*, section 10.5;
Dekker (1971), "A floating-point technique for extending the available precision".
"""

from __future__ import annotations

import math
from collections.abc import Callable
from decimal import Decimal, localcontext
from functools import cache
from typing import cast

import numpy as np
from llvmlite import ir  # type: ignore[import-untyped]  # numba's code generator, no stubs
from numba import types
from numba.extending import intrinsic, overload

from ..shared.jit import njit

__all__ = ["GAMMA_MARGIN", "rgb_to_lab_single", "srgb_levels", "srgb_linear"]

GAMMA_BITS = 7  # bits of u below its exponent that choose the table entry
FIRST_BINADE = -4  # the table covers u in [2⁻⁴, 2), 5 binades (u > 0.0905 past the knee)
GAMMA_MARGIN = 2.0**-6  # a power nearer a midpoint than this (in ulp) is left to pow
EXPONENT = 2.4  # the double nearest 2.4 (below it by 8.9e-17): pow's exponent as written


@cache
def srgb_levels(dtype: np.dtype) -> tuple[np.ndarray, np.ndarray]:
    """The 256 levels of an 8-bit channel in ``dtype`` and their linear sRGB values (float64)."""
    levels: np.ndarray = (np.arange(256) / 255.0).astype(dtype)
    wide = levels.astype(np.float64)
    linear = wide / 12.92
    curved = wide > 0.04045
    linear[curved] = [math.pow(u, 2.4) for u in (wide[curved] + 0.055) / 1.055]  # libm's
    return levels, linear


def _binomial(k: int) -> float:
    """The series coefficient binom(EXPONENT, k) of (1 + z)^EXPONENT."""
    term = Decimal(1)
    for i in range(k):
        term = term * (Decimal(EXPONENT) - i) / (i + 1)
    return float(term)


def _gamma_table() -> tuple[np.ndarray, np.ndarray]:
    """``C_j = r_j^-EXPONENT`` as double-double (high, low), ``r_j = 1 / centre_j`` rounded
    as the kernel rounds it, by decimal arithmetic to 40 digits."""
    size = (1 - FIRST_BINADE) << GAMMA_BITS
    high, low = np.empty(size), np.empty(size)
    with localcontext() as context:
        context.prec = 40
        for j in range(size):
            exponent, step = divmod(j, 1 << GAMMA_BITS)
            centre = 2.0 ** (FIRST_BINADE + exponent) * (1 + (step + 0.5) / (1 << GAMMA_BITS))
            power = (Decimal(1.0 / centre).ln() * -Decimal(EXPONENT)).exp()
            high[j] = float(power)
            low[j] = float(power - Decimal(high[j]))
    return high, low


LINEAR32 = srgb_levels(np.dtype(np.float32))[1]
LINEAR64 = srgb_levels(np.dtype(np.float64))[1]
POWER_HIGH, POWER_LOW = _gamma_table()
C2, C3, C4, C5, C6, C7 = (_binomial(k) for k in range(2, 8))
FIRST_INDEX = int(np.float64(2.0**FIRST_BINADE).view(np.int64)) >> (52 - GAMMA_BITS)
EXPONENT_BITS = 0x7FF0000000000000
# the largest |off| of a sure power, over 2^e for a y in [2^e, 2^(e+1)) (ulp 2^(e-52))
_SURE = (0.5 - GAMMA_MARGIN) * 2.0**-52
FRACTION_BITS = 0x000FFFFFFFFFFFFF


def _fma_codegen(context, builder, signature, args):
    """A call of LLVM's ``llvm.fma.f64``: a b + c rounded once."""
    double = ir.DoubleType()
    fma = builder.module.declare_intrinsic(
        "llvm.fma", [double], ir.FunctionType(double, [double] * 3)
    )
    return builder.call(fma, args)


@intrinsic
def _fma(typingctx, a, b, c):  # pragma: no cover
    return types.float64(types.float64, types.float64, types.float64), _fma_codegen


@intrinsic
def _bits(typingctx, x):  # pragma: no cover
    """The IEEE bits of a float64 as an int64 (no instruction: a register's reading)."""
    return types.int64(types.float64), lambda c, b, s, a: b.bitcast(a[0], ir.IntType(64))


@intrinsic
def _double(typingctx, n):  # pragma: no cover
    """The float64 whose IEEE bits are the int64 ``n``."""
    return types.float64(types.int64), lambda c, b, s, a: b.bitcast(a[0], ir.DoubleType())


# fma(a, b, c) = a b + c rounded once (LLVM's llvm.fma: one instruction where the CPU has it);
# bits_of(x): the IEEE bits of a float64 as an int64; double_of(n): the float64 of bits n
fma = cast("Callable[[float, float, float], float]", _fma)
bits_of = cast("Callable[[float], int]", _bits)
double_of = cast("Callable[[int | np.integer], float]", _double)


def _level_table(values: np.ndarray) -> np.ndarray:
    raise NotImplementedError  # compiled only: the overload below


@overload(_level_table)
def _level_table_compiled(values):  # pragma: no cover
    """The linear values of the levels in ``values``' float: module constants, so the
    compiler knows the loop's stores never write them and gathers the loads in SIMD."""
    if values.dtype == types.float32:
        return lambda values: LINEAR32
    return lambda values: LINEAR64


def _in_float_of(values: np.ndarray, x: float) -> float:
    raise NotImplementedError  # compiled only: the overload below


@overload(_in_float_of)
def _in_float_of_compiled(values, x):  # pragma: no cover
    """``x`` rounded to ``values``' float."""
    if values.dtype == types.float32:
        return lambda values, x: np.float32(x)
    return lambda values, x: x


def _is_single(values: np.ndarray) -> bool:
    raise NotImplementedError  # compiled only: the overload below


@overload(_is_single)
def _is_single_compiled(values):  # pragma: no cover
    """Whether ``values`` are float32 (whose powers the fast path was checked on), a
    constant of the compiled code."""
    single = values.dtype == types.float32
    return lambda values: single


@njit(cache=True, nogil=True, error_model="numpy")
def _off_levels(values: np.ndarray, pending: np.ndarray) -> int:  # pragma: no cover
    """``pending[t]`` set where ``values[t]`` is no 8-bit level; their number. The nearest
    level ``k / 255`` rounded to the values' float, as the table has it, is computed (a
    division in SIMD lanes), not read: an image off the levels reads no table at all."""
    misses = 0
    for t in range(values.size):
        value = values[t]
        k = int(value * 255 + 0.5) if 0 <= value <= 1 else 0
        miss = _in_float_of(values, k / 255.0) != value
        pending[t] = miss
        misses += miss
    return misses


@njit(cache=True, nogil=True, error_model="numpy")
def _from_levels(values: np.ndarray, linear: np.ndarray) -> None:  # pragma: no cover
    """``linear[t]`` from the table at ``values[t]``'s nearest 8-bit level (the value
    kept where ``values[t]`` is that level)."""
    table = _level_table(values)
    for t in range(values.size):
        value = values[t]
        linear[t] = table[int(value * 255 + 0.5) if 0 <= value <= 1 else 0]


@njit(cache=True, nogil=True, error_model="numpy")
def _power(u: float) -> tuple[float, bool]:  # pragma: no cover
    """``u^EXPONENT`` rounded to float64 and whether it is sure to equal ``pow``'s (module
    docstring): ``u`` in the table's range and the double-double sum hi + lo farther than
    ``GAMMA_MARGIN`` ulp from a midpoint (and not at a power of two, where the ulp below
    is half the ulp above)."""
    j = (bits_of(u) >> (52 - GAMMA_BITS)) - FIRST_INDEX
    inside = 0 <= j < POWER_HIGH.size
    j = min(max(j, 0), POWER_HIGH.size - 1)
    centre = double_of(
        (bits_of(u) >> (52 - GAMMA_BITS) << (52 - GAMMA_BITS)) | (1 << (51 - GAMMA_BITS))
    )
    r = 1.0 / centre
    high, low = POWER_HIGH[j], POWER_LOW[j]
    p = u * r
    z_high = p - 1.0  # exact (Sterbenz), p in [0.99, 1.01]
    z_low = fma(u, r, -p)  # exact: u r = p + z_low
    z = z_high + z_low
    series = z * z * fma(z, fma(z, fma(z, fma(z, fma(z, C7, C6), C5), C4), C3), C2)
    s = EXPONENT * z_high
    tail = fma(EXPONENT, z_low, fma(EXPONENT, z_high, -s) + series)  # (1 + z)^2.4 = 1 + s + tail
    p = high * s
    hi = high + p
    lo = (high - hi) + p  # exact (Fast2Sum: |high| > |p|)
    lo += fma(high, tail, fma(high, s, -p) + fma(low, s, low))
    y = hi + lo
    off = (hi - y) + lo  # exact: hi + lo = y + off
    sure = (
        abs(off) < double_of(bits_of(y) & EXPONENT_BITS) * _SURE
        and (bits_of(y) & FRACTION_BITS) != 0
    )
    return y, inside and sure


@njit(cache=True, nogil=True, error_model="numpy")
def _curve(values: np.ndarray, linear: np.ndarray, pending: np.ndarray) -> None:  # pragma: no cover
    """The pending values' linearisation by :func:`_power` in SIMD lanes (every lane, the
    result taken where pending); pending left set where ``pow`` must decide."""
    for t in range(values.size):
        wide = np.float64(values[t])
        power, sure = _power((wide + 0.055) / 1.055)
        curved = wide > 0.04045
        linear[t] = (power if curved else wide / 12.92) if pending[t] else linear[t]
        pending[t] = pending[t] and curved and not sure


@njit(cache=True, nogil=True, inline="always")
def _formula(wide: float) -> float:  # pragma: no cover
    """The linearisation of one value by the formula, with the C library's ``pow``."""
    return ((wide + 0.055) / 1.055) ** 2.4 if wide > 0.04045 else wide / 12.92


@njit(cache=True, nogil=True)
def _by_library(
    values: np.ndarray, linear: np.ndarray, pending: np.ndarray
) -> None:  # pragma: no cover
    """The pending values' linearisation by the formula itself (the C library's ``pow``),
    the flags scanned eight at a time (a 64-bit word of eight bools, 0 for most)."""
    words = pending[: values.size // 8 * 8].view(np.uint64)
    for w in range(words.size):
        if words[w] != 0:
            for t in range(8 * w, 8 * w + 8):
                if pending[t]:
                    linear[t] = _formula(np.float64(values[t]))
    for t in range(8 * words.size, values.size):
        if pending[t]:
            linear[t] = _formula(np.float64(values[t]))


@njit(cache=True, nogil=True)
def srgb_linear(
    values: np.ndarray, linear: np.ndarray, pending: np.ndarray
) -> None:  # pragma: no cover
    """``linear`` = the sRGB linearisation of ``values`` (float32 or float64, 1-D) in
    float64; ``pending`` (bool, as long) is scratch. An 8-bit level by the table; other
    float32 values by :func:`_power` where it is sure; the rest by the formula with
    ``pow``: the same bits as the formula and the table gave before."""
    misses = _off_levels(values, pending)
    if misses < values.size:
        _from_levels(values, linear)
    if misses == 0:
        return
    if _is_single(values):
        _curve(values, linear, pending)
    _by_library(values, linear, pending)


_CHUNK = 512  # pixels per pass: a chunk's buffers stay in the L1 cache


@njit(cache=True, nogil=True, error_model="numpy", inline="always")  # in the caller's loop
def _cube_root(x: float) -> float:  # pragma: no cover
    """``∛x`` for a positive normal ``x``, within an ulp or two of float64: the exponent
    divided by three on the bits (Kahan's seed, ~7 %), then three Halley steps
    ``y ← y (y³ + 2x) / (2y³ + x)`` (error cubed each). Branch-free: SIMD lanes."""
    y = double_of(np.int64(np.uint64(bits_of(x)) // np.uint64(3) + np.uint64(0x2A9F7893782DA1CE)))
    for _ in range(3):
        cube = y * y * y
        y = y * (cube + 2.0 * x) / (2.0 * cube + x)
    return y


@njit(cache=True, nogil=True, error_model="numpy")  # no zero-divisor check: it vectorises
def _linear_to_lab(
    linear: np.ndarray, matrix: np.ndarray, epsilon: float, slope: float, out: np.ndarray
) -> None:  # pragma: no cover
    """L*a*b* of the flat linear RGB triples ``linear`` into the flat ``out``, one SIMD
    loop: XYZ / white summed in column order, f(t) = ∛t by :func:`_cube_root` above
    ``epsilon`` (computed at 1.0 below it, the seed needing a positive normal number, and
    not taken), ``slope t + 16/116`` otherwise."""
    m00, m01, m02 = matrix[0, 0], matrix[0, 1], matrix[0, 2]
    m10, m11, m12 = matrix[1, 0], matrix[1, 1], matrix[1, 2]
    m20, m21, m22 = matrix[2, 0], matrix[2, 1], matrix[2, 2]
    for i in range(linear.size // 3):
        r, g, b = linear[3 * i], linear[3 * i + 1], linear[3 * i + 2]
        x = ((0.0 + m00 * r) + m01 * g) + m02 * b
        y = ((0.0 + m10 * r) + m11 * g) + m12 * b
        z = ((0.0 + m20 * r) + m21 * g) + m22 * b
        fx = _cube_root(x if x > epsilon else 1.0)
        fy = _cube_root(y if y > epsilon else 1.0)
        fz = _cube_root(z if z > epsilon else 1.0)
        fx = fx if x > epsilon else slope * x + 16.0 / 116.0
        fy = fy if y > epsilon else slope * y + 16.0 / 116.0
        fz = fz if z > epsilon else slope * z + 16.0 / 116.0
        out[3 * i] = 116.0 * fy - 16.0
        out[3 * i + 1] = 500.0 * (fx - fy)
        out[3 * i + 2] = 200.0 * (fy - fz)


@njit(cache=True, nogil=True)
def rgb_to_lab_single(
    rgb: np.ndarray, matrix: np.ndarray, epsilon: float, slope: float, out: np.ndarray
) -> None:  # pragma: no cover
    """``_spaces_kernels.rgb_to_lab`` for a float32 ``out``, ``_CHUNK`` pixels at a time,
    each step a loop that vectorises: the sRGB linearisation by :func:`srgb_linear` (the
    same bits as before), then :func:`_linear_to_lab`, whose cube root is not the C
    library's (a call per value, a quarter of a microsecond): it may differ from it in the
    last bit of float64, which rounding to float32 hides but for one value in millions."""
    pixels = rgb.reshape(-1)
    result = out.reshape(-1)
    linear = np.empty(3 * _CHUNK)
    pending = np.empty(3 * _CHUNK, dtype=np.bool_)
    for start in range(0, 3 * rgb.shape[0], 3 * _CHUNK):
        stop = min(start + 3 * _CHUNK, 3 * rgb.shape[0])
        chunk = linear[: stop - start]
        srgb_linear(pixels[start:stop], chunk, pending[: stop - start])
        _linear_to_lab(chunk, matrix, epsilon, slope, result[start:stop])
