"""segment/hull_kernels.py: the numba convex hull behind the concavity, against qhull on random,
grid, box and real mesh point sets."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from conftest import depth_below_hull
from polyfold.formats.meshes import load_mesh
from polyfold.segment.hull_kernels import HULL_FLAT_EPS, convex_hull


def _hull_sets(models_dir: Path):
    """Point sets for the hull kernel: random, on a small integer grid (duplicates, many coplanar
    and collinear points), box corners with face centres, and vertex sets of real mesh patches."""
    rng = np.random.default_rng(7)
    for n in (4, 5, 9, 20, 40, 64):
        for _ in range(40):
            yield rng.random((n, 3))
            yield rng.integers(0, 3, (n, 3)).astype(float)
    box = np.array([[x, y, z] for x in (0, 1) for y in (0, 2) for z in (0, 3)], dtype=float)
    yield np.concatenate([box, [[0.5, 1, 0], [0.5, 1, 3], [0, 1, 1.5], [0.5, 1, 1.5]]])
    for name in ("periscope-28", "periscope2-44", "horse-302", "bunny-128"):
        mesh = load_mesh(models_dir / f"{name}.obj").mesh
        for _ in range(30):
            faces = rng.choice(mesh.n_faces, size=min(mesh.n_faces, 12), replace=False)
            yield mesh.vertices[np.unique(mesh.faces[faces])]


def test_hull_kernel_matches_qhull(models_dir):
    """The numba hull behind the concavity: every point inside it, qhull's vertices among its
    vertices, and the same depth below the hull for interior points; flat sets have no hull."""
    checked = 0
    for pts in _hull_sets(models_dir):
        verts, eq = convex_hull(pts, HULL_FLAT_EPS)
        try:
            qh = ConvexHull(pts)
        except QhullError:
            assert len(eq) == 0
            continue
        checked += 1
        assert len(eq) > 0
        assert np.allclose(np.linalg.norm(eq[:, :3], axis=1), 1.0)
        scale = np.ptp(pts, axis=0).max()
        assert (pts @ eq[:, :3].T + eq[:, 3]).max() <= 1e-9 * scale  # outward planes, all inside
        assert set(map(tuple, pts[qh.vertices])) <= set(map(tuple, pts[verts]))
        probe = np.concatenate([pts, pts.mean(axis=0) + 0.3 * (pts - pts.mean(axis=0))])
        assert abs(depth_below_hull(probe, pts) - float(np.clip(-(probe @ eq[:, :3].T + eq[:, 3]), 0, None)
                                                       .min(axis=1).max())) <= 1e-9 * scale
    assert checked > 400
    flat = np.c_[np.random.default_rng(1).random((12, 2)), np.full(12, 2.0)]
    assert len(convex_hull(flat, HULL_FLAT_EPS)[1]) == 0
