"""Simplification to a buildable face count: a scan or a game asset of 20,000-1,000,000 triangles
in, about N faces out, before anything else.

Flat regions are made whole first (`flat.merge_flat`: exact, as few triangles as their outlines
allow; a subdivided cube is 12 triangles again), since the collapse does badly on them; when that
is not enough, the collapse itself is fast-simplification's (PyPI `fast-simplification`, MIT, numpy only: the
quadric edge collapse of Fast-Quadric-Mesh-Simplification, maintained by the PyVista team).
Compared here on an 89,088-face subdivided bunny and an 81,920-face noisy sphere, to 600 and 2,000
faces: fast-simplification and pyfqmr (the same algorithm) take 0.06-0.09 s and give the same
meshes (within 1-2 % of the bounding box, closed and manifold); pymeshlab's
quadric collapse with its quality threshold makes rounder triangles (smallest angle 9-19 degrees
against 1-9) at the same distance, but takes 1.1 s, installs 280 MB and is GPL-3 (polyfold is
MIT). Its aggressiveness is chosen per mesh for the fewest slivers (AGGRESSIVENESS). The result goes through the loader's own `repair` (welding, orientation, components), so
a simplified mesh is checked exactly like a file; its look (texture, colours) is baked onto the
new faces (`bake`). The report says the smallest angle, since the
collapse may leave slivers (bench/bench_big.py measures them).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np

from ..errors import PolyfoldError
from .geometry import face_areas
from .mesh import Mesh
from .repair import LoadedMesh, RawMesh, repair

AUTO_ABOVE = 3000  # --faces auto simplifies meshes with more faces than this
AUTO_EDGE_MM = 12.0  # --faces auto: the printed edge of an equilateral face of the mean area
MIN_FACES = 20  # fewer than this is no model of anything (and a tetrahedron needs 4)
# fast-simplification's aggressiveness (its default 7): each is tried and the result with the fewest
# faces under SLIVER_DEG kept; lower values leave rounder triangles but may stop short of the count
# (an 89k-face bunny to 762 faces: 5, 13 and 13 slivers at 5, 6, 7; 2,000 faces: 10, 21, 69)
AGGRESSIVENESS = (5, 6, 7)
# and each on the mesh as it is and shaken by this x its bounding-box diagonal (seeded): on flat
# regions every collapse costs nothing, and the collapse then makes needles by the hundred (a
# midpoint-subdivided Spot of 93,696 faces to 600: 164 faces under 5 deg, some of 1e-14 mm; shaken
# 1e-4: 1; the 89k bunny: 3 -> 0); the surface moves 1e-4 of its size, far below the collapse's error
JITTER = (0.0, 1e-4)
SLIVER_DEG = 5.0
SNAP = 1e-7  # x the bounding-box diagonal: vertices of the collapsed mesh this close are one
HAUSDORFF_SAMPLES = 20_000  # surface samples each way (and all vertices) for the distance estimate


@dataclass(frozen=True)
class Simplified:
    """A simplified mesh (`loaded`, repaired like a file: face_source indexes the SIMPLIFIED faces)
    and what it cost: faces before/after, the Hausdorff distance between the two surfaces over the
    input's bounding-box diagonal (`hausdorff`: exact at HAUSDORFF_SAMPLES points each way and
    the vertices), the smallest face angle in degrees, seconds."""

    loaded: LoadedMesh
    faces_before: int
    faces_after: int
    hausdorff: float
    min_angle_deg: float
    seconds: float


def auto_face_count(mesh: Mesh, size_mm: float, edge_mm: float = AUTO_EDGE_MM) -> int:
    """The face count at which the mesh printed at `size_mm` (longest bounding-box side) has faces
    of an equilateral triangle's area with `edge_mm` sides on average (at least MIN_FACES)."""
    extent = float(np.max(np.ptp(mesh.vertices, axis=0)))
    if extent <= 0:
        return MIN_FACES
    area_mm2 = float(face_areas(mesh.vertices, mesh.faces).sum()) * (size_mm / extent) ** 2
    return max(MIN_FACES, int(round(area_mm2 / (math.sqrt(3) / 4 * edge_mm ** 2))))


def min_angles_deg(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(F,) the smallest corner angle of every face, degrees."""
    tri = vertices[faces]
    out = np.full(len(faces), 180.0)
    for k in range(3):
        u, w = tri[:, (k + 1) % 3] - tri[:, k], tri[:, (k + 2) % 3] - tri[:, k]
        den = np.maximum(np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1), 1e-300)
        out = np.minimum(out, np.degrees(np.arccos(np.clip((u * w).sum(axis=1) / den, -1.0, 1.0))))
    return out


def hausdorff(a: Mesh, b: Mesh, samples: int = HAUSDORFF_SAMPLES, seed: int = 0) -> float:
    """Symmetric Hausdorff distance between the surfaces of a and b (model units), over `samples`
    area-weighted points on each and its vertices, each point's distance to the other surface
    exact (`closest.surface_distances`). Never below the distance at those points."""
    return max(farthest(surface_points(a, samples, seed), b), farthest(surface_points(b, samples, seed + 1), a))


def surface_points(m: Mesh, samples: int, seed: int) -> np.ndarray:
    """(samples + used vertices, 3) area-weighted random points on the surface of m (seeded), then
    its vertices (a distance measured at them is never below the one at the corners)."""
    rng = np.random.default_rng(seed)
    area = face_areas(m.vertices, m.faces)
    f = rng.choice(len(m.faces), size=samples, p=area / area.sum())
    r = rng.random((samples, 2))
    flip = r.sum(axis=1) > 1
    r[flip] = 1 - r[flip]
    tri = m.vertices[m.faces[f]]
    on = tri[:, 0] + r[:, :1] * (tri[:, 1] - tri[:, 0]) + r[:, 1:] * (tri[:, 2] - tri[:, 0])
    return np.concatenate([on, m.vertices[np.unique(m.faces)]])


def farthest(points: np.ndarray, m: Mesh) -> float:
    """The largest distance from the points to the surface of m (exact: `closest.surface_distances`)."""
    from .closest import surface_distances

    return float(surface_distances(points, m.vertices, m.faces).max(initial=0.0))


def face_target(spec: str, mesh: Mesh, size_mm: float) -> int | None:
    """The face count `--faces spec` asks for on this mesh, None for none: "none"; "auto": the
    `auto_face_count` at size_mm when the mesh has more than AUTO_ABOVE faces and more than that
    count; a number N >= MIN_FACES: N when the mesh has more. PolyfoldError for anything else."""
    key = spec.strip().lower()
    if key == "none":
        return None
    if key == "auto":
        if mesh.n_faces <= AUTO_ABOVE:
            return None
        n = auto_face_count(mesh, size_mm)
        return n if n < mesh.n_faces else None
    n = check_faces_spec(spec)
    return n if n < mesh.n_faces else None


def check_faces_spec(spec: str) -> int | None:
    """The number of `--faces spec` (None for auto / none); PolyfoldError when it is neither."""
    key = spec.strip().lower()
    if key in ("auto", "none"):
        return None
    try:
        n = int(key)
    except ValueError:
        raise PolyfoldError(f"--faces {spec!r}: use a number of faces, auto or none") from None
    if n < MIN_FACES:
        raise PolyfoldError(f"--faces {n}: too few (at least {MIN_FACES})")
    return n


def summary(spec: str, faces_before: int, faces_after: int, hausdorff_rel: float, min_angle_deg: float) -> str:
    """The line that tells a user what --faces did."""
    why = f": faces about {AUTO_EDGE_MM:g} mm across at the printed size" if spec.strip().lower() == "auto" else ""
    return (f"simplified {faces_before:,} faces to {faces_after:,} (--faces {spec}{why}; surface moved up to "
            f"{hausdorff_rel:.2%} of the model's size, smallest face angle {min_angle_deg:.1f} deg)")


def _snap(points: np.ndarray, tris: np.ndarray, tol: float) -> np.ndarray:
    """tris with vertices closer than `tol` made one (the collapse can leave two vertices a
    rounding error apart, whose faces would be slivers of 1e-14 that split the surface); faces
    that collapse are dropped by `repair` as degenerate."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    pairs = cKDTree(points).query_pairs(tol, output_type="ndarray")
    if not len(pairs):
        return tris
    n = len(points)
    _, label = connected_components(coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n)),
                                    directed=False)
    first = np.full(label.max() + 1, n, dtype=np.int64)
    np.minimum.at(first, label, np.arange(n))
    return first[label][tris]


def simplify(loaded: LoadedMesh, faces: int) -> Simplified:
    """The mesh reduced to about `faces` faces (quadric edge collapse, module docstring), repaired
    like a file. A mesh with no more faces than that comes back as it is. PolyfoldError when
    `faces` < MIN_FACES or what the collapse leaves cannot be used (the loader's message)."""
    import fast_simplification

    check_faces_spec(str(faces))
    t0 = time.perf_counter()
    mesh = loaded.mesh
    before = int(mesh.n_faces)
    if before <= faces:
        return Simplified(loaded, before, before, 0.0, float(min_angles_deg(mesh.vertices, mesh.faces).min()),
                          time.perf_counter() - t0)
    def quality(result) -> tuple:  # meets the count, then fewest slivers, then roundest
        points, tris = result
        angles = min_angles_deg(points, tris)
        return len(tris) > 1.05 * faces, int((angles < SLIVER_DEG).sum()), -float(angles.min(initial=180.0))

    diag = float(np.linalg.norm(np.ptp(mesh.vertices, axis=0)))
    from .flat import merge_flat  # (a compiled kernel: loaded only when a mesh is simplified)

    flat = merge_flat(mesh)  # flat regions whole first: exact, and the collapse does badly on them
    used, tris = np.unique(flat.faces, return_inverse=True)
    points, tris = flat.vertices[used], tris.reshape(-1, 3)
    if len(tris) > faces:
        shake = np.random.default_rng(0).standard_normal(points.shape)
        tries = [fast_simplification.simplify(points + jitter * diag * shake, tris.astype(np.int32),
                                              target_count=int(faces), agg=agg)
                 for jitter in JITTER for agg in AGGRESSIVENESS]
        points, tris = min(((np.asarray(p, dtype=np.float64), np.asarray(t, dtype=np.int64)) for p, t in tries),
                           key=quality)
        tris = _snap(points, tris, SNAP * diag)
    raw = RawMesh(vertices=points, tris=tris, source=np.arange(len(tris)), n_triangulated=0)
    out = repair(raw, loaded.path)
    if loaded.appearance is not None:  # the new faces get the old look (a baked texture, or colours)
        from .bake import bake

        out = replace(out, appearance=bake(mesh, loaded.appearance, out.mesh))
    dist = hausdorff(mesh, out.mesh) / diag if diag > 0 else 0.0
    return Simplified(out, before, int(out.mesh.n_faces), dist,
                      float(min_angles_deg(out.mesh.vertices, out.mesh.faces).min()), time.perf_counter() - t0)
