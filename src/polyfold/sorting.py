"""Sorting for compiled kernels: numba's own `np.argsort(kind="mergesort")` costs seconds of a
first run's compiling (8 s for float keys, in the fold stage's collision sweep), and its quicksort
(`np.argsort`, `.sort()`, `np.unique`) 0.6 s per key type; `stable_argsort` half a second, and the
others here are made of it. A stable sort has one answer, so this gives numpy's (NaN last)."""

from __future__ import annotations

import numpy as np

from .jit import njit


@njit(cache=True)
def stable_argsort(keys: np.ndarray) -> np.ndarray:
    """(n,) int64: the indices that sort the 1-D `keys` ascending, ties in index order, NaN last
    (`np.argsort(keys, kind="stable")`). Bottom-up merge sort."""
    n = keys.shape[0]
    idx = np.arange(n)
    tmp = np.empty(n, dtype=np.int64)
    width = 1
    while width < n:
        for lo in range(0, n, 2 * width):
            mid, hi = min(lo + width, n), min(lo + 2 * width, n)
            i, j, k = lo, mid, lo
            while i < mid and j < hi:
                a, b = keys[idx[i]], keys[idx[j]]
                if b < a or (b == b and a != a):  # the right one first only when strictly before
                    tmp[k] = idx[j]
                    j += 1
                else:
                    tmp[k] = idx[i]
                    i += 1
                k += 1
            while i < mid:
                tmp[k] = idx[i]
                i += 1
                k += 1
            while j < hi:
                tmp[k] = idx[j]
                j += 1
                k += 1
        idx, tmp = tmp, idx
        width *= 2
    return idx


@njit(cache=True)
def sort_in_place(values: np.ndarray) -> None:
    """Sort the 1-D integer array `values` ascending, in place (`values.sort()`, whose quicksort
    numba compiles for 0.6 s of a first run: equal integers are equal, so any sort gives this)."""
    ranked = values[stable_argsort(values)]
    for i in range(values.shape[0]):
        values[i] = ranked[i]


@njit(cache=True)
def sorted_unique(values: np.ndarray) -> np.ndarray:
    """(k,) the distinct values of the 1-D integer array `values`, ascending (`np.unique(values)`,
    whose numba version compiles a quicksort)."""
    ranked = values[stable_argsort(values)]
    n = 0
    for i in range(ranked.shape[0]):
        if i == 0 or ranked[i] != ranked[n - 1]:
            ranked[n] = ranked[i]
            n += 1
    return ranked[:n].copy()
