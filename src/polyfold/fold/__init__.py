"""Folding: a continuous, collision-free path from the flat net to the folded part (ALGORITHMS.md 6).

    tree.py        `FoldTree`: the crease tree of a net, as the kernels take it
    tree_kernels.py numba: a net's edge table, crease tree and crease axes, with error codes
    kinematics.py  forward kinematics (numba)
    checker.py     the one validity checker (configurations and straight segments) and its kernels
    plan.py        `plan_fold` -> `FoldPath`: the planner registry (linear, sequential, lazy-prm) over one
                   checker and one Deadline; "auto" runs them in turn
    sequential.py  the sequential planner (ours) with RRT-Connect over locked creases
    lazy_prm.py    the paper's Lazy PRM
    cspace.py      valid configuration ratios (the paper's Fig. 5)
"""
