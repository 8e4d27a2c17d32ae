"""Array copies for compiled kernels, without numba's slice assignment.

`dst[:k] = src[:k]` in a kernel makes numba compile, once per process and per pair of ranks, the
message it raises when the shapes differ (string formatting: about 2 s of a first run's
compiling, `numba.np.arrayobj.raise_with_shape_context`). A loop does the same copy and compiles
in milliseconds.
"""

from __future__ import annotations

import numpy as np

from .jit import njit


@njit(cache=True)
def copy_flat(dst: np.ndarray, src: np.ndarray, count: int) -> None:
    """Copy the first `count` elements of `src` into `dst`, both C-contiguous of any shape, in
    C order (for arrays of rows: the first count // row-size rows)."""
    d = dst.reshape(dst.size)
    s = src.reshape(src.size)
    for i in range(count):
        d[i] = s[i]


@njit(cache=True)
def copy_row(dst, i, src, j):
    """dst[i] = src[j] for rows of 3, element by element: a row assignment goes through numpy's
    setitem (a view, a broadcast) and costs ~100 ns, this a few."""
    dst[i, 0], dst[i, 1], dst[i, 2] = src[j, 0], src[j, 1], src[j, 2]
