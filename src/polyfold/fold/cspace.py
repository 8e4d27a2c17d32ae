"""Valid configuration ratios of a net (ALGORITHMS.md 6.6, the paper's Fig. 5)."""

from __future__ import annotations

import numpy as np

from .checker import ValidityChecker
from .tree import FoldTree


def sample_ratio(tree: FoldTree, samples: int = 1000, strategy: str = "discrete", seed: int = 0) -> tuple[int, int]:
    """Valid configuration ratio of ALGORITHMS.md 6.6: (valid, sampled).

    discrete: each crease flat or at its goal, i.i.d. Bernoulli(1/2); continuous: each crease
    uniform between 0 and its goal angle; continuous-full: each crease uniform in (-pi, pi), the
    whole configuration space (ALGORITHMS.md 6.4 names both continuous variants).
    """
    if strategy not in ("discrete", "continuous", "continuous-full"):
        raise ValueError(f"unknown strategy {strategy!r}")
    rng = np.random.default_rng(seed)
    check = ValidityChecker(tree, 1.0)
    creases = tree.creases
    valid = 0
    q = np.zeros(len(tree.goal))
    for _ in range(samples):
        if strategy == "continuous-full":
            q[creases] = rng.uniform(-np.pi, np.pi, len(creases))
            valid += check.valid(q)
            continue
        u = (rng.random(len(creases)) < 0.5) if strategy == "discrete" else rng.random(len(creases))
        q[creases] = u * tree.goal[creases]
        valid += check.valid(q)
    return valid, samples
