"""The 5×5 median's straight-line selection is current with the network it is generated
from, and gives the generic network kernel's values (the old path), to the bit."""

from __future__ import annotations

import numpy as np
import pytest

from graphvision_plugins.filters import _median
from graphvision_plugins.filters._median_generate import TARGET, select_source
from graphvision_plugins.filters._median_kernels import median_by_network
from graphvision_plugins.filters._median_network import median_network, sort_network
from graphvision_plugins.filters._median_select5 import median_5x5


def test_generated_module_is_current():
    assert TARGET.read_text(encoding="utf-8") == select_source()


@pytest.mark.parametrize("boundary", ["mirror", "replicate", "wrap", "zero", "crop"])
@pytest.mark.parametrize("shape", [(40, 53), (5, 7), (9, 600)])
def test_straight_line_selection_equals_the_network_kernel(boundary, shape):
    rng = np.random.default_rng(shape[1])
    image = rng.random(shape).astype(np.float32)
    image[::3, ::2] = 0.5  # ties
    rows = _median._boundary_index(shape[0], 2, boundary)
    columns = _median._boundary_index(shape[1], 2, boundary)
    out_shape = (rows.size - 4, columns.size - 4)
    found, expected = np.empty(out_shape, np.float32), np.empty(out_shape, np.float32)
    median_5x5(image, rows, columns, found, 512)
    selection, wire = median_network(5)
    median_by_network(image, rows, columns, sort_network(5), selection, wire, expected, 512)
    np.testing.assert_array_equal(found, expected)
