"""An independent checker of FOLD nets written by polyfold.

Stands alone on purpose (numpy, shapely, json, and trimesh only for non-OBJ meshes): it must not
share code, and so bugs, with the package it checks. Usage:

    python tests/fold_checker.py NET.fold MESH.obj [--orientation source|outward|none]

`check_fold(fold_path, mesh_path)` verifies

a. structure: faces in range, CCW in 2D, every face side listed in edges_vertices, creases (non-B
   edges) bordered by exactly two faces and cut (B) edges by exactly one, assignments agree with
   the sign of the fold angles;
b. congruence with the mesh: every net triangle has the side lengths of its source face, its
   foldedForm corners are that face's vertices (in the face's own cyclic order unless told
   otherwise), and every source face is used as often as it has triangles (degenerate faces and
   duplicates of a used face may be missing: a repair drops them);
c. no two faces overlap in the plane;
d. the number of pieces (faces joined by creases);
e. folding each piece by its edges_foldAngle reproduces the foldedForm, which is the mesh itself.

Units: a net in the mesh's units is compared with the mesh as it is; a net in mm (`frame_unit`
"mm", as `polyfold make` writes its pieces) with the mesh times the file's
`polyfold:mmPerModelUnit`.
"""

from __future__ import annotations

import json
import math
import os
import sys
from collections import defaultdict, deque
from dataclasses import dataclass, field

import numpy as np
import shapely
from shapely.geometry import Polygon
from shapely.strtree import STRtree

# ----------------------------------------------------------------------------------------------
# Mesh reading


def _obj_lines(text: str):
    """Non-empty lines of an OBJ as token lists (comments stripped, '\\' continuations joined)."""
    pending = ""
    for raw in text.splitlines():
        line = raw.split("#", 1)[0].rstrip()
        if line.endswith("\\"):
            pending += line[:-1] + " "
            continue
        tokens = (pending + line).split()
        pending = ""
        if tokens:
            yield tokens
    if pending.split():
        yield pending.split()


def read_obj(path: str) -> tuple[np.ndarray, list[list[int]]]:
    """(vertices (n, 3), polygons as 0-based vertex index lists, in file order)."""
    with open(path, encoding="utf-8", errors="replace") as fh:
        text = fh.read()
    verts: list[list[float]] = []
    polys: list[list[int]] = []
    for tokens in _obj_lines(text):
        if tokens[0] == "v":
            verts.append([float(t) for t in tokens[1:4]])
        elif tokens[0] in ("f", "fo"):
            poly = []
            for tok in tokens[1:]:
                k = int(tok.split("/", 1)[0])
                if k == 0:
                    raise ValueError(f"{path}: OBJ index 0")
                poly.append(k - 1 if k > 0 else len(verts) + k)
            polys.append(poly)
    return np.array(verts, dtype=float).reshape(-1, 3), polys


def read_mesh(path: str) -> tuple[np.ndarray, list[list[int]]]:
    """(vertices, polygons) of a mesh file: OBJ by our own reader, anything else through trimesh."""
    if os.path.splitext(path)[1].lower() == ".obj":
        return read_obj(path)
    import trimesh

    mesh = trimesh.load(path, process=False, force="mesh")
    return np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=int).tolist()


def _fan(poly: list[int]) -> list[tuple[int, int, int]]:
    return [(poly[0], poly[k], poly[k + 1]) for k in range(1, len(poly) - 1)]


def _tri_area(p: np.ndarray) -> float:
    return 0.5 * float(np.linalg.norm(np.cross(p[1] - p[0], p[2] - p[0])))


# ----------------------------------------------------------------------------------------------
# Report


@dataclass
class Report:
    pieces: int = 0
    faces: int = 0
    overlaps: list[tuple[int, int]] = field(default_factory=list)
    congruence_error: float = 0.0  # max side-length / corner-position mismatch, relative to the mesh diagonal
    fold_error: float = 0.0  # max distance folded piece vs foldedForm after alignment, relative
    problems: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.problems and not self.overlaps

    def __str__(self) -> str:
        lines = [
            f"ok: {self.ok}",
            f"faces: {self.faces}",
            f"pieces: {self.pieces}",
            f"overlapping face pairs: {len(self.overlaps)}" + (f" (e.g. {self.overlaps[:5]})" if self.overlaps else ""),
            f"congruence error: {self.congruence_error:.3g}",
            f"fold error: {self.fold_error:.3g}",
        ]
        lines += [f"problem: {p}" for p in self.problems[:50]]
        if len(self.problems) > 50:
            lines.append(f"... and {len(self.problems) - 50} more problems")
        return "\n".join(lines)


def _problem(report: Report, message: str) -> None:
    report.problems.append(message)


# ----------------------------------------------------------------------------------------------
# Geometry helpers


def _rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Right-hand rotation matrix about the unit vector `axis` by `angle` radians (Rodrigues)."""
    x, y, z = axis
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k)


def _kabsch(src: np.ndarray, dst: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Proper rotation R and translation t minimizing |R src + t - dst| (no reflection)."""
    cs, cd = src.mean(axis=0), dst.mean(axis=0)
    h = (src - cs).T @ (dst - cd)
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(vt.T @ u.T)) or 1.0
    r = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return r, cd - r @ cs


# ----------------------------------------------------------------------------------------------
# The checks


def _load_fold(fold_path: str, report: Report):
    with open(fold_path, encoding="utf-8") as fh:
        fold = json.load(fh)
    for key in ("vertices_coords", "faces_vertices", "edges_vertices", "edges_assignment",
                "edges_foldAngle", "file_frames", "polyfold:faces_meshFace"):
        if key not in fold:
            _problem(report, f"FOLD file has no {key!r}")
    return fold


def _check_structure(report, xy, faces, edges, assign, angles):
    """(a) Returns {undirected edge: edge index} and {edge index: [(face, directed side)]}."""
    n_v = len(xy)
    ok_faces = np.ones(len(faces), dtype=bool)
    if faces.ndim != 2 or faces.shape[1] != 3:
        _problem(report, f"faces_vertices must be triangles, shape is {faces.shape}")
        return {}, {}, ok_faces
    bad = np.flatnonzero(((faces < 0) | (faces >= n_v)).any(axis=1))
    for f in bad[:10]:
        _problem(report, f"face {f} has a vertex index out of range: {faces[f].tolist()}")
    ok_faces[bad] = False
    rep = np.flatnonzero((faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 0] == faces[:, 2]))
    for f in rep[:10]:
        _problem(report, f"face {f} repeats a vertex: {faces[f].tolist()}")
    ok_faces[rep] = False
    safe = np.where(ok_faces[:, None], faces, 0)
    p = xy[safe]
    signed = 0.5 * ((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
                    - (p[:, 2, 0] - p[:, 0, 0]) * (p[:, 1, 1] - p[:, 0, 1]))
    cw = np.flatnonzero(ok_faces & ~(signed > 0))
    for f in cw[:10]:
        _problem(report, f"face {f} is not counter-clockwise in 2D (signed area {signed[f]:.3g})")
    if len(cw) > 10:
        _problem(report, f"{len(cw)} faces are not counter-clockwise in total")

    if edges.ndim != 2 or (len(edges) and edges.shape[1] != 2):
        _problem(report, f"edges_vertices must be pairs, shape is {edges.shape}")
        return {}, {}, ok_faces
    if len(assign) != len(edges) or len(angles) != len(edges):
        _problem(report, f"{len(edges)} edges but {len(assign)} assignments and {len(angles)} fold angles")
        return {}, {}, ok_faces
    edge_id: dict[tuple[int, int], int] = {}
    for e, (a, b) in enumerate(edges.tolist()):
        if not (0 <= a < n_v and 0 <= b < n_v) or a == b:
            _problem(report, f"edge {e} has bad vertices {a, b}")
            continue
        key = (min(a, b), max(a, b))
        if key in edge_id:
            _problem(report, f"edges {edge_id[key]} and {e} join the same vertices {key}")
        edge_id[key] = e
    for e, (asg, ang) in enumerate(zip(assign, angles)):
        if asg not in ("B", "M", "V", "F", "U", "C", "J"):
            _problem(report, f"edge {e} has an unknown assignment {asg!r}")
        elif asg == "M" and not ang < 0:
            _problem(report, f"mountain edge {e} has fold angle {ang} (must be negative)")
        elif asg == "V" and not ang > 0:
            _problem(report, f"valley edge {e} has fold angle {ang} (must be positive)")
        elif asg == "F" and ang != 0:
            _problem(report, f"flat edge {e} has fold angle {ang} (must be 0)")
        elif asg in ("U", "C", "J"):
            _problem(report, f"edge {e} has assignment {asg!r}: a net has only B/M/V/F")
    sides: dict[int, list[tuple[int, int, int]]] = defaultdict(list)  # edge -> [(face, from, to)]
    for f in np.flatnonzero(ok_faces):
        for k in range(3):
            a, b = int(faces[f, k]), int(faces[f, (k + 1) % 3])
            e = edge_id.get((min(a, b), max(a, b)))
            if e is None:
                _problem(report, f"side {a}-{b} of face {f} is not in edges_vertices")
                continue
            sides[e].append((int(f), a, b))
    for e in range(len(edges)):
        n = len(sides.get(e, []))
        want = 1 if assign[e] == "B" else 2
        if n != want:
            _problem(report, f"edge {e} ({assign[e]}) borders {n} faces, should border {want}")
        elif want == 2:
            (_, a1, b1), (_, a2, b2) = sides[e]
            if (a1, b1) != (b2, a2):
                _problem(report, f"crease {e}: its two faces run along it in the same direction")
    return edge_id, sides, ok_faces


def _check_congruence(report, xy, xyz, faces, ok_faces, src, verts, polys, diag, tol, orientation):
    """(b) Side lengths, corner positions and orientation against the source faces; coverage."""
    n_src = len(polys)
    atol = tol * diag
    err = 0.0
    used = np.zeros(n_src, dtype=int)
    used_tris: dict[int, set] = defaultdict(set)
    n_bad = 0

    def bad(msg):
        nonlocal n_bad
        n_bad += 1
        if n_bad <= 20:
            _problem(report, msg)

    for f in np.flatnonzero(ok_faces):
        s = int(src[f])
        if not 0 <= s < n_src:
            bad(f"face {f}: faces_meshFace {s} is not a face of the mesh (it has {n_src})")
            continue
        used[s] += 1
        poly = polys[s]
        if any(not 0 <= v < len(verts) for v in poly):
            bad(f"face {f}: source face {s} has a vertex index out of range")
            continue
        u = faces[f]
        p2 = xy[u]
        len2 = np.array([np.linalg.norm(p2[(k + 1) % 3] - p2[k]) for k in range(3)])
        if len(poly) == 3:
            q = verts[poly]
            len3 = np.array([np.linalg.norm(q[(k + 1) % 3] - q[k]) for k in range(3)])
            e = float(np.abs(np.sort(len2) - np.sort(len3)).max())
            err = max(err, e)
            if e > atol:
                bad(f"face {f}: side lengths {np.sort(len2)} differ from source face {s}'s {np.sort(len3)}")
        # Which corner of the source polygon is each net corner (by the foldedForm position)?
        pv = verts[poly]
        corner = []
        for k in range(3):
            d = np.linalg.norm(pv - xyz[u[k]], axis=1)
            j = int(np.argmin(d))
            err = max(err, float(d[j]))
            if d[j] > atol:
                bad(f"face {f}: foldedForm corner {k} at {xyz[u[k]].tolist()} is not a vertex of source face {s}")
                break
            corner.append(j)
        else:
            if len(set(corner)) < 3:
                bad(f"face {f}: its corners are not three different vertices of source face {s}")
                continue
            # 2D sides against the 3D sides they stand for (corner correspondence, not just multiset).
            for k in range(3):
                l3 = float(np.linalg.norm(pv[corner[(k + 1) % 3]] - pv[corner[k]]))
                e = abs(len2[k] - l3)
                err = max(err, e)
                if e > atol:
                    bad(f"face {f}: side {k} is {len2[k]:.9g} long in 2D, {l3:.9g} on the mesh")
                    break
            key = frozenset(corner)
            if key in used_tris[s]:
                bad(f"face {f}: source face {s}'s triangle {sorted(corner)} appears twice")
            used_tris[s].add(key)
            if orientation == "source":
                # CCW in 2D = outside up; must follow the source face's own cyclic order.
                m = len(poly)
                c = corner
                steps = [(c[(k + 1) % 3] - c[k]) % m for k in range(3)]
                if sum(steps) != m:
                    bad(f"face {f}: corner order {c} runs against source face {s}'s vertex order "
                        "(the outside does not face +z)")
    if n_bad > 20:
        _problem(report, f"{n_bad} congruence problems in total")
    report.congruence_error = max(report.congruence_error, err / diag)

    # Coverage: every source face used as often as it has (non-degenerate) triangles.
    pos_key = lambda v: tuple(np.round(verts[v] / atol).astype(np.int64).tolist()) if atol > 0 else tuple(verts[v])
    used_keys = set()
    for s in np.flatnonzero(used):
        used_keys.add(frozenset(pos_key(v) for v in polys[s]))
    missing = 0
    for s, poly in enumerate(polys):
        if any(not 0 <= v < len(verts) for v in poly):
            continue
        tris = _fan(poly)
        want = sum(1 for t in tris if _tri_area(verts[list(t)]) > 1e-12 * diag * diag)
        if used[s] > max(want, len(tris)):
            _problem(report, f"source face {s} is used by {used[s]} net faces, it has {want} triangles")
        elif used[s] == 0:
            if want == 0 or frozenset(pos_key(v) for v in poly) in used_keys:
                continue  # a degenerate face or a duplicate of a used face: dropped by a repair
            missing += 1
            if missing <= 10:
                _problem(report, f"source face {s} is missing from the net")
        elif used[s] != want:
            _problem(report, f"source face {s} is used by {used[s]} net faces, it has {want} triangles")
    if missing > 10:
        _problem(report, f"{missing} source faces missing in total")


def _check_outward(report, xyz, faces, ok_faces, diag, tol):
    """Orientation without the source order: consistent across the folded surface, and every
    closed component of it encloses positive volume (the outside faces out)."""
    atol = tol * diag
    keys = {}
    vid = np.empty(len(xyz), dtype=np.int64)
    for i, p in enumerate(np.round(xyz / atol).astype(np.int64).tolist()):
        vid[i] = keys.setdefault(tuple(p), len(keys))
    directed: dict[tuple[int, int], list[int]] = defaultdict(list)
    ids = np.flatnonzero(ok_faces)
    for f in ids:
        t = vid[faces[f]]
        for k in range(3):
            directed[(int(t[k]), int(t[(k + 1) % 3]))].append(int(f))
    parent = {int(f): int(f) for f in ids}

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    open_roots = set()
    for (a, b), fs in directed.items():
        if len(fs) > 1:
            _problem(report, f"faces {fs} run along edge {a}-{b} of the folded surface in the same direction")
        back = directed.get((b, a), [])
        for f in fs:
            for g in back:
                parent[find(f)] = find(g)
        if not back:
            open_roots.add(fs[0])
    open_comps = {find(f) for f in open_roots}
    vol: dict[int, float] = defaultdict(float)
    for f in ids:
        p = xyz[faces[f]]
        vol[find(int(f))] += float(np.dot(p[0], np.cross(p[1], p[2]))) / 6.0
    for root, v in vol.items():
        if root not in open_comps and not v > 0:
            _problem(report, f"closed surface containing face {root} is inside out (signed volume {v:.3g})")


def _pieces(n_faces, sides, assign):
    """(d) Piece label per face: components of faces joined by creases."""
    parent = list(range(n_faces))

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    adj: dict[int, list[tuple[int, int, int, int]]] = defaultdict(list)  # face -> (nbr, edge, a, b)
    for e, lst in sides.items():
        if assign[e] != "B" and len(lst) == 2:
            (f, a, b), (g, c, d) = lst
            parent[find(f)] = find(g)
            adj[f].append((g, e, a, b))  # (a, b): the edge as it runs in f's CCW order
            adj[g].append((f, e, c, d))
    roots = {}
    label = np.array([roots.setdefault(find(f), len(roots)) for f in range(n_faces)], dtype=int)
    return label, adj


def _check_folding(report, xy, xyz, faces, ok_faces, label, adj, angles, diag):
    """(e) Fold each piece by its angles and compare with the foldedForm."""
    worst = 0.0
    for piece in range(int(label.max()) + 1 if len(label) else 0):
        members = np.flatnonzero((label == piece) & ok_faces)
        if len(members) == 0:
            continue
        root = int(members[0])
        transform = {root: (np.eye(3), np.zeros(3))}  # 3D point = R @ (x, y, 0) + t
        queue = deque([root])
        while queue:
            f = queue.popleft()
            r, t = transform[f]
            for g, e, a, b in adj[f]:
                if g in transform or not ok_faces[g]:
                    continue
                pa = np.array([*xy[a], 0.0])
                pb = np.array([*xy[b], 0.0])
                axis = pb - pa
                axis /= np.linalg.norm(axis)
                rot = _rotation(axis, -math.radians(float(angles[e])))
                # child = T_f o (rotation about the line a-b, in the flat sheet's coordinates)
                transform[g] = (r @ rot, r @ (pa - rot @ pa) + t)
                queue.append(g)
        src, dst = [], []
        for f in members:
            r, t = transform[int(f)]
            for v in faces[f]:
                src.append(r @ np.array([*xy[v], 0.0]) + t)
                dst.append(xyz[v])
        src, dst = np.array(src), np.array(dst)
        rr, tt = _kabsch(src, dst)
        dist = float(np.linalg.norm(src @ rr.T + tt - dst, axis=1).max())
        worst = max(worst, dist / diag)
    report.fold_error = worst


def check_fold(fold_path, mesh_path, tol: float = 1e-6, orientation: str = "source") -> Report:
    """Check the FOLD net `fold_path` against the mesh file it was made from.

    orientation: "source" (each net face, outside up, follows its source face's vertex order),
    "outward" (for repaired meshes whose faces were flipped: the folded surface is consistently
    oriented and every closed part of it has positive volume) or "none".
    """
    if orientation not in ("source", "outward", "none"):
        raise ValueError(f"orientation must be 'source', 'outward' or 'none', not {orientation!r}")
    report = Report()
    fold = _load_fold(os.fspath(fold_path), report)
    if report.problems:
        return report
    verts, polys = read_mesh(os.fspath(mesh_path))
    if fold.get("frame_unit") == "mm" and "polyfold:mmPerModelUnit" in fold:
        verts = verts * float(fold["polyfold:mmPerModelUnit"])  # the mesh at the net's scale
    used_v = sorted({v for p in polys for v in p if 0 <= v < len(verts)})
    diag = float(np.linalg.norm(np.ptp(verts[used_v], axis=0))) if used_v else 0.0
    if not diag > 0:
        _problem(report, "the mesh has no extent")
        return report

    xy = np.asarray(fold["vertices_coords"], dtype=float)
    faces = np.asarray(fold["faces_vertices"], dtype=np.int64)
    edges = np.asarray(fold["edges_vertices"], dtype=np.int64).reshape(-1, 2)
    assign = list(fold["edges_assignment"])
    angles = np.asarray(fold["edges_foldAngle"], dtype=float)
    src = np.asarray(fold["polyfold:faces_meshFace"], dtype=np.int64)
    report.faces = len(faces)
    if xy.ndim != 2 or xy.shape[1] != 2:
        _problem(report, f"vertices_coords must be 2D, shape is {xy.shape}")
        return report
    if not np.isfinite(xy).all() or not np.isfinite(angles).all():
        _problem(report, "non-finite coordinates or fold angles")
        return report
    if len(faces) == 0:
        _problem(report, "the net has no faces")
        return report
    if len(src) != len(faces):
        _problem(report, f"{len(faces)} faces but {len(src)} faces_meshFace entries")
        return report
    folded = [fr for fr in fold["file_frames"] if "foldedForm" in fr.get("frame_classes", [])]
    if not folded or folded[0] is not fold["file_frames"][0]:
        _problem(report, "file_frames[0] is not the foldedForm")
        return report
    xyz = np.asarray(folded[0].get("vertices_coords", []), dtype=float)
    if xyz.shape != (len(xy), 3):
        _problem(report, f"foldedForm vertices_coords has shape {xyz.shape}, expected {(len(xy), 3)}")
        return report

    # a. structure
    edge_id, sides, ok_faces = _check_structure(report, xy, faces, edges, assign, angles)

    # b. congruence with the mesh (and the foldedForm is the mesh)
    _check_congruence(report, xy, xyz, faces, ok_faces, src, verts, polys, diag, tol, orientation)
    if orientation == "outward":
        _check_outward(report, xyz, faces, ok_faces, diag, tol)

    # c. overlaps in the plane
    safe = np.where(ok_faces[:, None], faces, 0)
    polys2d = [Polygon(xy[t]) for t in safe]
    scale = float(np.linalg.norm(np.ptp(xy, axis=0)))
    tree = STRtree(polys2d)
    pairs = tree.query(polys2d, predicate="intersects")
    i, j = pairs
    keep = (i < j) & ok_faces[i] & ok_faces[j]
    i, j = i[keep], j[keep]
    if len(i):
        areas = shapely.area(shapely.intersection(np.array(polys2d, dtype=object)[i], np.array(polys2d, dtype=object)[j]))
        hit = areas > 1e-9 * scale * scale
        report.overlaps = [(int(a), int(b)) for a, b in zip(i[hit], j[hit])]

    # d. pieces
    label, adj = _pieces(len(faces), sides, assign)
    report.pieces = int(label.max()) + 1
    if "polyfold:faces_piece" in fold:
        declared = np.asarray(fold["polyfold:faces_piece"])
        if declared.shape != label.shape:
            _problem(report, "polyfold:faces_piece has the wrong length")
        else:
            pairs_declared = set(zip(declared.tolist(), label.tolist()))
            if len(pairs_declared) != report.pieces or len(set(declared.tolist())) != report.pieces:
                _problem(report, f"polyfold:faces_piece ({len(set(declared.tolist()))} pieces) does not match "
                                 f"the {report.pieces} pieces joined by creases")

    # e. folding reproduces the foldedForm
    if len(edge_id):
        _check_folding(report, xy, xyz, faces, ok_faces, label, adj, angles, diag)
        if report.fold_error > tol:
            _problem(report, f"folding by the angles misses the foldedForm by {report.fold_error:.3g} (relative)")
    return report


def main(argv: list[str] | None = None) -> int:
    import argparse

    parser = argparse.ArgumentParser(description="Check a FOLD net against its mesh.")
    parser.add_argument("fold")
    parser.add_argument("mesh")
    parser.add_argument("--tol", type=float, default=1e-6)
    parser.add_argument("--orientation", choices=("source", "outward", "none"), default="source")
    args = parser.parse_args(argv)
    report = check_fold(args.fold, args.mesh, tol=args.tol, orientation=args.orientation)
    print(report)
    return 0 if report.ok else 1


if __name__ == "__main__":
    sys.exit(main())
