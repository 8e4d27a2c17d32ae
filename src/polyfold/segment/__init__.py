"""Segmentation: split a mesh into a few edge-connected, nearly convex parts (ALGORITHMS.md 4).

    segment.py    `segment` -> `Segmentation`: merging on the dual graph, concavity, Rand index
    kernels.py    numba: convex hulls, depth below a hull, the merging runs
"""
