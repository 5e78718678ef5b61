"""socialzoo.core.jit.numpy_sum: a kernel's sum in numpy's order, the same bits as numpy's."""

import numpy as np
import pytest

from socialzoo.core.jit import numpy_sum


@pytest.mark.parametrize("count", [0, 1, 7, 8, 9, 16, 127, 128, 129, 130, 255, 256, 1000, 4099])
def test_numpy_sum_has_numpy_bits(count: int) -> None:
    rng = np.random.default_rng(count)
    for _ in range(20):
        # Magnitudes over six decades and many zeros: a sum in another order would differ in the last bits.
        values = rng.standard_normal(count) * 10.0 ** rng.uniform(-3, 3, count)
        values[rng.random(count) < 0.4] = 0.0
        assert numpy_sum(values, 0, count) == values.sum()
        rows = np.stack((values, values[::-1]))
        assert numpy_sum(rows[1], 0, count) == rows.sum(-1)[1]


def test_numpy_sum_of_a_slice() -> None:
    values = np.random.default_rng(0).standard_normal(300)
    assert numpy_sum(values, 17, 200) == values[17:217].sum()
