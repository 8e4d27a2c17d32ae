"""Segmentation: split a mesh into a few edge-connected, nearly convex parts (ALGORITHMS.md 4).

    segment.py          `segment` -> `Segmentation`: merging on the dual graph, the parts=K search on
                        tau (within an optional Deadline), concavity, Rand index
    table_kernels.py    numba: the per-mesh arrays (seed groups, face keys, lengths, inner edges,
                        initial clusters, samples) and the parts' tables and concavities
    memo_kernels.py     numba: the memo of union concavities (hash buckets, regrowth, union evaluation)
    merge_kernels.py    numba: one merging run (`merge_run`: merge cost, lazy heap, cluster adjacency)
"""
