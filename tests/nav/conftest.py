"""Fixtures shared by the navigation tests."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest


def _random_building(rng: np.random.Generator) -> np.ndarray:
    """A grid of rooms: walls every 4 m with 1 m door gaps, plus a few random segments; (W, 4)."""
    walls = []
    for x in range(0, 21, 4):
        for y0 in range(0, 20, 4):
            walls.append((x, y0, x, y0 + 1.5))
            walls.append((x, y0 + 2.5, x, y0 + 4))
            walls.append((y0, x, y0 + 1.5, x))
            walls.append((y0 + 2.5, x, y0 + 4, x))
    a = rng.uniform(0, 20, (15, 2))
    extra = np.hstack((a, a + rng.uniform(-1.5, 1.5, (15, 2))))
    return np.vstack((np.array(walls, float), extra))


@pytest.fixture
def random_building() -> Callable[[np.random.Generator], np.ndarray]:
    """Walls of a 20 m x 20 m building of 4 m rooms with doors, drawn from a generator."""
    return _random_building
