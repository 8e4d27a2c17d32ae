"""Inflation: pop local dents of a mesh with a mass-spring model (ALGORITHMS.md 3).

    inflate.py    `inflate` -> `InflateResult`: the driver, guards and stopping rules, numba kernels
"""
