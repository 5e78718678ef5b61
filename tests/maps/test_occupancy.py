"""Walls from floor-plan images: pixel outlines traced, simplified and scaled."""

import numpy as np
import pytest

from socialzoo.core.walls import WallIndex
from socialzoo.maps.occupancy import wall_pixels, walls_from_occupancy


def plan_image() -> np.ndarray:
    """A 15 x 10 m plan at 5 cm per pixel: outer walls 20 cm thick, a middle wall with a 0.9 m door."""
    img = np.full((200, 300), 255, np.uint8)
    img[:4, :] = img[-4:, :] = 0
    img[:, :4] = img[:, -4:] = 0
    img[:80, 148:152] = 0
    img[98:, 148:152] = 0  # door: rows 80..97 (18 px = 0.9 m), y from 5.1 to 6.0 m
    return img


def test_a_plan_image_becomes_its_wall_outlines():
    walls = walls_from_occupancy(wall_pixels(plan_image()), 0.05)
    index = WallIndex(walls)
    # The door lets a line through at y = 5.5; below it the middle wall blocks.
    assert not index.crosses(np.array([[3.0, 5.5]]), np.array([[12.0, 5.5]]))[0]
    assert index.crosses(np.array([[3.0, 2.0]]), np.array([[12.0, 2.0]]))[0]
    # The outline hugs the pixels: the door's jambs lie at y = 5.1 and 6.0, the middle wall at x 7.4..7.6.
    ys = walls[:, [1, 3]]
    assert np.isclose(ys, 5.1).any() and np.isclose(ys, 6.0).any()
    assert np.isclose(walls[:, [0, 2]], 7.4).any() and np.isclose(walls[:, [0, 2]], 7.6).any()
    # Few segments: straight runs are merged (three rectangles and the outer ring's two loops).
    assert len(walls) <= 20


def test_staircases_are_simplified_and_origin_and_scale_apply():
    img = np.full((60, 60), 255, np.uint8)
    for k in range(50):
        img[5 + k, 5 + k : 9 + k] = 0  # a diagonal wall drawn as a pixel staircase
    walls = walls_from_occupancy(wall_pixels(img), 0.1, origin=(10.0, -2.0))
    assert len(walls) <= 8
    pts = walls.reshape(-1, 2)
    assert pts[:, 0].min() >= 10.0 - 1e-9 and pts[:, 1].min() >= -2.0 - 1e-9
    assert pts[:, 0].max() <= 16.0 + 1e-9 and pts[:, 1].max() <= 4.0 + 1e-9


def test_pixel_classes_and_bad_input():
    rgba = np.zeros((2, 2, 4), np.uint8)
    rgba[..., 3] = 255
    rgba[0, 0] = (255, 255, 255, 255)
    rgba[1, 1, 3] = 0  # transparent: free
    np.testing.assert_array_equal(wall_pixels(rgba), [[False, True], [True, False]])
    assert wall_pixels(np.array([[0.2, 0.8]]), threshold=0.3).tolist() == [[True, False]]
    with pytest.raises(ValueError, match="threshold must be in"):
        wall_pixels(plan_image(), threshold=1.5)
    with pytest.raises(ValueError, match="scale must be a positive number"):
        walls_from_occupancy(np.zeros((3, 3), bool), 0.0)
    assert walls_from_occupancy(np.zeros((3, 3), bool), 0.1).shape == (0, 4)
    speck = np.zeros((20, 20), bool)
    speck[10, 10] = True
    assert walls_from_occupancy(speck, 0.1, min_area=0.05).shape == (0, 4)
    assert len(walls_from_occupancy(speck, 0.1)) == 4
