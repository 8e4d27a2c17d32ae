"""A stable argsort for compiled kernels: numba's own `np.argsort(kind="mergesort")` costs seconds
of a first run's compiling (8 s for float keys, in the fold stage's collision sweep), this one
half a second. A stable sort has one answer, so this gives numpy's (NaN last)."""

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
