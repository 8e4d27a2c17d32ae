"""unfold/setup_kernels.py: the heuristic weight rules (steepest cuts, random incident edges) against
plain numpy / lexsort formulations. (The edge table is tested in mesh/test_mesh.py.)"""

import numpy as np
import pytest

from polyfold.unfold import setup_kernels as S


@pytest.mark.parametrize("seed", range(20))
def test_weight_rules_match_lexsort(seed):
    rng = np.random.default_rng(seed)
    n_v = 12
    edges = rng.integers(0, n_v, size=(30, 2))
    edges = edges[edges[:, 0] != edges[:, 1]]
    slope = np.round(rng.normal(size=len(edges)), 1)  # ties
    slope[rng.random(len(edges)) < 0.1] = np.nan
    for un in (False, True):
        v = np.concatenate([edges[:, 0], edges[:, 1]])
        score = np.concatenate([slope, -slope])
        score = 1.0 - np.abs(score) if un else score
        order = np.lexsort((-score, v))
        first = np.ones(len(order), dtype=bool)
        first[1:] = v[order][1:] != v[order][:-1]
        pick = order[first]
        pick = pick[v[pick] != 3]
        want = np.zeros(len(edges))
        want[np.concatenate([np.arange(len(edges))] * 2)[pick]] = 1.0
        assert np.array_equal(S.steepest_cuts(slope, edges, n_v, 3, un), want)
    inner = np.flatnonzero(rng.random(len(edges)) < 0.8)
    mask = rng.random(n_v) < 0.5
    for count in (1, 2):
        v = np.concatenate([edges[inner, 0], edges[inner, 1]])
        e = np.concatenate([inner, inner])
        keep = mask[v]
        keys = np.round(rng.random(int(keep.sum())), 1)  # ties
        assert S.incident_count(inner, edges, mask) == len(keys)
        hyperbolic = rng.random(n_v) < 0.3
        order = np.lexsort((keys, v[keep]))
        vs, es = v[keep][order], e[keep][order]
        rank = np.arange(len(vs)) - np.searchsorted(vs, vs)
        want = np.zeros(len(edges))
        want[es[rank < count]] = 1.0
        got = np.zeros(len(edges))
        uncut, n_next = S.pick_random_incident(inner, edges, mask, count, keys, got, hyperbolic)
        assert np.array_equal(got, want)
        chosen = np.zeros(n_v, dtype=bool)
        chosen[edges[got >= 1.0].reshape(-1)] = True
        assert np.array_equal(uncut, ~chosen & ~hyperbolic) and n_next == S.incident_count(inner, edges, uncut)
