"""mesh/hull_kernels.py: the numba convex hull behind the concavity, against qhull on random,
grid, box and real mesh point sets; `geometry.hull_planes` and `concavity` through the kernels and
through qhull and numpy."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from conftest import depth_below_hull, height_grid
from polyfold.formats.meshes import load_mesh
from polyfold.mesh.geometry import MESH_HULL_COMPILED_POINTS, concavity, hull_planes
from polyfold.mesh.hull_kernels import DENSE_EDGES, HULL_FLAT_EPS, _hull_at, convex_hull
from polyfold.mesh.mesh import Mesh


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
        yield mesh.vertices  # a whole mesh, as `concavity` gives it
    for n in (200, DENSE_EDGES + 1, 600, 3000):  # beyond DENSE_EDGES the edge counts are hashed
        sphere = rng.normal(size=(n, 3))
        yield sphere / np.linalg.norm(sphere, axis=1)[:, None] * (1 + 0.01 * rng.random((n, 1)))
        yield rng.random((n, 3))


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


def test_hashed_edge_counts_make_the_dense_tables_hull(models_dir):
    """Counting the facets on each directed edge in a hash table (beyond DENSE_EDGES points) or in
    the n x n table gives the same hull, facet for facet."""
    for pts in _hull_sets(models_dir):
        for eps in (HULL_FLAT_EPS, 1e-8):
            dense, hashed = _hull_at(pts, eps, True), _hull_at(pts, eps, False)
            assert np.array_equal(dense[0], hashed[0]) and np.array_equal(dense[1], hashed[1]), len(pts)


def test_a_whole_meshs_worth_of_points(models_dir):
    """Up to MESH_HULL_COMPILED_POINTS (a whole mesh's vertices for `polyfold info`): qhull's
    vertices, every point inside, on a sphere (every point on the hull) and in a ball."""
    rng = np.random.default_rng(12)
    n = MESH_HULL_COMPILED_POINTS
    sphere = rng.normal(size=(n, 3))
    sphere /= np.linalg.norm(sphere, axis=1)[:, None]
    for pts in (sphere, sphere * rng.random((n, 1)) ** (1 / 3)):
        verts, eq = convex_hull(pts, HULL_FLAT_EPS)
        qh = ConvexHull(pts)
        assert np.array_equal(np.sort(verts), np.sort(qh.vertices)) and len(eq) == len(qh.equations)
        assert max(float((pts[k:k + 2000] @ eq[:, :3].T + eq[:, 3]).max()) for k in range(0, n, 2000)) <= 1e-9


def test_concavity_through_the_kernels_is_numpys(models_dir, monkeypatch):
    """A whole mesh's concavity (`polyfold info`) is the same with the kernels compiled ahead of
    time (the hull compiled up to MESH_HULL_COMPILED_POINTS points, else qhull's; the depth
    compiled) as without them (qhull and numpy), on shared models and on generated meshes nobody
    tuned for: within 1e-9 of the bounding-box diagonal."""
    import polyfold.jit as jit
    import polyfold.mesh.geometry as geometry
    from polyfold.apps.warmup import bumpy_sphere

    meshes = {name: load_mesh(models_dir / f"{name}.obj").mesh
              for name in ("bunny-128", "horse-302", "fish-472", "periscope-28", "cube-12", "torus-12x6-144")}
    meshes["saddle"] = height_grid(6, lambda x, y: (x * x - y * y) / 6)  # open, flat-ish
    meshes["flat"] = height_grid(4, lambda x, y: 0 * x)  # no volume: concavity 0
    for k, (sub, sigma) in enumerate(((2, 0.1), (3, 0.05), (3, 0.2))):  # 320-1,280 faces, up to 642 vertices
        meshes[f"bumpy{k}"] = Mesh(*bumpy_sphere(sub, sigma, seed=11 + k))
    rng = np.random.default_rng(3)
    for k in range(3):  # the hulls of random point clouds: their faces, all on the hull
        pts = rng.normal(size=(rng.integers(40, 900), 3))
        meshes[f"hull{k}"] = Mesh(pts, ConvexHull(pts).simplices)
    for name, mesh in meshes.items():
        values = []
        for ready, compiled_up_to in ((True, MESH_HULL_COMPILED_POINTS), (True, 0), (False, MESH_HULL_COMPILED_POINTS)):
            monkeypatch.setattr(jit, "ahead_ready", lambda ready=ready: ready)
            monkeypatch.setattr(geometry, "MESH_HULL_COMPILED_POINTS", compiled_up_to)
            values.append(concavity(mesh))
        assert max(values) - min(values) <= 1e-9, (name, values)
        if name.startswith("bumpy") or name in ("bunny-128", "horse-302", "saddle"):
            assert values[0] > 1e-3, (name, values)  # dents are measured, not missed
        if name == "flat" or name.startswith("hull"):
            assert values[0] <= 1e-12, (name, values)
    pts = meshes["bumpy1"].vertices
    assert hull_planes(pts[:3], 10) is None and hull_planes(pts, 0)[1].shape[1] == 4
