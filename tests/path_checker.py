"""An independent checker of folding paths (`polyfold:path`) written by `polyfold fold`.

Stands alone on purpose: it does not import polyfold (numpy, shapely and json only), so it shares
no code, and so no bugs, with the planner it checks. It builds its own crease tree, folds the net
itself and has its own triangle-triangle test (edge-through-interior, chord overlap and coplanar
area tests; not the separating-axis test the package uses). Usage:

    python tests/path_checker.py OUT.fold [--step-deg 1] [--tol-rel 1e-7]

`check_path(fold_path_or_dict)` verifies

a. the path's endpoints: the first frame is all zeros, the last frame is edges_foldAngle, cut (B)
   edges stay at 0 in every frame, every frame has one finite angle per edge;
b. folding by the last frame reproduces the foldedForm frame, up to one rigid motion per piece;
c. every straight segment between consecutive frames is free of self-intersection, sampled at
   t = k / m, k = 0..m, m = ceil(max |delta angle| / step_deg): every pair of faces of one piece is
   tested except the two faces of each crease (faces sharing only a vertex and the twins of a cut
   edge are tested too). Touching within tol (tol_rel * bounding-box diagonal) is allowed,
   crossing is not, and neither is paper lying on paper (coplanar interiors overlapping).

Conventions (FOLD): fold angles in degrees, valley positive, mountain negative. The lowest face
of each piece stays in the plane z = 0 (outer side +z); each other face is its tree parent's
transform composed with a rotation about the shared edge by -radians(foldAngle), around the axis
directed along the edge as the parent runs it (CCW), right-hand rule: a mountain (negative angle)
turns the child below the parent's plane.
"""

from __future__ import annotations

import json
import math
import os
import sys
from collections import deque
from dataclasses import dataclass, field

import numpy as np
import shapely

CUT = ("B", "C")  # edge assignments that do not join faces
CHUNK = 64  # configurations folded and tested at once


# ----------------------------------------------------------------------------------------------
# Report


@dataclass
class Report:
    pieces: int = 0
    faces: int = 0
    frames: int = 0
    segments: int = 0
    configs_checked: int = 0
    step_deg: float = 1.0
    resolution_deg: float | None = None  # as stated in the file (polyfold:path_resolutionDeg)
    tol_rel: float = 1e-7  # contact tolerance used, relative to the bounding-box diagonal
    stated_tol_rel: float | None = None  # as stated in the file (polyfold:path_contactTol)
    first_collision: tuple[int, float, int, int] | None = None  # (segment, t, face i, face j)
    fold_error: float = 0.0  # last frame vs foldedForm after per-piece alignment, relative to the diagonal
    problems: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.problems and self.first_collision is None

    def __str__(self) -> str:
        hit = "none"
        if self.first_collision is not None:
            s, t, i, j = self.first_collision
            hit = f"segment {s} at t = {t:.6g}: faces {i} and {j} cross"
        lines = [
            f"ok: {self.ok}",
            f"faces: {self.faces}",
            f"pieces: {self.pieces}",
            f"frames: {self.frames}",
            f"segments: {self.segments}",
            f"step: {self.step_deg:g} deg (file states {self.resolution_deg})",
            f"contact tolerance: {self.tol_rel:g} of the diagonal (file states {self.stated_tol_rel})",
            f"configurations checked: {self.configs_checked}",
            f"fold error: {self.fold_error:.3g}",
            f"first collision: {hit}",
        ]
        lines += [f"problem: {p}" for p in self.problems[:50]]
        if len(self.problems) > 50:
            lines.append(f"... and {len(self.problems) - 50} more problems")
        return "\n".join(lines)


# ----------------------------------------------------------------------------------------------
# Geometry helpers


def _unit(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(v / |v|, |v|) along the last axis; zero vectors stay zero."""
    n = np.linalg.norm(v, axis=-1)
    return v / np.where(n > 0, n, 1.0)[..., None], n


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("...i,...i->...", a, b)


def _rotations(axis: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Right-hand rotations (S, 3, 3) about the unit vector `axis` by angles (S,) radians."""
    x, y, z = axis
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    s = np.sin(angles)[:, None, None]
    c = (1.0 - np.cos(angles))[:, None, None]
    return np.eye(3)[None] + s * k[None] + c * (k @ k)[None]


def _kabsch(src: np.ndarray, dst: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Proper rotation R and translation t minimizing |R src + t - dst|."""
    cs, cd = src.mean(axis=0), dst.mean(axis=0)
    u, _, vt = np.linalg.svd((src - cs).T @ (dst - cd))
    d = np.sign(np.linalg.det(vt.T @ u.T)) or 1.0
    r = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return r, cd - r @ cs


# ----------------------------------------------------------------------------------------------
# Triangle-triangle crossing (vectorized over pairs)


def _edges_through(X, Y, d, nY, tol):
    """(K,) True where an edge of triangle X passes through the plane of Y (its ends farther than
    tol on both sides) at a point inside Y farther than tol from Y's boundary.
    d (K, 3): signed distances of X's corners to Y's plane; nY (K, 3) unit normal of Y."""
    inward = []
    for j in range(3):
        m, _ = _unit(np.cross(nY, Y[:, (j + 1) % 3] - Y[:, j]))  # n x edge points into Y
        inward.append(m)
    hit = np.zeros(len(X), dtype=bool)
    for i in range(3):
        dp, dq = d[:, i], d[:, (i + 1) % 3]
        through = ((dp > tol) & (dq < -tol)) | ((dp < -tol) & (dq > tol))
        if not through.any():
            continue
        s = np.where(through, dp / np.where(through, dp - dq, 1.0), 0.0)
        p = X[:, i] + s[:, None] * (X[:, (i + 1) % 3] - X[:, i])
        depth = np.min([_dot(p - Y[:, j], inward[j]) for j in range(3)], axis=0)
        hit |= through & (depth > tol)
    return hit


def _chord(X, d, direction, tol):
    """Interval (lo, hi) along `direction` of X's intersection with the other plane (d: signed
    distances of X's corners to it): corners within tol of it and edge crossings; and a point of
    that intersection (K, 3) with its parameter (K,), to place the line."""
    lo = np.full(len(X), np.inf)
    hi = np.full(len(X), -np.inf)
    anchor = np.zeros((len(X), 3))
    at = np.zeros(len(X))
    for i in range(3):
        on = np.abs(d[:, i]) <= tol
        dp, dq = d[:, i], d[:, (i + 1) % 3]
        through = ((dp > tol) & (dq < -tol)) | ((dp < -tol) & (dq > tol))
        s = np.where(through, dp / np.where(through, dp - dq, 1.0), 0.0)
        p = X[:, i] + s[:, None] * (X[:, (i + 1) % 3] - X[:, i])
        for mask, point in ((on, X[:, i]), (through, p)):
            t = _dot(point, direction)
            anchor = np.where(mask[:, None], point, anchor)
            at = np.where(mask, t, at)
            lo = np.where(mask, np.minimum(lo, t), lo)
            hi = np.where(mask, np.maximum(hi, t), hi)
    return lo, hi, anchor, at


def _inward(T, n):
    """Unit in-plane inward normals (K, 3, 3) of the sides of triangles T (unit normals n)."""
    return np.stack([_unit(np.cross(n, T[:, (j + 1) % 3] - T[:, j]))[0] for j in range(3)], axis=1)


def _deepest_on_segment(anchor, at, direction, s0, s1, tris, inward):
    """max over s in [s0, s1] of the depth of the point anchor + (s - at) direction inside every
    triangle of `tris` (depth: least in-plane distance to the triangle's sides; negative outside).
    The depth is a minimum of affine functions of s: its maximum is at an end or a crossing."""
    c, g = [], []
    for T, m in zip(tris, inward):
        for j in range(3):
            c.append(_dot(anchor - at[:, None] * direction - T[:, j], m[:, j]))
            g.append(_dot(direction, m[:, j]))
    c, g = np.array(c).T, np.array(g).T  # (K, 6): depth_k(s) = c_k + g_k s
    cand = [s0, s1]
    n = c.shape[1]
    for a in range(n):
        for b in range(a + 1, n):
            dg = g[:, b] - g[:, a]
            s = np.where(np.abs(dg) > 1e-300, (c[:, a] - c[:, b]) / np.where(np.abs(dg) > 1e-300, dg, 1.0), s0)
            cand.append(np.clip(s, s0, s1))
    cand = np.array(cand).T  # (K, candidates)
    depth = (c[:, None, :] + g[:, None, :] * cand[:, :, None]).min(axis=2)
    return depth.max(axis=1)


def _coplanar_overlap(base, other, n, tol, longest):
    """(K,) True where the triangles, projected to base's plane (unit normal n), overlap by an area
    larger than tol * longest."""
    u, _ = _unit(base[:, 1] - base[:, 0])
    v = np.cross(n, u)
    out = np.zeros(len(base), dtype=bool)
    if not len(base):
        return out
    o = base[:, 0][:, None, :]
    pa = np.stack([_dot(base - o, u[:, None, :]), _dot(base - o, v[:, None, :])], axis=-1)
    pb = np.stack([_dot(other - o, u[:, None, :]), _dot(other - o, v[:, None, :])], axis=-1)
    area = shapely.area(shapely.intersection(shapely.polygons(pa), shapely.polygons(pb)))
    return area > tol * longest


def triangles_cross(A: np.ndarray, B: np.ndarray, tol: float) -> np.ndarray:
    """(K,) True where triangles A[k], B[k] (K, 3, 3) cross: their relative interiors meet by more
    than tol. Touching (a shared corner or edge, a corner or an edge resting on the other face)
    is no crossing; coplanar triangles whose interiors overlap (area > tol x longest side) are.

    A pair crosses when (a) an edge of one passes through the interior of the other, farther than
    tol from its boundary (both ways), or (b) they are coplanar within tol and overlap in area, or
    (c) each straddles the other's plane by more than tol and their chords on the planes'
    intersection line overlap in a segment reaching deeper than tol into both triangles (catches
    crossings through a shared corner, where the crossing points of (a) lie on the boundaries).
    Degenerate triangles (height over the longest side <= tol) never cross.
    """
    A = np.asarray(A, dtype=float).reshape(-1, 3, 3)
    B = np.asarray(B, dtype=float).reshape(-1, 3, 3)
    nA, areaA = _unit(np.cross(A[:, 1] - A[:, 0], A[:, 2] - A[:, 0]))
    nB, areaB = _unit(np.cross(B[:, 1] - B[:, 0], B[:, 2] - B[:, 0]))
    longA = np.linalg.norm(A - np.roll(A, -1, axis=1), axis=-1).max(axis=1)
    longB = np.linalg.norm(B - np.roll(B, -1, axis=1), axis=-1).max(axis=1)
    solid = (areaA > tol * longA) & (areaB > tol * longB) & (longA > 0) & (longB > 0)
    dA = _dot(A - B[:, :1], nB[:, None, :])  # A's corners to B's plane
    dB = _dot(B - A[:, :1], nA[:, None, :])  # B's corners to A's plane
    hit = _edges_through(A, B, dA, nB, tol) | _edges_through(B, A, dB, nA, tol)

    # (b) coplanar
    a_in_b = (np.abs(dA) <= tol).all(axis=1)
    b_in_a = (np.abs(dB) <= tol).all(axis=1) & ~a_in_b
    longest = np.maximum(longA, longB)
    for mask, base, other, n in ((a_in_b, B, A, nB), (b_in_a, A, B, nA)):
        idx = np.flatnonzero(mask & solid & ~hit)
        if len(idx):
            hit[idx] |= _coplanar_overlap(base[idx], other[idx], n[idx], tol, longest[idx])

    # (c) chords on the line where the planes meet: they overlap, and the overlap reaches deeper
    # than tol into both triangles (an overlap along a side of one is touching, not crossing)
    straddle = ((dA.max(axis=1) > tol) & (dA.min(axis=1) < -tol)
                & (dB.max(axis=1) > tol) & (dB.min(axis=1) < -tol))
    idx = np.flatnonzero(straddle & solid & ~hit)
    if len(idx):
        line, size = _unit(np.cross(nA[idx], nB[idx]))
        loA, hiA, anchor, at = _chord(A[idx], dA[idx], line, tol)
        loB, hiB, _, _ = _chord(B[idx], dB[idx], line, tol)
        s0, s1 = np.maximum(loA, loB), np.minimum(hiA, hiB)
        ok = (size > 1e-12) & (s1 - s0 > tol)
        if ok.any():
            k = np.flatnonzero(ok)
            deep = _deepest_on_segment(anchor[k], at[k], line[k], s0[k], s1[k], (A[idx[k]], B[idx[k]]),
                                       (_inward(A[idx[k]], nA[idx[k]]), _inward(B[idx[k]], nB[idx[k]])))
            hit[idx[k]] |= deep > tol
    return hit & solid


# ----------------------------------------------------------------------------------------------
# The net: own crease tree, own folding, own collision test


class FoldNet:
    """A FOLD net prepared for folding: crease tree per piece, candidate face pairs, tolerance."""

    def __init__(self, fold: dict, tol_rel: float = 1e-7):
        xy = np.asarray(fold["vertices_coords"], dtype=float)
        if xy.ndim != 2 or xy.shape[1] not in (2, 3):
            raise ValueError(f"vertices_coords has shape {xy.shape}")
        self.xy = xy[:, :2]
        self.faces = np.asarray(fold["faces_vertices"], dtype=np.int64).reshape(-1, 3)
        self.edges = np.asarray(fold["edges_vertices"], dtype=np.int64).reshape(-1, 2)
        self.assign = [str(a).upper() for a in fold["edges_assignment"]]
        self.angles = np.asarray(fold.get("edges_foldAngle", np.zeros(len(self.edges))), dtype=float)
        n_f, n_e = len(self.faces), len(self.edges)
        if len(self.assign) != n_e or self.angles.shape != (n_e,):
            raise ValueError(f"{n_e} edges, {len(self.assign)} assignments, {self.angles.size} fold angles")
        self.cut = np.array([a in CUT for a in self.assign], dtype=bool)
        self.folded = None
        for frame in fold.get("file_frames") or []:
            if isinstance(frame, dict) and "foldedForm" in (frame.get("frame_classes") or []):
                self.folded = np.asarray(frame["vertices_coords"], dtype=float).reshape(-1, 3)
                break
        ref = self.folded if self.folded is not None else self.xy
        self.scale = float(np.linalg.norm(ref.max(axis=0) - ref.min(axis=0)))
        self.tol = tol_rel * self.scale

        # the face sides: edge -> [(face, a, b)] with a -> b as the face runs it (CCW)
        edge_of = {}
        for e, (u, v) in enumerate(self.edges.tolist()):
            edge_of[(min(u, v), max(u, v))] = e
        sides: dict[int, list[tuple[int, int, int]]] = {}
        for f, tri in enumerate(self.faces.tolist()):
            for k in range(3):
                a, b = tri[k], tri[(k + 1) % 3]
                e = edge_of.get((min(a, b), max(a, b)))
                if e is None:
                    raise ValueError(f"side {a}-{b} of face {f} is not an edge")
                sides.setdefault(e, []).append((f, a, b))
        neighbours: list[list[tuple[int, int, int, int]]] = [[] for _ in range(n_f)]
        hinge = set()
        for e, lst in sides.items():
            if self.cut[e]:
                continue
            if len(lst) != 2:
                raise ValueError(f"crease {e} borders {len(lst)} faces")
            (f, a, b), (g, c, d) = lst
            neighbours[f].append((g, e, a, b))
            neighbours[g].append((f, e, c, d))
            hinge.add((min(f, g), max(f, g)))

        # BFS tree from the lowest face of each piece
        self.piece = np.full(n_f, -1, dtype=np.int64)
        self.order: list[tuple[int, int, int, int, int]] = []  # (face, parent, edge, a, b)
        n_p = 0
        for root in range(n_f):
            if self.piece[root] >= 0:
                continue
            self.piece[root] = n_p
            self.order.append((root, -1, -1, -1, -1))
            queue = deque([root])
            while queue:
                f = queue.popleft()
                for g, e, a, b in sorted(neighbours[f]):
                    if self.piece[g] < 0:
                        self.piece[g] = n_p
                        self.order.append((g, f, e, a, b))
                        queue.append(g)
            n_p += 1
        self.n_pieces = n_p
        # every pair of faces of one piece except the two faces of a crease
        i, j = np.triu_indices(n_f, k=1)
        keep = self.piece[i] == self.piece[j]
        if hinge:
            h = np.array(sorted(hinge))
            code = i * n_f + j
            keep &= ~np.isin(code, h[:, 0] * n_f + h[:, 1])
        self.pair_i, self.pair_j = i[keep], j[keep]

    @property
    def n_faces(self) -> int:
        return len(self.faces)

    def fold(self, angles_deg) -> np.ndarray:
        """Face corners (S, F, 3, 3) for fold angles (S, E) or (E,) in FOLD degrees
        (a single configuration gives (F, 3, 3))."""
        q = np.asarray(angles_deg, dtype=float)
        single = q.ndim == 1
        q = q.reshape(-1, len(self.edges))
        n_s = len(q)
        rad = -np.radians(q)
        R = np.empty((n_s, self.n_faces, 3, 3))
        t = np.empty((n_s, self.n_faces, 3))
        p3 = np.zeros((len(self.xy), 3))
        p3[:, :2] = self.xy
        for f, p, e, a, b in self.order:
            if p < 0:
                R[:, f] = np.eye(3)
                t[:, f] = 0.0
                continue
            pa = p3[a]
            axis, _ = _unit(p3[b] - pa)
            rot = _rotations(axis, rad[:, e])  # in the flat sheet's frame
            R[:, f] = R[:, p] @ rot
            t[:, f] = np.einsum("sij,sj->si", R[:, p], pa - rot @ pa) + t[:, p]
        flat = p3[self.faces]  # (F, 3, 3)
        out = np.einsum("sfij,fkj->sfki", R, flat) + t[:, :, None, :]
        return out[0] if single else out

    def collisions(self, pos: np.ndarray) -> list[tuple[int, int] | None]:
        """First crossing face pair (i < j, lowest i then j) of each configuration pos (S, F, 3, 3)."""
        pos = np.asarray(pos, dtype=float)
        if pos.ndim == 3:
            pos = pos[None]
        out: list[tuple[int, int] | None] = [None] * len(pos)
        if not len(self.pair_i):
            return out
        lo, hi = pos.min(axis=2), pos.max(axis=2)  # (S, F, 3)
        I, J = self.pair_i, self.pair_j
        near = ((lo[:, I] <= hi[:, J] + self.tol) & (lo[:, J] <= hi[:, I] + self.tol)).all(axis=2)
        s, p = np.nonzero(near)
        if not len(s):
            return out
        hit = triangles_cross(pos[s, I[p]], pos[s, J[p]], self.tol)
        for k in np.flatnonzero(hit):  # nonzero is row-major: ascending (sample, pair)
            if out[s[k]] is None:
                out[s[k]] = (int(I[p[k]]), int(J[p[k]]))
        return out

    def first_collision(self, angles_deg) -> tuple[int, int] | None:
        """The first crossing face pair of one configuration (FOLD degrees), or None."""
        return self.collisions(self.fold(np.asarray(angles_deg, dtype=float)))[0]

    def segment_collision(self, qa, qb, step_deg: float = 1.0, skip_start: bool = False):
        """Check the segment qa -> qb at t = k/m, k = 0..m, m = ceil(max|qb - qa| / step_deg).

        Returns (configurations checked, None or (t, face i, face j) of the first crossing)."""
        qa = np.asarray(qa, dtype=float)
        qb = np.asarray(qb, dtype=float)
        span = float(np.abs(qb - qa).max()) if len(qa) else 0.0
        m = max(int(math.ceil(span / step_deg - 1e-12)), 1)
        ks = np.arange(1 if skip_start else 0, m + 1)
        checked = 0
        for c in range(0, len(ks), CHUNK):
            t = ks[c:c + CHUNK] / m
            q = qa[None] + t[:, None] * (qb - qa)[None]
            hits = self.collisions(self.fold(q))
            for k, h in enumerate(hits):
                checked += 1
                if h is not None:
                    return checked, (float(t[k]), h[0], h[1])
        return checked, None


# ----------------------------------------------------------------------------------------------
# The check


def _load(fold_path_or_dict) -> dict:
    if isinstance(fold_path_or_dict, dict):
        return fold_path_or_dict
    with open(os.fspath(fold_path_or_dict), encoding="utf-8") as fh:
        return json.load(fh)


def check_path(fold_path_or_dict, step_deg: float = 1.0, tol_rel: float | None = 1e-7) -> Report:
    """Check the `polyfold:path` of a FOLD file (path or dict); see the module docstring.

    tol_rel None: the contact tolerance the file states (polyfold:path_contactTol), else 1e-7."""
    fold = _load(fold_path_or_dict)
    stated = fold.get("polyfold:path_contactTol")
    if tol_rel is None:
        tol_rel = float(stated) if stated is not None else 1e-7
    report = Report(step_deg=step_deg, tol_rel=tol_rel, stated_tol_rel=stated)
    try:
        net = FoldNet(fold, tol_rel)
    except (KeyError, ValueError, TypeError, IndexError) as exc:
        report.problems.append(f"not a usable net: {type(exc).__name__}: {exc}")
        return report
    report.faces, report.pieces = net.n_faces, net.n_pieces
    report.resolution_deg = fold.get("polyfold:path_resolutionDeg")
    if "polyfold:path" not in fold:
        report.problems.append("no 'polyfold:path'")
        return report
    n_e = len(net.edges)
    try:
        frames = np.asarray(fold["polyfold:path"], dtype=float)
    except (ValueError, TypeError):
        report.problems.append("'polyfold:path' is not a list of equally long lists of numbers")
        return report
    report.frames = len(frames)
    if frames.ndim != 2 or frames.shape[1] != n_e:
        report.problems.append(f"'polyfold:path' has shape {frames.shape}, expected (frames, {n_e})")
        return report
    if len(frames) < 2:
        report.problems.append(f"'polyfold:path' has {len(frames)} frame(s), at least 2 needed")
        return report
    if not np.isfinite(frames).all():
        report.problems.append("'polyfold:path' has non-finite angles")
        return report

    # a. endpoints
    if np.abs(frames[0]).max() > 1e-9:
        e = int(np.argmax(np.abs(frames[0])))
        report.problems.append(f"first frame is not flat: edge {e} at {frames[0, e]} deg")
    diff = np.abs(frames[-1] - net.angles)
    if diff.max() > 1e-9:
        e = int(np.argmax(diff))
        report.problems.append(f"last frame differs from edges_foldAngle: edge {e} at {frames[-1, e]} deg, "
                               f"goal {net.angles[e]} deg")
    bad = np.argwhere(np.abs(frames[:, net.cut]) > 0)
    if len(bad):
        k, e = bad[0]
        report.problems.append(f"cut edge {np.flatnonzero(net.cut)[e]} is at {frames[k, np.flatnonzero(net.cut)[e]]} "
                               f"deg in frame {k} ({len(bad)} such entries)")

    # b. the last frame folds into the foldedForm
    if net.folded is None or net.folded.shape != (len(net.xy), 3):
        report.problems.append("no foldedForm frame with one 3D point per vertex")
    elif net.scale > 0:
        pos = net.fold(frames[-1])
        worst = 0.0
        for k in range(net.n_pieces):
            members = np.flatnonzero(net.piece == k)
            src = pos[members].reshape(-1, 3)
            dst = net.folded[net.faces[members]].reshape(-1, 3)
            r, t = _kabsch(src, dst)
            worst = max(worst, float(np.linalg.norm(src @ r.T + t - dst, axis=1).max()) / net.scale)
        report.fold_error = worst
        if worst > 1e-6:
            report.problems.append(f"folding by the last frame misses the foldedForm by {worst:.3g} (relative)")

    # c. every segment, sampled
    report.segments = len(frames) - 1
    for s in range(len(frames) - 1):
        n, hit = net.segment_collision(frames[s], frames[s + 1], step_deg, skip_start=s > 0)
        report.configs_checked += n
        if hit is not None:
            report.first_collision = (s, *hit)
            break
    return report


def main(argv: list[str] | None = None) -> int:
    import argparse

    parser = argparse.ArgumentParser(description="Check the folding path (polyfold:path) of a FOLD file.")
    parser.add_argument("fold")
    parser.add_argument("--step-deg", type=float, default=1.0)
    parser.add_argument("--tol-rel", type=float, default=1e-7,
                        help="contact tolerance relative to the bounding-box diagonal (0 or less: as the file states)")
    args = parser.parse_args(argv)
    report = check_path(args.fold, step_deg=args.step_deg, tol_rel=args.tol_rel if args.tol_rel > 0 else None)
    print(report)
    return 0 if report.ok else 1


if __name__ == "__main__":
    sys.exit(main())
