"""Shared test fixtures and helpers: where the benchmark meshes live, and what tests in more than
one file use (pytest imports this file as `conftest`; tests/ is on sys.path through it).

Only this one conftest.py: a second one in a subfolder would replace the module `conftest` that
test files import helpers from (pytest loads each conftest.py under that one name)."""

from __future__ import annotations

import json
import math
import os
import re
import struct
import subprocess
import sys
import xml.etree.ElementTree as ET
import zlib
from collections import Counter
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
import shapely
import trimesh
from numba import njit
from scipy.spatial import ConvexHull, QhullError
from shapely.geometry import Polygon

from polyfold.apps.warmup import height_grid as warmup_height_grid
from polyfold.collide.triangles import triangles_collide
from polyfold.fabricate.page import Page, TextItem
from polyfold.fold.plan import plan_fold
from polyfold.formats.fold import dumps, fold_tree, net_to_fold
from polyfold.formats.meshes import load_mesh
from polyfold.mesh.geometry import merged_edges
from polyfold.mesh.mesh import Mesh, face_components
from polyfold.pipeline.make import make
from polyfold.pipeline.options import MakeOptions
from polyfold.unfold.kernels import piece_labels
from polyfold.unfold.net import Net
from polyfold.unfold.search import unfold

REPO_ROOT = Path(__file__).resolve().parents[1]
# a polyfold server the developer left running must not answer the tests' commands (the tests of
# the server itself start their own, in a runtime directory of their own)
os.environ["POLYFOLD_SERVER"] = "off"


def models_path() -> Path | None:
    """The benchmark models: $POLYFOLD_MODELS, else ../shared/models beside the checkout (as in CI)."""
    env = os.environ.get("POLYFOLD_MODELS")
    path = Path(env) if env else REPO_ROOT.parent / "shared" / "models"
    return path if path.is_dir() else None


def closed_meshes() -> list[Path]:
    """All closed meshes: the *.obj files directly in the models directory (for parametrize)."""
    root = models_path()
    return sorted(root.glob("*.obj")) if root else []


@pytest.fixture(scope="session")
def models_dir() -> Path:
    root = models_path()
    if root is None:
        pytest.skip("benchmark models not found (set POLYFOLD_MODELS or put them in ../shared/models)")
    return root


# ----------------------------------------------------------------------------------------------
# The command line


CLI = [sys.executable, "-m", "polyfold"]


def run_cli(*args, timeout: float = 300, env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    """`python -m polyfold ARGS...` (arguments made strings), output captured as text; env: variables
    set for it on top of this process's."""
    return subprocess.run([*CLI, *map(str, args)], capture_output=True, text=True, timeout=timeout,
                          env=None if env is None else {**os.environ, **env})


def one_line(stderr: str) -> str:
    """The one line of an error on stderr (no traceback); fails on anything else."""
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, f"expected one line on stderr, got:\n{stderr}"
    assert "Traceback" not in stderr
    return lines[0]


def bad_cases() -> list[tuple[str, dict]]:
    """(file, expectation) per bad/expected.json; empty when the models are absent."""
    root = models_path()
    if root is None:
        return []
    table = json.loads((root / "bad" / "expected.json").read_text())
    return sorted((name, spec) for name, spec in table.items() if not name.startswith("_"))


def unfold_cli(mesh: Path, out: Path, *extra, seed: int = 1, time_limit: float = 60) -> subprocess.CompletedProcess:
    """`polyfold unfold MESH -o OUT` with a seed and a time limit (and any further options)."""
    return run_cli("unfold", mesh, "-o", out, "--seed", seed, "--time-limit", time_limit, *extra)


# ----------------------------------------------------------------------------------------------
# Meshes


def signed_volume(m: Mesh) -> float:
    """Volume enclosed by the faces (positive when they face outward)."""
    tri = m.vertices[m.faces]
    return float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6)


def assert_valid_component(m: Mesh) -> None:
    """Manifold, consistently oriented, edge-connected; closed => positive volume."""
    f = m.faces
    assert len(f) > 0
    assert (f[:, 0] != f[:, 1]).all() and (f[:, 1] != f[:, 2]).all() and (f[:, 0] != f[:, 2]).all()
    assert set(np.unique(f)) == set(range(m.n_vertices)), "unused or missing vertices"
    directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    # Each directed edge at most once: <= 2 faces per edge, and two faces run it in opposite ways.
    assert len(np.unique(directed, axis=0)) == len(directed), "inconsistent orientation or non-manifold edge"
    # Every vertex's faces form a single fan (joined through edges at the vertex).
    by_edge: dict[tuple[int, int], list[int]] = {}
    for i, (a, b) in enumerate(directed):
        by_edge.setdefault((min(a, b), max(a, b)), []).append(i % len(f))
    parent = {(v, int(fi)): (v, int(fi)) for fi in range(len(f)) for v in f[fi]}

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for (a, b), owners in by_edge.items():
        if len(owners) == 2:
            for v in (a, b):
                parent[find((v, owners[0]))] = find((v, owners[1]))
    fans = {v: set() for v in range(m.n_vertices)}
    for key in parent:
        fans[key[0]].add(find(key))
    assert all(len(s) == 1 for s in fans.values()), "a vertex has more than one fan"
    labels = face_components(m.n_faces, m.topology)
    assert labels.max() == 0, "component is not edge-connected"
    if not m.topology.boundary.any():
        assert signed_volume(m) > 0, "closed component faces inward"


def single_component(models_dir, name):
    """The one component of a model (unpacking fails when there are more)."""
    (mesh,) = load_mesh(models_dir / f"{name}.obj").components
    return mesh


def fitted_parts(models_dir, name: str) -> tuple:
    """(mesh, options, scale, page width, page height, parts): a shared model unfolded as make does
    (fold and guide off) and its parts cut to fit A4 at 150 mm (`sheets.fit_parts`)."""
    from polyfold.deadline import Deadline
    from polyfold.fabricate.fit import model_scale
    from polyfold.pipeline.options import paper_size
    from polyfold.pipeline.parts import make_parts
    from polyfold.pipeline.sheets import fit_parts, pack_box

    mesh = load_mesh(models_dir / f"{name}.obj").mesh
    opts = MakeOptions(fold=False, guide=False)
    parts, _, _ = make_parts(mesh, opts, Deadline.after(60), lambda *a: None)
    scale = model_scale([mesh], opts.size)
    w, h = paper_size(opts.paper)
    fitted, _ = fit_parts(parts, scale, opts, pack_box(w, h, opts), name)
    return mesh, opts, scale, w, h, fitted


def sorted_side_lengths(tri):
    """Side lengths of each triangle (..., 3, d), sorted."""
    return np.sort(np.linalg.norm(tri - np.roll(tri, -1, axis=-2), axis=-1), axis=-1)


# Meshes (names under the models directory) where keeping the flat regions whole leaves no single
# net, so unfold spends its whole time limit in vain:
# star-4split-96 splits each star triangle in 4 nearly coplanar ones (|rho| <= 8e-5); 14 of the 36
# midpoints of the star's edges are hyperbolic (by 1e-6 to 9e-5 rad) with only the two halves of
# their star edge cuttable, so both halves are cut (one cut would overlap), and the 24 whole
# triangles keep only 36 - 14 = 22 edges to be joined by (a tree needs 23).
# torus-12x6-144 (and open/tube-132, the same torus less one ring of faces): the top and bottom rings
# of quads are flat annuli, each one polygon; no single net around them was found (2 seeds x 90 s),
# their holes leave the 24 inner-wall quads little room.
NO_SINGLE_NET = {"star-4split-96", "torus-12x6-144", "open/tube-132"}


def subdivided_box(times: int = 2) -> Mesh:
    """A 1 x 1.3 x 0.8 box, each side 2 * 4**times coplanar triangles around interior vertices (flat
    regions whose dual graph has cycles)."""
    box = trimesh.creation.box((1.0, 1.3, 0.8))
    for _ in range(times):
        box = box.subdivide()
    return Mesh(box.vertices, box.faces)


def height_grid(n: int, height) -> Mesh:
    """An n x n grid of unit squares over z = height(x, y), each split along one diagonal
    (`apps.warmup.height_grid`)."""
    return Mesh(*warmup_height_grid(n, height))


def torus_inside(major: int) -> Mesh:
    """`major` x 4 quads of a 24 x 10 torus's inside, a disk whose interior vertices are all
    hyperbolic (each quad split in two, kept whole as a flat region)."""
    torus = trimesh.creation.torus(1.0, 0.35, major_sections=24, minor_sections=10)
    v = torus.vertices
    radius, angle = np.hypot(v[:, 0], v[:, 1]), np.arctan2(v[:, 1], v[:, 0])
    inside = (radius < 1.0 - 0.35 * np.cos(2 * np.pi / 5) + 1e-9) & (angle > -1e-9) & (angle < major * np.pi / 12 + 1e-9)
    keep = inside[torus.faces].all(axis=1)
    return Mesh(v, torus.faces[keep]).submesh(np.arange(int(keep.sum())))


def assert_flat_regions_whole(net: Net) -> None:
    """Every flat region of the net's mesh (faces joined by `merged_edges`) is one polygon of the
    net: its faces are joined by merged creases, and exactly the cycles of its dual graph are left
    out of the tree (one flat edge per cycle, its two sides coincide in the plane)."""
    mesh = net.mesh
    merged = merged_edges(mesh)
    region = face_components(mesh.n_faces, mesh.topology, merged)
    whole = face_components(mesh.n_faces, mesh.topology, merged & net.crease_mask)
    n_regions = region.max() + 1
    assert len(np.unique(np.stack([region, whole]), axis=1).T) == n_regions, "a flat region is cut through"
    assert (merged & ~net.crease_mask).sum() == merged.sum() - mesh.n_faces + n_regions


# ----------------------------------------------------------------------------------------------
# Collisions: exact oracles and an O(n^2) reference


def _orient(a, b, c, d):
    """Exact sign of det(b - a, c - a, d - a) (Fractions of the float inputs)."""
    a, b, c, d = ([Fraction(float(x)) for x in p] for p in (a, b, c, d))
    u = [b[i] - a[i] for i in range(3)]
    v = [c[i] - a[i] for i in range(3)]
    w = [d[i] - a[i] for i in range(3)]
    det = (u[1] * v[2] - u[2] * v[1]) * w[0] + (u[2] * v[0] - u[0] * v[2]) * w[1] + (u[0] * v[1] - u[1] * v[0]) * w[2]
    return (det > 0) - (det < 0)


def segment_crosses_triangle(p, q, t):
    """Exact: segment pq crosses the interior of triangle t (general position)."""
    if _orient(t[0], t[1], t[2], p) * _orient(t[0], t[1], t[2], q) >= 0:
        return False
    s = [_orient(p, q, t[k], t[(k + 1) % 3]) for k in range(3)]
    return all(x > 0 for x in s) or all(x < 0 for x in s)


def oracle_general_position(a, b):
    """Exact: an edge of one triangle crosses the interior of the other (general position)."""
    return any(segment_crosses_triangle(a[k], a[(k + 1) % 3], b) for k in range(3)) or any(
        segment_crosses_triangle(b[k], b[(k + 1) % 3], a) for k in range(3)
    )


# self-crossing inputs, and closed / open ones that do not cross themselves
MESHES = ["fish-472.obj", "bad/intersecting-cubes.obj", "bad/two-cubes.obj", "bunny-348.obj", "torus-12x6-144.obj",
          "spiky-icosahedron-60.obj", "open/tube-132.obj"]


@njit(cache=True)
def _reference(tris, tol, piece, parent, faces, keys):
    """Every pair i < j the skip rule keeps (empty array: that part off), tested by
    triangles_collide: no broad phase at all. Hits as rows (i, j), in (i, j) order."""
    n = tris.shape[0]
    hits = []
    for i in range(n):
        for j in range(i + 1, n):
            if piece.shape[0] and piece[i] != piece[j]:
                continue
            if parent.shape[0] and (parent[i] == j or parent[j] == i):
                continue
            if faces.shape[0]:
                shared = 0
                for a in range(3):
                    for b in range(3):
                        if faces[i, a] == faces[j, b]:
                            shared += 1
                if shared >= 2:
                    continue
            if keys.shape[0] and (keys == i * n + j).any():
                continue
            if triangles_collide(tris[i], tris[j], tol):
                hits.append((i, j))
    out = np.empty((len(hits), 2), dtype=np.int64)
    for k in range(len(hits)):
        out[k, 0] = hits[k][0]
        out[k, 1] = hits[k][1]
    return out


NONE_I = np.empty(0, dtype=np.int64)
NONE_F = np.empty((0, 3), dtype=np.int64)


def reference(tris, tol, piece=None, parent=None, faces=None, keys=None) -> list[tuple[int, int]]:
    """The pairs `_reference` finds, as tuples (None: that part of the skip rule off)."""
    return [tuple(p) for p in _reference(tris, tol, NONE_I if piece is None else piece,
                                         NONE_I if parent is None else parent, NONE_F if faces is None else faces,
                                         NONE_I if keys is None else keys).tolist()]


@pytest.fixture(scope="module")
def meshes(models_dir: Path) -> dict[str, Mesh]:
    """The MESHES, loaded."""
    return {name: load_mesh(models_dir / name).mesh for name in MESHES}


# ----------------------------------------------------------------------------------------------
# FOLD nets and their trees


# (model, unfolding method): single- and multi-piece nets, closed meshes and an open paper part
NETS = [
    ("bunny-128", "auto"),
    ("bunny-128", "steepest-edge"),  # several pieces
    ("paper-parts/bunny-128/part-0", "auto"),
    ("paper-parts/horse/part-5", "steepest-edge"),
    ("dodecahedron-36", "auto"),
    ("torus-8x4-64", "max-perimeter"),  # several pieces (its steepest-edge net is one piece, quads kept whole)
]


_FOLDS: dict = {}


def get_fold(models_dir, name, method="auto", seed=1):
    """The FOLD net of a model (one net per component), made once per session."""
    key = (name, method, seed)
    if key not in _FOLDS:
        loaded = load_mesh(models_dir / f"{name}.obj")
        nets = [unfold(c, method=method, seed=seed)[0] for c in loaded.components]
        _FOLDS[key] = net_to_fold(nets)
    return _FOLDS[key]


@pytest.fixture(scope="module", params=NETS, ids=["-".join(n).replace("/", ":") for n in NETS])
def net(request, models_dir):
    """(FOLD dict, FoldTree) of each of the NETS."""
    fold = get_fold(models_dir, *request.param)
    return fold, fold_tree(fold)


def kabsch_error(P, Q):
    """Max distance between P and Q (n, 3) after the best rigid motion of P onto Q."""
    pc, qc = P.mean(axis=0), Q.mean(axis=0)
    U, _, Vt = np.linalg.svd((P - pc).T @ (Q - qc))
    d = np.sign(np.linalg.det(Vt.T @ U.T))
    rot = Vt.T @ np.diag([1.0, 1.0, d]) @ U.T
    return float(np.linalg.norm((P - pc) @ rot.T + qc - Q, axis=1).max())


def random_q(tree, rng, kind):
    """Random crease angles of a kind: "uniform", "toward-goal" or discrete (the PRM samples)."""
    q = np.zeros(tree.n_edges)
    c = tree.creases
    if kind == "uniform":
        q[c] = rng.uniform(-np.pi, np.pi, len(c))
    elif kind == "toward-goal":
        q[c] = rng.uniform(0, 1) * tree.goal[c]
    else:  # discrete: each crease at 0 or its goal (the PRM samples), plus a little noise
        q[c] = rng.integers(0, 2, len(c)) * tree.goal[c] + rng.normal(0, 0.02, len(c))
    return q


def strip_fold(n_faces):
    """A zigzag strip of n_faces unit triangles: a chain n_faces deep (tree built by BFS)."""
    xy = [[i / 2, i % 2] for i in range(n_faces + 2)]
    faces = [[i, i + 2, i + 1] if i % 2 == 0 else [i, i + 1, i + 2] for i in range(n_faces)]
    edges = [[i, i + 1] for i in range(n_faces + 1)] + [[i, i + 2] for i in range(n_faces)]
    assign = ["B"] + ["F"] * (n_faces - 1) + ["B"] + ["B"] * n_faces
    return {"vertices_coords": xy, "faces_vertices": faces, "edges_vertices": edges, "edges_assignment": assign}


def small_fold():
    """Two triangles joined by a crease (edge 0-2), a mountain of 90 degrees."""
    return {
        "vertices_coords": [[0, 0], [1, 0], [1, 1], [0, 1]],
        "faces_vertices": [[0, 1, 2], [0, 2, 3]],
        "edges_vertices": [[0, 1], [1, 2], [2, 0], [2, 3], [3, 0]],
        "edges_assignment": ["B", "B", "M", "B", "B"],
        "edges_foldAngle": [0, 0, -90, 0, 0],
        "polyfold:faces_parent": [-1, 0],
    }


# ----------------------------------------------------------------------------------------------
# Folding paths


PARTS = [f"paper-parts/horse/part-{i}" for i in range(7)] + ["periscope-28"]


def straight(fold: dict) -> dict:
    """The FOLD with its path replaced by the straight line flat -> goal."""
    out = dict(fold)
    goal = [float(a) for a in fold["edges_foldAngle"]]
    out["polyfold:path"] = [[0.0] * len(goal), goal]
    return out


def api_net(mesh: Path, method: str = "auto", seed: int = 1) -> dict:
    """The FOLD net of a mesh file made through the API (one net per component)."""
    comps = load_mesh(mesh).components
    return net_to_fold([unfold(c, method=method, seed=seed + i, time_limit=10)[0] for i, c in enumerate(comps)])


@pytest.fixture(scope="session")
def folded_parts(models_dir, tmp_path_factory) -> dict:
    """name -> (mesh, FOLD file written by `polyfold unfold --fold`, completed process)."""
    root = tmp_path_factory.mktemp("parts")
    out = {}
    for name in PARTS:
        mesh = models_dir / f"{name}.obj"
        net = root / f"{name.replace('/', '_')}.fold"
        proc = run_cli("unfold", mesh, "-o", net, "--fold", "--seed", 1, "--time-limit", 30)
        out[name] = (mesh, net, proc)
    return out


L_OUTLINE = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]  # an L, star-shaped from corner 0
L_CAP = [(0, 1, 2), (0, 2, 3), (0, 3, 4), (0, 4, 5)]


def prism_obj(outline, cap, height: float) -> str:
    """Closed prism over a CCW outline (cap: triangles of it), outward faces, as OBJ text."""
    n = len(outline)
    lines = [f"v {x} {y} 0" for x, y in outline] + [f"v {x} {y} {height}" for x, y in outline]
    for i in range(n):
        j = (i + 1) % n
        lines += [f"f {i + 1} {j + 1} {j + n + 1}", f"f {i + 1} {j + n + 1} {i + n + 1}"]
    for a, b, c in cap:
        lines += [f"f {a + 1} {c + 1} {b + 1}", f"f {a + n + 1} {b + n + 1} {c + n + 1}"]
    return "\n".join(lines) + "\n"


SEARCH = [(m, s) for m in ("auto", "random", "unflat-tree", "steepest-edge", "flat-tree") for s in (1, 2, 3)]


@pytest.fixture(scope="session")
def lazy_case(tmp_path_factory):
    """(name, mesh, FOLD dict, net file, FoldPath): the first net, in a fixed search order, that is not
    linearly foldable but for which the planner finds a Lazy PRM path with an intermediate frame.
    First a hand-made L-shaped prism (written here), then benchmark meshes if they are around."""
    root = tmp_path_factory.mktemp("lazy")
    hand = root / "l-prism-hand.obj"
    hand.write_text(prism_obj(L_OUTLINE, L_CAP, 1.5))
    meshes = [hand]
    models = models_path()
    if models is not None:
        meshes += [models / f"{n}.obj" for n in ("l-prism-20", "u-prism-28", "periscope-28")]
    for mesh in meshes:
        for method, seed in SEARCH:
            fold = api_net(mesh, method, seed)
            tree = fold_tree(fold)
            if plan_fold(tree, planner="linear") is not None:
                continue
            path = plan_fold(tree, planner="lazy-prm", time_limit=20, seed=1)
            if path is not None and len(path.frames) > 2:
                net = root / f"{mesh.stem}-{method}-{seed}.fold"
                net.write_text(dumps(fold))
                return f"{mesh.name} --method {method} --seed {seed}", mesh, fold, net, path
    pytest.fail("no net needing the Lazy PRM found")


def whole_net(models_dir: Path, name: str, seed: int, n_faces: int) -> dict:
    """A one-piece net of a whole model as a FOLD dict (of n_faces faces)."""
    fold = api_net(models_dir / f"{name}.obj", "auto", seed)
    assert len(fold["faces_vertices"]) == n_faces
    return fold


@pytest.fixture(scope="session")
def whole_bunny(models_dir, tmp_path_factory) -> tuple[dict, Path]:
    """A one-piece net of the whole bunny (127 DOF) as a FOLD dict and file."""
    fold = whole_net(models_dir, "bunny-128", 1, 128)
    net = tmp_path_factory.mktemp("whole") / "bunny.fold"
    net.write_text(dumps(fold))
    return fold, net


# ----------------------------------------------------------------------------------------------
# Segmentation


def depth_below_hull(points: np.ndarray, hull_points: np.ndarray) -> float:
    """max over points of the distance to the boundary of conv(hull_points) (0 for flat sets)."""
    try:
        eq = ConvexHull(hull_points).equations
    except (QhullError, ValueError):
        return 0.0
    d = -(points @ eq[:, :3].T + eq[:, 3])  # >= 0 inside, distance to each facet plane
    return float(np.clip(d.min(axis=1), 0.0, None).max())


# ----------------------------------------------------------------------------------------------
# Pages, sheets and make folders


PAGE_TOL = 1e-3  # mm: how exactly the page writers keep coordinates


def _square_piece(x0: float, y0: float, s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A square (outline, its diagonal, its two triangles) with top-left corner (x0, y0)."""
    a, b, c, d = (x0, y0), (x0 + s, y0), (x0 + s, y0 + s), (x0, y0 + s)
    return np.array([a, b, c, d], float), np.array([a, c], float), np.array([[a, b, c], [a, c, d]], float)


@pytest.fixture
def page() -> Page:
    """Two 30 mm squares split into triangles (one mountain, one valley diagonal); the first has a
    glue tab on its top edge (in its outline, fold along the edge); edge, piece and title labels."""
    sq1, diag1, tris1 = _square_piece(20.0, 25.0, 30.0)
    sq2, diag2, tris2 = _square_piece(70.5, 40.25, 30.0)
    # Tab on the top edge (20,25)-(50,25) of piece 1: outline goes a -> tab -> b -> c -> d.
    outline1 = np.array([sq1[0], (25.0, 19.0), (45.0, 19.0), sq1[1], sq1[2], sq1[3]])
    return Page(
        width=120.0,
        height=90.0,
        cut=(outline1, sq2),
        mountain=diag1[None],
        valley=diag2[None],
        tab_folds=np.array([[sq1[0], sq1[1]]]),
        texts=(
            TextItem("7", 35.0, 22.0, 0.0, 2.5, "edge-label"),
            TextItem("7", 85.5, 41.5, 90.0, 2.5, "edge-label"),
            TextItem("P1", 38.0, 45.0, 30.0, 4.0, "piece-label"),
            TextItem("test net", 60.0, 5.0, 0.0, 3.0, "title"),
        ),
        faces=(tris1, tris2),
    )


H3 = math.sqrt(3) / 2  # height of the unit equilateral triangle


def make_net(net_xy, faces, mesh_vertex, vertices3, parent) -> Net:
    """A Net from a flat layout: net_xy (k, 2) net vertices; faces (m, 3) net vertex ids, CCW;
    mesh_vertex (k,) the mesh vertex each net vertex is a copy of; vertices3 (n, 3) the mesh's
    vertices (they give the fold signs); parent (m,) parent face of each face, -1 for roots."""
    net_xy, faces = np.asarray(net_xy, dtype=float), np.asarray(faces)
    mesh_faces = np.asarray(mesh_vertex)[faces]
    mesh = Mesh(np.asarray(vertices3, dtype=float), mesh_faces)
    edge_id = {tuple(e): i for i, e in enumerate(mesh.topology.edges.tolist())}
    parent = np.asarray(parent, dtype=np.int64)
    parent_edge = np.full(len(faces), -1, dtype=np.int64)
    for f, p in enumerate(parent):
        if p >= 0:
            (a, b) = sorted(set(mesh_faces[f].tolist()) & set(mesh_faces[p].tolist()))
            parent_edge[f] = edge_id[(a, b)]
    order, todo = [], [int(f) for f in np.flatnonzero(parent < 0)]
    while todo:  # parents first
        f = todo.pop(0)
        order.append(f)
        todo += [int(c) for c in np.flatnonzero(parent == f)]
    order = np.array(order, dtype=np.int64)
    return Net(mesh, parent, parent_edge, order, net_xy[faces], piece_labels(order, parent))


APEX = [1.0, H3 / 3, -math.sqrt(2 / 3)]  # apex of the regular tetrahedron of edge 1 on the base of tetra_net


def tetra_net() -> Net:
    """Regular tetrahedron (edge 1) unfolded into one big triangle: corners A B C (copies of the
    apex), midpoints D E F (the base), face DEF the root. Cut edges: AD|DB, BE|EC, CF|FA."""
    A, D, B, E, F, C = range(6)
    xy = [(0, 0), (1, 0), (2, 0), (1.5, H3), (0.5, H3), (1, 2 * H3)]
    mesh_vertex = [0, 1, 0, 2, 3, 0]
    v3 = [APEX, [1, 0, 0], [1.5, H3, 0], [0.5, H3, 0]]
    return make_net(xy, [[A, D, F], [D, B, E], [F, E, C], [D, E, F]], mesh_vertex, v3, [3, 3, 3, -1])


def square_net(fold_z: float) -> Net:
    """A unit square of two triangles creased along the diagonal 0-2; corners 1 and 3 at height
    fold_z: > 0 a valley seen from the printed side (+z), < 0 a mountain. Open boundary only."""
    xy = [(0, 0), (1, 0), (1, 1), (0, 1)]
    v3 = [(0, 0, 0), (1, 0, fold_z), (1, 1, 0), (0, 1, fold_z)]
    return make_net(xy, [[0, 1, 2], [0, 2, 3]], [0, 1, 2, 3], v3, [-1, 0])


def by_class(root, cls):
    """The elements of an SVG tree that have the class `cls`."""
    return [el for el in root.iter() if cls in (el.get("class") or "").split()]


def read_png(path):
    """An RGB PNG file read back by hand (chunks, CRCs, filter bytes checked): (h, w, 3) uint8."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, chunks = 8, []
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos:pos + 4])
        tag, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + n]
        (crc,) = struct.unpack(">I", data[pos + 8 + n:pos + 12 + n])
        assert crc == zlib.crc32(tag + body) & 0xFFFFFFFF
        chunks.append((tag, body))
        pos += 12 + n
    assert chunks[0][0] == b"IHDR" and chunks[-1][0] == b"IEND"
    w, h, depth, ctype, comp, filt, inter = struct.unpack(">IIBBBBB", chunks[0][1])
    assert (depth, ctype, comp, filt, inter) == (8, 2, 0, 0, 0)
    raw = zlib.decompress(b"".join(body for tag, body in chunks if tag == b"IDAT"))
    assert len(raw) == h * (1 + 3 * w)
    rows = np.frombuffer(raw, dtype=np.uint8).reshape(h, 1 + 3 * w)
    assert (rows[:, 0] == 0).all()
    return rows[:, 1:].reshape(h, w, 3)


SVG_NS = {"svg": "http://www.w3.org/2000/svg"}
ROUNDING_MM = 2e-4  # twice the SVG's coordinate resolution
AREA_EPS = 1e-3  # mm^2; the SVG stores coordinates to 1e-4 mm, so touching shapes may show slivers


def _rings(d: str) -> list[np.ndarray]:
    """Closed subpaths of an SVG path made of M / L / Z commands with absolute coordinates."""
    out = []
    for sub in re.findall(r"M([^MZ]*)Z", d):
        nums = [float(x) for x in re.findall(r"-?\d+(?:\.\d+)?(?:e-?\d+)?", sub)]
        out.append(np.array(nums).reshape(-1, 2))
    return out


def read_sheet(path: Path) -> dict:
    """A make sheet SVG read back with a parser of its own: size, faces, tabs, cut outlines, labels."""
    root = ET.parse(path).getroot()
    w, h = (float(root.get(k).removesuffix("mm")) for k in ("width", "height"))
    layers = {g.get("id"): g for g in root.findall("svg:g", SVG_NS)}
    faces, tabs, cuts, labels = [], [], [], []
    for el in layers["preview"].findall("svg:path", SVG_NS):
        (tabs if el.get("class") == "tab" else faces).extend(_rings(el.get("d")))
    for el in layers["cut"].findall("svg:path", SVG_NS):
        if "slit" not in (el.get("class") or ""):
            cuts.extend(_rings(el.get("d")))
    for el in layers["labels"].findall("svg:text", SVG_NS):
        labels.append((el.get("class"), el.text))
    return {"width": w, "height": h, "faces": faces, "tabs": tabs, "cuts": cuts, "labels": labels,
            "layers": set(layers)}


def check_sheet(sheet: dict, margin: float) -> list[str]:
    """Problems of one sheet (empty = fine), from its SVG content alone."""
    problems = []
    faces = shapely.polygons([f for f in sheet["faces"]])
    tabs = np.array([Polygon(t) for t in sheet["tabs"]], dtype=object)  # trapezoids or clipped tabs
    shapes = np.concatenate([faces, tabs])
    kind = np.array(["face"] * len(faces) + ["tab"] * len(tabs))
    i, j = shapely.STRtree(shapes).query(shapes, predicate="intersects")
    keep = i < j
    i, j = i[keep], j[keep]
    # shrunk by the file's rounding (1e-4 mm): a clipped tab's fold line has corners in the middle
    # of its face's edge, which rounding moves off the line (slivers along the whole edge)
    shrunk = shapely.buffer(shapes, -ROUNDING_MM, join_style="mitre")
    area = shapely.area(shapely.intersection(shrunk[i], shrunk[j]))
    for a, b, ar in zip(i, j, area):
        if ar > AREA_EPS:
            problems.append(f"{kind[a]} {a} overlaps {kind[b]} {b} by {ar:.4f} mm^2")
    # cut outlines: disjoint or nested (holes), inside the margins
    cut_polys = [shapely.make_valid(Polygon(c)) for c in sheet["cuts"]]  # (rounded to 1e-4 mm in the file)
    inner = shapely.box(margin, margin, sheet["width"] - margin, sheet["height"] - margin).buffer(1e-3)
    for k, c in enumerate(cut_polys):
        if not inner.contains(c):
            problems.append(f"cut outline {k} crosses the margin")
        for m in range(k + 1, len(cut_polys)):
            d = cut_polys[m]
            nested = c.buffer(ROUNDING_MM).contains(d) or d.buffer(ROUNDING_MM).contains(c)  # a hole may touch its ring
            if c.intersects(d) and not nested:
                if shapely.area(shapely.intersection(c, d)) > AREA_EPS:
                    problems.append(f"cut outlines {k} and {m} overlap")
    # everything printed is inside some cut outline (nothing floats outside a piece)
    union = shapely.union_all(cut_polys).buffer(1e-3)
    for name, group in (("face", faces), ("tab", tabs)):
        for k, g in enumerate(group):
            if not union.contains(g):
                problems.append(f"{name} {k} lies outside every cut outline")
    return problems


def guide_problems(asm: dict) -> list[str]:
    """What is wrong with the build steps of a make folder's assembly.json (issue 22): every glue
    label in exactly one step, every net piece brought in by exactly one step and every glue strip
    used in exactly one, each step gluing only pieces already in the model, and attaching only
    to pieces placed before it (for a join: of other parts)."""
    problems = []
    steps = asm["steps"]
    if [s["step"] for s in steps] != list(range(1, len(steps) + 1)):
        problems.append("steps not numbered 1..n")
    labels = Counter(label for s in steps for label in s["labels"])
    glue = {g["label"]: g for g in asm["glue"]}
    if set(labels) != set(glue) or any(n != 1 for n in labels.values()):
        problems.append(f"labels not in exactly one step: {sorted(set(glue) ^ set(labels))[:5]} "
                        f"{[k for k, n in labels.items() if n > 1][:5]}")
    new = Counter(s["piece"] for s in steps if s["piece"] is not None)
    if set(new) != {p["piece"] for p in asm["pieces"]} or any(n != 1 for n in new.values()):
        problems.append("net pieces not brought in by exactly one step each")
    strips = Counter(name for s in steps for name in s["strips"])
    nets = {p["piece"] for p in asm["pieces"]}  # (a glue strip is a piece of the sheets, not of the net)
    if set(strips) != {g["tab_on"] for g in asm["glue"] if g["tab_on"] and g["tab_on"] not in nets} \
            or any(n != 1 for n in strips.values()):
        problems.append("glue strips not used in exactly one step each")
    part_of = {p["piece"]: p["part"] for p in asm["pieces"]}
    placed: list[str] = []
    for s in steps:
        before = list(placed)
        if s["piece"] is not None:
            placed.append(s["piece"])
        if not set(s["attach_to"]) <= set(before):
            problems.append(f"step {s['step']} attaches to a piece not placed yet")
        if s["kind"] == "join" and any(part_of[q] == s["part"] for q in s["attach_to"]):
            problems.append(f"step {s['step']} joins part {s['part']} to itself")
        for label in s["labels"]:
            if label in glue and not set(glue[label]["pieces"]) <= set(placed):
                problems.append(f"step {s['step']} glues {label} to a piece not placed yet")
    return problems


@pytest.fixture(scope="module")
def make_dir(models_dir: Path, tmp_path_factory) -> Path:
    """A make folder with several parts (so the part picker and ghosting have work to do)."""
    out = tmp_path_factory.mktemp("view") / "bunny-128"
    make(models_dir / "bunny-128.obj", out, MakeOptions(parts=3, time_limit=30))
    return out
