r"""numba kernels of Malvar-He-Cutler's four 5×5 kernels, written out (imported on first use).

Each is one run of ``_bayer_kernels.demosaic_taps`` over the ring of padded rows, its
taps in the order of ``_bayer._tap_lists`` (row-major), those whose weight is a power of
two in float32 (exact: the rows hold no value below float32's normal range).

The other taps, ``RN32(RN64(t + w·s))`` (``t`` the float32 sum so far), are one float32
FMA, ``RN32(t + w·s)``, where the two roundings are one: where ``t + w·s`` is exact in
float64. Let ``e_min`` and ``e_max`` be the binades of the least nonzero and the largest
magnitude of the five rows read. Every sample is a multiple of
:math:`2^{e_{min} - 23}`, every weight of 1/16, so every product and (by induction:
rounding a multiple of a power of two to float32 keeps it one) every sum ``t`` is a
multiple of :math:`g = 2^{e_{min} - 27}`; and :math:`|t + w s| < 2.5 \cdot 2^{e_{max} + 1}
(1 + 2^{-20}) < 2^{e_{max} + 3}` (2.5 the largest sum of a kernel's weights' magnitudes).
So ``t + w·s`` is an integer multiple of ``g`` below :math:`2^{e_{max} - e_{min} + 30}`,
exact in float64's 53 bits when :math:`e_{max} - e_{min} \le 23`. Rows of at most
``_bayer_kernels.NARROW`` = 22 binades (an 8-bit image's levels span 8) take the FMA,
eight times fewer conversions; the others keep float64 (a partial sum of 2⁻⁷⁰ beside a
product of 0.4 on a float32 midpoint rounds otherwise: the tests hold such a row).
"""

from __future__ import annotations

import numpy as np
from numba import types
from numba.extending import intrinsic

from ..shared.jit import njit

__all__ = ["malvar_run"]


@intrinsic
def _fma(typingctx, a, b, c):  # pragma: no cover
    """``a · b + c`` rounded once, in float32 (the processor's FMA, never two roundings)."""
    if not (a == b == c == types.float32):
        return None

    def codegen(context, builder, signature, args):
        return builder.fma(*args)

    return types.float32(a, b, c), codegen


# Malvar's weights that are powers of two, as float32 (a product by them is exact)
_N8, _S16, _Q, _H = np.float32(-0.125), np.float32(0.0625), np.float32(0.25), np.float32(0.5)
_M316 = np.float32(-0.1875)  # exact in float32


@njit(cache=True, nogil=True, inline="always")
def _wide(
    total: np.float32, weight: float, sample: np.float32, narrow: bool
) -> np.float32:  # pragma: no cover
    """One tap whose weight is not a power of two: the product in float64, as
    ``_bayer_kernels._add_taps``; where ``narrow`` (a constant where inlined: no branch is
    left in the loop) one float32 FMA, the same number where the five rows' magnitudes
    span at most ``_bayer_kernels.NARROW`` binades (module docstring)."""
    if narrow:
        return _fma(np.float32(weight), sample, total)  # type: ignore[call-arg]  # numba's call
    return np.float32(np.float64(total) + weight * np.float64(sample))


@njit(cache=True, nogil=True)
def malvar_run(
    kind: int,
    total: np.ndarray,
    same: np.ndarray,
    other: np.ndarray,
    row: int,
    tx: int,
    narrow: bool,
) -> None:  # pragma: no cover
    """One run of ``_bayer_kernels.demosaic_taps`` by one of Malvar's kernels (1: G at R/B,
    2: R/B at G in their row, 3: in their column, 4: R at B / B at R), its taps written out
    in the order of ``_tap_lists`` (row-major), power-of-two weights in float32 (for rows
    with no value below float32's normal range only). The sum stays in a register across
    the taps instead of being stored and loaded once a tap, with the same bits.
    ``same``/``other``: the ring's columns of the run's parity / of the other parity;
    padded row ``row + dy`` is in slot ``(row + dy) % 5``; ``same[:, 1 + j + dx // 2]`` is
    tap ``dx`` (even) of pixel ``j``, ``other[:, tx + j + (dx + 1) // 2]`` tap ``dx`` (odd)."""
    slots = ((row - 2) % 5, (row - 1) % 5, row % 5, (row + 1) % 5, (row + 2) % 5)
    if kind == 1:
        _green_at_rb(total, same, other, slots, tx)
    elif narrow:  # each kernel inlined once per way of taking the other taps
        _rb_kernel(kind, total, same, other, slots, tx, True)
    else:
        _rb_kernel(kind, total, same, other, slots, tx, False)


@njit(cache=True, nogil=True, inline="always")
def _rb_kernel(
    kind: int,
    total: np.ndarray,
    same: np.ndarray,
    other: np.ndarray,
    slots: tuple[int, ...],
    tx: int,
    narrow: bool,
) -> None:  # pragma: no cover
    """Kernels 2–4 of :func:`malvar_run`, their taps whose weight is not a power of two
    taken by :func:`_wide` with ``narrow``."""
    if kind == 2:
        _rb_in_row(total, same, other, slots, tx, narrow)
    elif kind == 3:
        _rb_in_column(total, same, other, slots, tx, narrow)
    else:
        _rb_at_br(total, same, other, slots, tx, narrow)


@njit(cache=True, nogil=True)
def _green_at_rb(
    total: np.ndarray, a: np.ndarray, b: np.ndarray, slots: tuple[int, ...], tx: int
) -> None:  # pragma: no cover
    """G at R or B (kernel 1; its nine weights are powers of two): see ``malvar_run``."""
    m2, m1, c0, p1, p2 = slots
    am2 = a[m2]
    am1 = a[m1]
    ac0 = a[c0]
    bc0 = b[c0, tx:]
    ap1 = a[p1]
    ap2 = a[p2]
    for j in range(total.size):
        t = _N8 * am2[1 + j]
        t = t + _Q * am1[1 + j]
        t = t + _N8 * ac0[j]
        t = t + _Q * bc0[j]
        t = t + _H * ac0[1 + j]
        t = t + _Q * bc0[1 + j]
        t = t + _N8 * ac0[2 + j]
        t = t + _Q * ap1[1 + j]
        t = t + _N8 * ap2[1 + j]
        total[j] = t


@njit(cache=True, nogil=True, inline="always")
def _rb_in_row(
    total: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    slots: tuple[int, ...],
    tx: int,
    narrow: bool,
) -> None:  # pragma: no cover
    """R (B) at a G whose row holds R (B) samples (kernel 2): see ``malvar_run``."""
    m2, m1, c0, p1, p2 = slots
    am2 = a[m2]
    bm1 = b[m1, tx:]
    ac0 = a[c0]
    bc0 = b[c0, tx:]
    bp1 = b[p1, tx:]
    ap2 = a[p2]
    for j in range(total.size):
        t = _S16 * am2[1 + j]
        t = t + _N8 * bm1[j]
        t = t + _N8 * bm1[1 + j]
        t = t + _N8 * ac0[j]
        t = t + _H * bc0[j]
        t = _wide(t, 0.625, ac0[1 + j], narrow)
        t = t + _H * bc0[1 + j]
        t = t + _N8 * ac0[2 + j]
        t = t + _N8 * bp1[j]
        t = t + _N8 * bp1[1 + j]
        t = t + _S16 * ap2[1 + j]
        total[j] = t


@njit(cache=True, nogil=True, inline="always")
def _rb_in_column(
    total: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    slots: tuple[int, ...],
    tx: int,
    narrow: bool,
) -> None:  # pragma: no cover
    """R (B) at a G whose column holds them (kernel 3): see ``malvar_run``."""
    m2, m1, c0, p1, p2 = slots
    am2 = a[m2]
    am1 = a[m1]
    bm1 = b[m1, tx:]
    ac0 = a[c0]
    ap1 = a[p1]
    bp1 = b[p1, tx:]
    ap2 = a[p2]
    for j in range(total.size):
        t = _N8 * am2[1 + j]
        t = t + _N8 * bm1[j]
        t = t + _H * am1[1 + j]
        t = t + _N8 * bm1[1 + j]
        t = t + _S16 * ac0[j]
        t = _wide(t, 0.625, ac0[1 + j], narrow)
        t = t + _S16 * ac0[2 + j]
        t = t + _N8 * bp1[j]
        t = t + _H * ap1[1 + j]
        t = t + _N8 * bp1[1 + j]
        t = t + _N8 * ap2[1 + j]
        total[j] = t


@njit(cache=True, nogil=True, inline="always")
def _rb_at_br(
    total: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    slots: tuple[int, ...],
    tx: int,
    narrow: bool,
) -> None:  # pragma: no cover
    """R at B or B at R (kernel 4): see ``malvar_run``."""
    m2, m1, c0, p1, p2 = slots
    am2 = a[m2]
    bm1 = b[m1, tx:]
    ac0 = a[c0]
    bp1 = b[p1, tx:]
    ap2 = a[p2]
    for j in range(total.size):
        t = _M316 * am2[1 + j]  # one rounding of the exact product, as in float64
        t = t + _Q * bm1[j]
        t = t + _Q * bm1[1 + j]
        t = _wide(t, -0.1875, ac0[j], narrow)
        t = _wide(t, 0.75, ac0[1 + j], narrow)
        t = _wide(t, -0.1875, ac0[2 + j], narrow)
        t = t + _Q * bp1[j]
        t = t + _Q * bp1[1 + j]
        t = _wide(t, -0.1875, ap2[1 + j], narrow)
        total[j] = t
