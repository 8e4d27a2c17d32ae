"""sorting.py: the compiled stable argsort gives numpy's stable order (ties by index, NaN last), and
the sort and unique made of it numpy's sort and unique."""

from __future__ import annotations

import numpy as np

from polyfold.sorting import sort_in_place, sorted_unique, stable_argsort


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


def test_sort_in_place_and_sorted_unique_are_numpys():
    rng = np.random.default_rng(12)
    for _ in range(200):
        n = int(rng.integers(0, 60))
        ints = rng.integers(-5, 6, n)
        assert np.array_equal(sorted_unique(ints), np.unique(ints))
        whole = rng.integers(0, 1000, n + 4)
        part, want = whole.copy(), whole.copy()
        sort_in_place(part[2:n + 2])  # a slice, as the kernels pass
        want[2:n + 2].sort()
        assert np.array_equal(part, want)
