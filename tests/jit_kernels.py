"""Kernels for tests/test_jit.py to compile ahead of time in a folder of its own (a module, so a
second process imports the same names)."""

from __future__ import annotations

import numpy as np

from polyfold.jit import njit


@njit(cache=True, inline="always")
def _square(x):
    return x * x


@njit(cache=True)
def row_sums_of_squares(a):
    """(n, m) float64 -> (n,): a kernel calling an inlined kernel."""
    out = np.zeros(a.shape[0])
    for i in range(a.shape[0]):
        for j in range(a.shape[1]):
            out[i] += _square(a[i, j])
    return out


@njit(cache=True, error_model="numpy")
def ratio(x, y):
    """x / y as numpy divides (1 / 0 = inf), not as Python does (ZeroDivisionError)."""
    return x / y


@njit(cache=True)
def shifted(pair, k, flag):
    """A tuple (array, float), an int and a bool in, a tuple out."""
    a, d = pair
    return a + d * k, not flag


@njit(cache=True)
def first_negative(a):
    """Raises inside compiled code."""
    for i in range(a.shape[0]):
        if a[i] < 0:
            return i
    raise ValueError("no negative entry")
