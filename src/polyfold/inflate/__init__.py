"""Inflation: pop local dents of a mesh with a mass-spring model (ALGORITHMS.md 3).

    inflate.py    `inflate` -> `InflateResult`: the model (docstring), argument checks, set-up,
                  the step loop, the self-intersection guard (`collide.self_intersect`), stopping rules
    kernels.py    numba kernels: the surface's geometry and HV count, forces, a chunk of steps
                  with the per-step guards (flip, collapse, fold-through)
"""
