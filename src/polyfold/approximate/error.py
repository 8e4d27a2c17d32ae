"""How far and how valid a convex approximation is: per-part Hausdorff distances to the part's own
surface, volumes, and two disjointness checks of closed convex meshes that share no code with the
clipping in `hulls.py`: an LP per pair (scipy only, cheap enough for every make) and the
intersection volume of a boolean engine (manifold3d, the `test` extra: tests and benchmarks).

Distances are relative to the bounding-box diagonal of the WHOLE mesh (as the segmenter's tau);
samples are `simplify.surface_points` (area-weighted, plus the vertices) and each distance exact
(`closest.surface_distances`), so a reported distance is never below the true one at those points
and misses the true maximum by at most about the samples' spacing.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ..errors import PolyfoldError
from ..mesh.geometry import face_normals, signed_volume
from ..mesh.mesh import Mesh
from ..mesh.simplify import farthest, surface_points

SAMPLES = 4000  # area-weighted surface samples per part and direction (plus the vertices)
LP_TOL = 1e-9  # x the bounding-box diagonal: an LP depth above this is an overlap


def hausdorff_one_sided(a: Mesh, b: Mesh, samples: int = SAMPLES, seed: int = 0) -> float:
    """max over the surface of a of the distance to the surface of b (model units), at `samples`
    area-weighted points of a and its vertices."""
    return farthest(surface_points(a, samples, seed), b)


def part_errors(parts: Sequence[Mesh], approx: Sequence[Mesh], diag: float, samples: int = SAMPLES,
                seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(out, in, volume), each (P,): out[p] = one-sided Hausdorff distance from approximation p to
    the open surface patch parts[p], in[p] = from the patch to the approximation's surface, both
    over `diag`; volume[p] = the enclosed volume of approx[p] (model units cubed)."""
    pairs = list(enumerate(zip(parts, approx)))
    out = np.array([hausdorff_one_sided(a, s, samples, seed + 2 * p) for p, (s, a) in pairs]) / diag
    inn = np.array([hausdorff_one_sided(s, a, samples, seed + 2 * p + 1) for p, (s, a) in pairs]) / diag
    vol = np.array([signed_volume(a.vertices, a.faces) for a in approx])
    return out, inn, vol


# ----------------------------------------------------------------------------------------------
# Disjointness


def chebyshev_centre(planes: np.ndarray, cap: float = 1.0) -> tuple[np.ndarray, float]:
    """(centre (3,), radius) of the largest ball inside n . x + d <= 0 for all rows (n, d) of
    planes (K, 4), n unit: one LP, max t s.t. n . x + d + t <= 0 (HiGHS). radius <= 0: no
    interior (minus the distance the planes would have to move); radius == cap: unbounded (or at
    least that large). Coordinates should be of order 1 (HiGHS's tolerances are absolute).

    HiGHS at feasibility tolerance 1e-10 now and then ends in an unknown status (a torus's
    planes); then 1e-9, then its interior-point method."""
    from scipy.optimize import linprog

    a = np.concatenate([planes[:, :3], np.ones((len(planes), 1))], axis=1)
    res = None
    for method, tol in (("highs", 1e-10), ("highs", 1e-9), ("highs-ipm", 1e-9)):
        res = linprog(c=[0, 0, 0, -1], A_ub=a, b_ub=-planes[:, 3], bounds=[(None, None)] * 3 + [(None, cap)],
                      method=method, options={"primal_feasibility_tolerance": tol, "dual_feasibility_tolerance": tol})
        if res.status == 0:
            return res.x[:3], float(res.x[3])
    raise PolyfoldError(f"Chebyshev centre LP failed: {res.message}")


def lp_overlap_depth(a: Mesh, b: Mesh) -> float:
    """The radius (model units) of the largest ball inside both closed convex meshes a and b (their
    face planes, CCW outward): > 0 when their interiors overlap, <= 0 when a plane separates them
    (then minus half the gap along the best separating direction, roughly): `chebyshev_centre` of
    the face planes of both, in a frame of their size. The planes come from the meshes' faces, not
    from the halfspaces the clipping kept, so the check does not trust the clipping's bookkeeping."""
    verts = np.concatenate([a.vertices, b.vertices])
    centre = 0.5 * (verts.min(axis=0) + verts.max(axis=0))
    scale = float(np.linalg.norm(np.ptp(verts, axis=0))) or 1.0
    rows = []
    for m in (a, b):
        v = (m.vertices - centre) / scale  # unit scale: HiGHS's tolerances are absolute
        n = face_normals(v, m.faces)
        ok = np.linalg.norm(n, axis=1) > 0.5  # degenerate faces have no plane
        rows.append(np.concatenate([n[ok], -np.einsum("ij,ij->i", n[ok], v[m.faces[ok, 0]])[:, None]], axis=1))
    return chebyshev_centre(np.concatenate(rows))[1] * scale


def lp_overlap_depths(parts: Sequence[Mesh]) -> np.ndarray:
    """(P, P) symmetric `lp_overlap_depth` of every pair of closed convex meshes (model units; the
    diagonal is 0); pairs whose bounding boxes are apart get -inf without an LP."""
    n = len(parts)
    depth = np.zeros((n, n))
    lo = np.array([m.vertices.min(axis=0) for m in parts]).reshape(n, 3)
    hi = np.array([m.vertices.max(axis=0) for m in parts]).reshape(n, 3)
    for i in range(n):
        for j in range(i + 1, n):
            apart = bool((lo[i] > hi[j]).any() or (lo[j] > hi[i]).any())
            depth[i, j] = depth[j, i] = -np.inf if apart else lp_overlap_depth(parts[i], parts[j])
    return depth


def overlap_volumes(parts: Sequence[Mesh]) -> np.ndarray:
    """(P, P) symmetric volume (model units cubed) of the intersection of every pair of closed
    meshes, by manifold3d's booleans in float64 (the diagonal holds each mesh's own volume).

    manifold3d is an optional dependency (the `test` extra); PolyfoldError when it is missing or
    does not accept a mesh as a closed oriented manifold."""
    try:
        import manifold3d
    except ImportError as exc:
        raise PolyfoldError("overlap_volumes needs manifold3d (pip install 'polyfold[test]')") from exc

    solids = []
    for k, m in enumerate(parts):
        s = manifold3d.Manifold(manifold3d.Mesh64(vert_properties=np.ascontiguousarray(m.vertices, dtype=np.float64),
                                                  tri_verts=np.ascontiguousarray(m.faces, dtype=np.uint64)))
        if s.status() != manifold3d.Error.NoError:
            raise PolyfoldError(f"approximation {k} is no closed oriented manifold for manifold3d ({s.status()})")
        solids.append(s)
    n = len(solids)
    vol = np.zeros((n, n))
    for i in range(n):
        vol[i, i] = solids[i].volume()
        for j in range(i + 1, n):
            vol[i, j] = vol[j, i] = (solids[i] ^ solids[j]).volume()
    return vol
