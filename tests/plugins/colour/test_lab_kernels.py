"""The sRGB linearisation of L*a*b* equals the formula with the C library's ``pow`` to the
bit: for every float32 value where the fast power is used (exhaustively), every 8-bit level,
float64 values and values outside [0, 1]."""

from __future__ import annotations

import importlib
import math

import numpy as np
import pytest
from numba import njit
from numba.core.caching import FunctionCache
from numba.core.registry import CPUDispatcher

from graphvision_plugins.colour import _lab_kernels
from graphvision_plugins.colour._lab_kernels import GAMMA_MARGIN, srgb_levels, srgb_linear


@njit
def _before(
    values: np.ndarray, levels: np.ndarray, levels_linear: np.ndarray, out: np.ndarray
) -> None:  # pragma: no cover
    """The linearisation as the L*a*b* kernels computed it before: an 8-bit level from the
    table (:func:`srgb_levels`), any other
    value by the formula with ``pow``."""
    for t in range(values.size):
        value = values[t]
        k = int(value * 255 + 0.5) if 0 <= value <= 1 else 0
        wide = np.float64(value)
        if levels[k] == value:
            out[t] = levels_linear[k]
        elif wide > 0.04045:
            out[t] = ((wide + 0.055) / 1.055) ** 2.4
        else:
            out[t] = wide / 12.92


def _formula(values: np.ndarray, out: np.ndarray) -> None:
    _before(values, *srgb_levels(values.dtype), out)


def _differences(values: np.ndarray) -> tuple[int, int]:
    """(values whose linearisation differs from the formula's, values left to ``pow``)."""
    found, expected = np.empty(values.size), np.empty(values.size)
    pending = np.empty(values.size, dtype=np.bool_)
    srgb_linear(values, found, pending)
    _formula(values, expected)
    return int(np.count_nonzero(found.view(np.int64) != expected.view(np.int64))), int(
        np.count_nonzero(pending)
    )


def test_every_float32_above_the_knee_equals_the_formula_with_pow():
    """Every float32 from 0.0404 to 2.06 (48 million, all that reach the fast power:
    u = (c + 0.055) / 1.055 in [2⁻⁴, 2)), in blocks of 2²² bit patterns."""
    first = int(np.float32(0.0404).view(np.uint32))
    last = int(np.float32(2.06).view(np.uint32))
    differ = to_pow = 0
    for start in range(first, last + 1, 1 << 22):
        bits = np.arange(start, min(start + (1 << 22), last + 1), dtype=np.uint32)
        wrong, left = _differences(bits.view(np.float32))
        differ, to_pow = differ + wrong, to_pow + left
    assert differ == 0
    # the fast power leaves to pow about 2 GAMMA_MARGIN of the values (a band of
    # ± GAMMA_MARGIN ulp around each midpoint): 3 %, so it is used for the rest
    assert 0.02 < to_pow / (last - first) < 0.04
    assert GAMMA_MARGIN == 2.0**-6


def test_levels_float64_and_values_outside_the_unit_range_equal_the_formula():
    rng = np.random.default_rng(3)
    levels = np.arange(256) / 255.0
    outside = np.array([-1.0, -0.0, 0.0, 1.0, 1.5, 2.5, 1e30, np.inf, -np.inf, np.nan])
    for values in (levels, rng.random(10_000), outside, 0.999 * levels + 0.0005):
        for dtype in (np.float32, np.float64):
            found, expected = np.empty(values.size), np.empty(values.size)
            srgb_linear(values.astype(dtype), found, np.empty(values.size, dtype=np.bool_))
            _formula(values.astype(dtype), expected)
            np.testing.assert_array_equal(found.view(np.int64), expected.view(np.int64))


def test_the_power_table_is_the_reciprocal_centres_power():
    """C_j = r_j^-2.4 (high + low) for r_j = 1 / centre_j: checked at u = centre, where the
    series is 1 and u^2.4 = centre^2.4 (a value of Python's own pow, within an ulp)."""
    for j in (0, 1, 127, 128, 300, 639):
        exponent, step = divmod(j, 128)
        centre = 2.0 ** (exponent - 4) * (1 + (step + 0.5) / 128)
        high, low = _lab_kernels.POWER_HIGH[j], _lab_kernels.POWER_LOW[j]
        assert abs(low) <= np.spacing(high) / 2
        assert abs(high - (1.0 / centre) ** -2.4) <= 2 * np.spacing(high)


def test_every_kernel_is_cached_on_disk():
    name = "graphvision_plugins.colour._lab_kernels"
    module = importlib.import_module(name)
    dispatchers = [
        value
        for value in vars(module).values()
        if isinstance(value, CPUDispatcher) and value.py_func.__module__ == name
    ]
    assert dispatchers
    assert all(isinstance(d._cache, FunctionCache) for d in dispatchers)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_the_8_bit_levels_are_linearised_by_the_c_library_pow_on_every_cpu(dtype) -> None:
    """The table holds the C library's ``pow``, as the kernels call it off the levels, not
    numpy's power (whose AVX-512 code differs in the last bit for some levels): a level's
    L*a*b* value does not depend on the CPU that computed it."""
    levels, linear = srgb_levels(np.dtype(dtype))
    wide = [float(level) for level in levels]
    expected = [math.pow((c + 0.055) / 1.055, 2.4) if c > 0.04045 else c / 12.92 for c in wide]
    assert linear.tolist() == expected
