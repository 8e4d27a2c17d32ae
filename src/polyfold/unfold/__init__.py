"""Unfolding: overlap-free nets of a mesh component (ALGORITHMS.md 5).

    net.py        `Net` (a spanning forest of the dual graph laid out in the plane) and operations on it
    problem.py    `UnfoldProblem` (the arrays of one component) and the heuristic edge weights
    search.py     `unfold` (within time_limit or a Deadline): heuristics, the GA and its memetic variant
                  (`tree_local_search`), the multi-piece fallback
    pattern.py    `CreasePattern`: the nets of a mesh in one plane (what a FOLD file holds, what fold/ builds trees from)
    kernels.py, setup_kernels.py   numba: Prim's tree, layout, overlap counts, local search, set-up
    pattern_kernels.py             numba: a net as a crease pattern (net vertices, edges, angles)
"""
