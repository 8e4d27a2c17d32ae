"""formats/raster.py: the distance transform the guide's label spots use (own kernel, checked
against scipy's exact Euclidean one, which polyfold no longer imports for it)."""

from __future__ import annotations

import numpy as np
from scipy.ndimage import distance_transform_edt

from polyfold.formats.raster import distance_to_background


def test_distance_to_background_is_scipys_exact_transform():
    """Random masks of every density and shape (rows and columns of one pixel too), with and
    without a False border, and a guide-sized picture with a bar across: equal, bit for bit."""
    rng = np.random.default_rng(7)
    masks = []
    for _ in range(300):
        h, w = (int(x) for x in rng.integers(1, 50, 2))
        m = rng.random((h, w)) < rng.random()
        if rng.random() < 0.5:
            m[0, :] = m[-1, :] = m[:, 0] = m[:, -1] = False
        masks.append(m)
    big = np.ones((225, 300), dtype=bool)
    big[0, :] = big[-1, :] = big[:, 0] = big[:, -1] = False
    big[100:120, 50:250] = False
    masks.append(big)
    compared = 0
    for m in masks:
        if m.all():
            continue
        got, want = distance_to_background(m), distance_transform_edt(m)
        assert got.dtype == np.float64 and np.array_equal(got, want), m.shape
        compared += 1
    assert compared > 250


def test_distance_to_background_without_background_is_infinite():
    assert np.isinf(distance_to_background(np.ones((3, 4), dtype=bool))).all()
    assert distance_to_background(np.zeros((0, 5), dtype=bool)).shape == (0, 5)
    assert (distance_to_background(np.zeros((2, 2), dtype=bool)) == 0).all()
