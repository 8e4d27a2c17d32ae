"""sorting.py: the compiled stable argsort gives numpy's stable order (ties by index, NaN last)."""

from __future__ import annotations

import numpy as np

from polyfold.sorting import stable_argsort


def test_stable_argsort_is_numpys_stable_argsort():
    rng = np.random.default_rng(11)
    for trial in range(500):
        n = int(rng.integers(0, 90))
        ints = rng.integers(-3, 4, n)  # many ties
        assert np.array_equal(stable_argsort(ints), np.argsort(ints, kind="stable"))
        floats = rng.integers(0, 5, n) * 0.25
        if n and trial % 2:
            floats[rng.integers(0, n, 3)] = np.nan
        assert np.array_equal(stable_argsort(floats), np.argsort(floats, kind="stable"))
        column = np.stack([floats, -floats], axis=1)[:, 0]  # a strided view, as the sweep passes
        assert np.array_equal(stable_argsort(column), np.argsort(column, kind="stable"))
