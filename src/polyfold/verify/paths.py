"""Independent re-verification of a written folding path (`polyfold:path` of a FOLD dict).

The planners (`fold/`) find a path with their own kinematics and collision kernel; before the
word "verified" is written anywhere, the path as it is written (FOLD degrees, valley positive) is
checked again here by a second implementation that shares no code with them: its own crease tree
(breadth-first from the lowest face of each piece), its own forward kinematics, its own broad
phase (sweep on z) and its own triangle tests (edge piercing and clipped-slab overlap, not the
planners' separating-axis test). Nothing here imports the rest of polyfold but its kernel
decorator (`jit.njit`: numba's, compiled ahead of time where it can be).

The physical model (README "Paper thickness"): faces are rigid plates of thickness `thickness`
(absolute, in the file's units). Two faces of one piece that are not the two faces of a crease
collide when

1. they cross: an edge of one passes through the other's interior (more than `tol` from its plane
   on both sides and from its sides), or
2. they come closer than the thickness with overlapping projections (with no thickness: they lie
   in one plane, within tol, and overlap): the part of one face within
   w = max(thickness, tol) of the other's plane, projected onto that plane, reaches more than w
   into the other face, in an area above tol x its longest side (paper lying on paper, whatever
   the tiny gap; a face resting on the other's edge touches it).

Exempt from 2, where plates meet anyway: the overlap lying entirely within `reach` (default
EXEMPT_REACH x thickness) of a point the two faces share in the net (they may touch at it) or of
either copy of a mesh vertex or edge they share on the model (they close onto each other there);
and every pair that shares a mesh vertex or edge where it is posed as on the model: at the goal
(the last frame), or earlier when the pair already holds its final pose (their nine corner
distances those of the foldedForm). Not modelled:
bending, the thickness at creases (two plates of one crease), glue and tab layers.

`check_fold_path(fold, step_deg, tol_rel, thickness)` samples every segment between consecutive
frames at t = k / m, m = ceil(max |angle change| / step_deg), and also checks the endpoints (first
frame flat, last frame the goal, cut edges never folded) and that the last frame rebuilds the
foldedForm (one rigid motion per piece). Every pair is tested at the first frame; along a segment,
only pairs of faces in different rigid bodies (`_bodies`: faces joined by creases that do not
turn in it move as one), as the pair test depends only on the two faces' relative pose, which
for two faces of one body is that at the segment's start, already checked. A sequential path
turns one or two creases per segment: its samples cost a tenth of testing every pair.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..jit import njit

# faces sharing a point may come within the thickness this many thicknesses from it (the same
# rule as the planners' collide.tolerance.EXEMPT_REACH, stated here again: nothing is imported)
EXEMPT_REACH = 10.0
CUT = ("B", "C")
# configurations x faces from which `check_fold_path` checks a path's two halves side by side
# (a fork costs about 10 ms; a configuration of a 300-face piece about 2 ms)
PARALLEL_CHECK_WORK = 50_000


@dataclass(frozen=True)
class PathCheck:
    """The verdict on one written path. first_collision: (segment, t, face i, face j) or None;
    problems: what else is wrong (endpoints, cut edges, the goal); configs: configurations checked."""

    ok: bool
    segments: int
    configs: int
    step_deg: float
    tol: float
    thickness: float
    first_collision: tuple[int, float, int, int] | None
    problems: tuple[str, ...]

    def why(self) -> str:
        """One line: what failed (empty when ok)."""
        if self.problems:
            return self.problems[0]
        if self.first_collision is not None:
            s, t, i, j = self.first_collision
            return f"segment {s} at t = {t:.4g}: faces {i} and {j} collide"
        return ""


# ----------------------------------------------------------------------------------------------
# The crease tree and forward kinematics


@dataclass(frozen=True)
class _Tree:
    flat: np.ndarray  # (F, 3, 3) flat corners, z = 0
    order: np.ndarray  # (F,) parents first
    parent: np.ndarray  # (F,) -1 at roots
    edge: np.ndarray  # (F,) the crease (edge index) to the parent, -1 at roots
    hinge: np.ndarray  # (F, 2, 3) the crease's ends as the parent runs it (CCW)
    piece: np.ndarray  # (F,) the piece (connected by creases) of each face


def _tree(coords: np.ndarray, faces: np.ndarray, edges: np.ndarray, assignment: list[str]) -> _Tree:
    """The crease tree, breadth-first from the lowest face of each piece."""
    n_f = len(faces)
    flat = np.zeros((n_f, 3, 3))
    flat[:, :, :2] = coords[faces][:, :, :2]
    key = {}
    for e, (u, v) in enumerate(edges.tolist()):
        if assignment[e] not in CUT:
            key[(min(u, v), max(u, v))] = e
    by_edge: dict[int, list[tuple[int, int, int]]] = {}
    for f in range(n_f):
        for k in range(3):
            u, v = int(faces[f, k]), int(faces[f, (k + 1) % 3])
            e = key.get((min(u, v), max(u, v)))
            if e is not None:
                by_edge.setdefault(e, []).append((f, u, v))
    nbrs: list[list[tuple[int, int, int, int]]] = [[] for _ in range(n_f)]
    for e, sides in by_edge.items():
        if len(sides) == 2:
            (f, u, v), (g, u2, v2) = sides
            nbrs[f].append((g, e, u, v))
            nbrs[g].append((f, e, u2, v2))
    parent = np.full(n_f, -1, dtype=np.int64)
    edge = np.full(n_f, -1, dtype=np.int64)
    piece = np.full(n_f, -1, dtype=np.int64)
    hinge = np.zeros((n_f, 2, 3))
    order = []
    for root in range(n_f):
        if piece[root] >= 0:
            continue
        piece[root] = root
        queue = deque([root])
        while queue:
            f = queue.popleft()
            order.append(f)
            for g, e, u, v in nbrs[f]:  # (u, v): the crease as f runs it
                if piece[g] < 0:
                    piece[g], parent[g], edge[g] = root, f, e
                    hinge[g, 0, :2], hinge[g, 1, :2] = coords[u][:2], coords[v][:2]
                    queue.append(g)
    return _Tree(flat, np.array(order, dtype=np.int64), parent, edge, hinge, piece)


@njit(cache=True)
def _fold(angles_deg, order, parent, edge, hinge, flat, out):
    """out (F, 3, 3) = the faces folded by angles_deg (E,) FOLD degrees (valley +): a child turns
    about its crease (directed as its parent runs it) by -angle, right-hand rule."""
    n = order.shape[0]
    rot = np.empty((n, 3, 3))
    tr = np.empty((n, 3))
    for ii in range(n):
        f = order[ii]
        p = parent[f]
        if p < 0:
            for i in range(3):
                for j in range(3):
                    rot[f, i, j] = 1.0 if i == j else 0.0
                tr[f, i] = 0.0
        else:
            a0, a1, a2 = hinge[f, 0, 0], hinge[f, 0, 1], hinge[f, 0, 2]
            d0, d1, d2 = hinge[f, 1, 0] - a0, hinge[f, 1, 1] - a1, hinge[f, 1, 2] - a2
            ln = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            d0, d1, d2 = d0 / ln, d1 / ln, d2 / ln
            th = -angles_deg[edge[f]] * math.pi / 180.0
            c, s = math.cos(th), math.sin(th)
            C = 1.0 - c
            # Rodrigues: the rotation by th about unit d
            m = ((c + d0 * d0 * C, d0 * d1 * C - d2 * s, d0 * d2 * C + d1 * s),
                 (d1 * d0 * C + d2 * s, c + d1 * d1 * C, d1 * d2 * C - d0 * s),
                 (d2 * d0 * C - d1 * s, d2 * d1 * C + d0 * s, c + d2 * d2 * C))
            # x -> P (a + m (x - a)) + tp  =  (P m) x + P (a - m a) + tp
            w0 = a0 - (m[0][0] * a0 + m[0][1] * a1 + m[0][2] * a2)
            w1 = a1 - (m[1][0] * a0 + m[1][1] * a1 + m[1][2] * a2)
            w2 = a2 - (m[2][0] * a0 + m[2][1] * a1 + m[2][2] * a2)
            for i in range(3):
                for j in range(3):
                    rot[f, i, j] = rot[p, i, 0] * m[0][j] + rot[p, i, 1] * m[1][j] + rot[p, i, 2] * m[2][j]
                tr[f, i] = rot[p, i, 0] * w0 + rot[p, i, 1] * w1 + rot[p, i, 2] * w2 + tr[p, i]
        for k in range(3):
            for i in range(3):
                out[f, k, i] = (rot[f, i, 0] * flat[f, k, 0] + rot[f, i, 1] * flat[f, k, 1]
                                + rot[f, i, 2] * flat[f, k, 2] + tr[f, i])
    return out


# ----------------------------------------------------------------------------------------------
# The pair test


@njit(cache=True)
def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@njit(cache=True)
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True)
def _crs(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@njit(cache=True)
def _corner(T, f, k):
    return (T[f, k, 0], T[f, k, 1], T[f, k, 2])


@njit(cache=True)
def _frame(T, f):
    """(unit normal, longest side, solid): solid False for a sliver (height <= 1e-9 x longest side)."""
    p0, p1, p2 = _corner(T, f, 0), _corner(T, f, 1), _corner(T, f, 2)
    n = _crs(_sub(p1, p0), _sub(p2, p0))
    ln = math.sqrt(_dot(n, n))
    longest = max(math.sqrt(_dot(_sub(p1, p0), _sub(p1, p0))), math.sqrt(_dot(_sub(p2, p1), _sub(p2, p1))),
                  math.sqrt(_dot(_sub(p0, p2), _sub(p0, p2))))
    if not (ln > 1e-9 * longest * longest) or longest == 0.0:
        return (0.0, 0.0, 0.0), longest, False
    return (n[0] / ln, n[1] / ln, n[2] / ln), longest, True


@njit(cache=True)
def _inside_by(T, f, n, x, margin):
    """True when point x (on f's plane) lies inside face f farther than margin from every side."""
    for k in range(3):
        a, b = _corner(T, f, k), _corner(T, f, (k + 1) % 3)
        side = _sub(b, a)
        inward = _crs(n, side)
        li = math.sqrt(_dot(inward, inward))
        if li == 0.0 or _dot(inward, _sub(x, a)) / li <= margin:
            return False
    return True


@njit(cache=True)
def _pierces(T, f, g, nf, tol):
    """True when an edge of face g passes through face f's interior (beyond tol)."""
    o = _corner(T, f, 0)
    for k in range(3):
        p, q = _corner(T, g, k), _corner(T, g, (k + 1) % 3)
        dp, dq = _dot(nf, _sub(p, o)), _dot(nf, _sub(q, o))
        if (dp > tol and dq < -tol) or (dp < -tol and dq > tol):
            s = dp / (dp - dq)
            x = (p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1]), p[2] + s * (q[2] - p[2]))
            if _inside_by(T, f, nf, x, tol):
                return True
    return False


@njit(cache=True)
def _clip(px, py, pz, qx, qy, qz, n, nx, o, w, sign):
    """Clip the convex polygon (px, py, pz)[:n] (in place, up to 8 corners; q*: scratch) to
    sign * nx.(x - o) <= w."""
    m = 0
    for k in range(n):
        k1 = (k + 1) % n
        da = sign * (nx[0] * (px[k] - o[0]) + nx[1] * (py[k] - o[1]) + nx[2] * (pz[k] - o[2])) - w
        db = sign * (nx[0] * (px[k1] - o[0]) + nx[1] * (py[k1] - o[1]) + nx[2] * (pz[k1] - o[2])) - w
        if da <= 0.0:
            qx[m], qy[m], qz[m] = px[k], py[k], pz[k]
            m += 1
        if (da < 0.0 < db) or (db < 0.0 < da):
            s = da / (da - db)
            qx[m] = px[k] + s * (px[k1] - px[k])
            qy[m] = py[k] + s * (py[k1] - py[k])
            qz[m] = pz[k] + s * (pz[k1] - pz[k])
            m += 1
    for k in range(m):
        px[k], py[k], pz[k] = qx[k], qy[k], qz[k]
    return m


@njit(cache=True)
def _near_feature(x, feats, nfeat, reach):
    """True when point x lies within reach of one of the features (segments a -> b; a point when a = b)."""
    for k in range(nfeat):
        a = (feats[k, 0], feats[k, 1], feats[k, 2])
        ab = (feats[k, 3] - a[0], feats[k, 4] - a[1], feats[k, 5] - a[2])
        l2 = _dot(ab, ab)
        ax = _sub(x, a)
        s = 0.0 if l2 == 0.0 else min(1.0, max(0.0, _dot(ax, ab) / l2))
        d = (ax[0] - s * ab[0], ax[1] - s * ab[1], ax[2] - s * ab[2])
        if _dot(d, d) <= reach * reach:
            return True
    return False


@njit(cache=True)
def _slab_overlap(T, f, g, nf, lf, w, tol, feats, nfeat, reach, buf, gshared):
    """True when the part of face g within w of face f's plane, projected onto it, overlaps f shrunk
    by w (a face resting on f's edge touches it) in an area above tol x f's longest side and,
    with features, not all within reach of them.
    buf (6, 8) scratch; gshared: bit k set when g's corner k is a point they share (a quick
    rejection: g's other corners beyond w on one side leave only a wedge at those points)."""
    o = _corner(T, f, 0)
    if gshared:
        wedge, area, sides, ok = 0.0, 1.0, 0, True
        for c in range(3):
            if gshared & (1 << c):
                continue
            d = _dot(nf, _sub(_corner(T, g, c), o))
            if abs(d) <= w:
                ok = False
                break
            sides |= 1 if d > 0 else 2
            for s_ in range(3):
                if gshared & (1 << s_):
                    e = _sub(_corner(T, g, c), _corner(T, g, s_))
                    ln = math.sqrt(_dot(e, e)) * w / abs(d)
                    wedge = max(wedge, ln)
                    area *= ln
        if ok and sides != 3 and (wedge + w <= reach or 0.5 * area <= tol * lf):
            return False
    px, py, pz, qx, qy, qz = buf[0], buf[1], buf[2], buf[3], buf[4], buf[5]
    for k in range(3):
        px[k], py[k], pz[k] = T[g, k, 0], T[g, k, 1], T[g, k, 2]
    n = _clip(px, py, pz, qx, qy, qz, np.int64(3), nf, o, w, 1.0)  # (a literal 3 compiles _clip twice)
    n = _clip(px, py, pz, qx, qy, qz, n, nf, o, w, -1.0)
    if n < 3:
        return False
    for k in range(n):  # onto f's plane
        d = nf[0] * (px[k] - o[0]) + nf[1] * (py[k] - o[1]) + nf[2] * (pz[k] - o[2])
        px[k], py[k], pz[k] = px[k] - d * nf[0], py[k] - d * nf[1], pz[k] - d * nf[2]
    for k in range(3):  # inside f, deeper than w: resting on its edge is touching
        a, b = _corner(T, f, k), _corner(T, f, (k + 1) % 3)
        out = _crs(_sub(b, a), nf)
        lo = math.sqrt(_dot(out, out))
        if lo == 0.0:
            return False
        n = _clip(px, py, pz, qx, qy, qz, n, (out[0] / lo, out[1] / lo, out[2] / lo), a, -w, 1.0)
        if n < 3:
            return False
    area = 0.0
    for k in range(1, n - 1):
        c = _crs((px[k] - px[0], py[k] - py[0], pz[k] - pz[0]), (px[k + 1] - px[0], py[k + 1] - py[0], pz[k + 1] - pz[0]))
        area += 0.5 * math.sqrt(_dot(c, c))
    if not (area > tol * lf):
        return False
    if nfeat == 0:
        return True
    for k in range(n):
        if not _near_feature((px[k], py[k], pz[k]), feats, nfeat, reach):
            return True
    return False


@njit(cache=True)
def _shared(faces, mesh_faces, T, i, j, feats):
    """The features faces i and j share, into feats (k, 6) as segments: (net vertices shared,
    mesh vertices shared, features written, bit masks of i's and j's corners at them). Mesh vertices: both copies (one per face); a shared
    mesh edge: both copies of the edge."""
    net = 0
    nfeat = 0
    mi, mj = 0, 0
    for a in range(3):
        for b in range(3):
            if faces[i, a] == faces[j, b]:
                net += 1
                mi |= 1 << a
                mj |= 1 << b
                for c in range(3):
                    feats[nfeat, c] = T[i, a, c]
                    feats[nfeat, 3 + c] = T[i, a, c]
                nfeat += 1
    mesh = 0
    ia = np.empty(2, dtype=np.int64)
    jb = np.empty(2, dtype=np.int64)
    for a in range(3):
        for b in range(3):
            if mesh_faces[i, a] >= 0 and mesh_faces[i, a] == mesh_faces[j, b]:
                mi |= 1 << a
                mj |= 1 << b
                if mesh < 2:
                    ia[mesh], jb[mesh] = a, b
                mesh += 1
                for c in range(3):
                    feats[nfeat, c] = T[i, a, c]
                    feats[nfeat, 3 + c] = T[i, a, c]
                    feats[nfeat + 1, c] = T[j, b, c]
                    feats[nfeat + 1, 3 + c] = T[j, b, c]
                nfeat += 2
    if mesh >= 2:  # a mesh edge: both copies as segments
        for c in range(3):
            feats[nfeat, c] = T[i, ia[0], c]
            feats[nfeat, 3 + c] = T[i, ia[1], c]
            feats[nfeat + 1, c] = T[j, jb[0], c]
            feats[nfeat + 1, 3 + c] = T[j, jb[1], c]
        nfeat += 2
    return net, mesh, nfeat, mi, mj


@njit(cache=True)
def _goal_pose(T, G, i, j, tol):
    """True when faces i and j are posed relative to each other as at the goal G (F, 3, 3): their
    nine corner-to-corner distances those of G within tol (G empty: never)."""
    if G.shape[0] == 0:
        return False
    for a in range(3):
        for b in range(3):
            d = _sub(_corner(T, i, a), _corner(T, j, b))
            e = _sub(_corner(G, i, a), _corner(G, j, b))
            if abs(math.sqrt(_dot(d, d)) - math.sqrt(_dot(e, e))) > tol:
                return False
    return True


@njit(cache=True)
def _pair_collides(T, G, nrm, lng, faces, mesh_faces, i, j, tol, thick, reach, goal, feats, buf):
    """The pair test of the module docstring for faces i, j of one piece, both solid (`_frame`;
    nrm, lng: their unit normals and longest sides; G: the faces at the goal, or empty)."""
    ni = (nrm[i, 0], nrm[i, 1], nrm[i, 2])
    nj = (nrm[j, 0], nrm[j, 1], nrm[j, 2])
    li, lj = lng[i], lng[j]
    net, mesh, nfeat, mi, mj = _shared(faces, mesh_faces, T, i, j, feats)
    if net >= 2:
        return False  # the two faces of a crease
    if _pierces(T, i, j, ni, tol) or _pierces(T, j, i, nj, tol):
        return True
    if mesh > 0 and (goal or _goal_pose(T, G, i, j, tol)):
        return False  # posed as on the model, where they meet (at the goal, or held so since)
    if thick <= 0.0:  # no thickness: only paper lying on paper (coplanar within tol) beyond crossing
        if not (_within(T, j, i, ni, tol) or _within(T, i, j, nj, tol)):
            return False
    w = max(thick, tol)
    r = max(reach, tol)
    return (_slab_overlap(T, i, j, ni, li, w, tol, feats, nfeat, r, buf, mj)
            or _slab_overlap(T, j, i, nj, lj, w, tol, feats, nfeat, r, buf, mi))


@njit(cache=True)
def _within(T, g, f, nf, tol):
    """True when every corner of face g lies within tol of face f's plane."""
    o = _corner(T, f, 0)
    for k in range(3):
        if abs(_dot(nf, _sub(_corner(T, g, k), o))) > tol:
            return False
    return True


@njit(cache=True)
def _first_pair(T, G, piece, body, faces, mesh_faces, tol, thick, reach, goal):
    """The first colliding pair (i, j) of folded faces T (F, 3, 3) by a sweep on z, or (-1, -1):
    of the pairs in one piece and in different rigid bodies (body (F,), see `_bodies`)."""
    n = T.shape[0]
    lo = np.empty((n, 3))
    hi = np.empty((n, 3))
    nrm = np.empty((n, 3))
    lng = np.empty(n)
    solid = np.empty(n, dtype=np.bool_)
    for f in range(n):
        u, lng[f], solid[f] = _frame(T, f)
        nrm[f, 0], nrm[f, 1], nrm[f, 2] = u
        for c in range(3):
            lo[f, c] = min(T[f, 0, c], T[f, 1, c], T[f, 2, c])
            hi[f, c] = max(T[f, 0, c], T[f, 1, c], T[f, 2, c])
    zs = np.argsort(lo[:, 2].copy())  # (contiguous: the quicksort the unfolder compiled, not another)
    m = max(thick, tol)
    feats = np.empty((16, 6))
    buf = np.empty((6, 8))
    for a in range(n):
        i = zs[a]
        if not solid[i]:
            continue  # a sliver has no interior
        for b in range(a + 1, n):
            j = zs[b]
            if lo[j, 2] > hi[i, 2] + m:
                break
            if piece[i] != piece[j] or body[i] == body[j] or not solid[j]:
                continue
            if lo[j, 0] > hi[i, 0] + m or lo[i, 0] > hi[j, 0] + m or lo[j, 1] > hi[i, 1] + m or lo[i, 1] > hi[j, 1] + m:
                continue
            if _pair_collides(T, G, nrm, lng, faces, mesh_faces, i, j, tol, thick, reach, goal, feats, buf):
                return min(i, j), max(i, j)
    return -1, -1


@njit(cache=True)
def _bodies(qa, qb, whole, order, parent, edge):
    """(F,) the rigid body of every face along the segment qa -> qb: faces joined by creases whose
    angle stays put (qa[e] == qb[e], so every sample has it bit for bit) move as one, and the
    pair test of two faces of one body, a function of their relative pose alone (distances, dot
    products, tolerances in model units), gives what it gave at qa. whole: every face a body of its
    own (every pair is tested)."""
    body = np.empty(order.shape[0], dtype=np.int64)
    for ii in range(order.shape[0]):
        f = order[ii]
        p = parent[f]
        body[f] = body[p] if p >= 0 and not whole and qa[edge[f]] == qb[edge[f]] else f
    return body


@njit(cache=True)
def _segment(qa, qb, m, k0, last, whole, order, parent, edge, hinge, flat, G, piece, faces, mesh_faces, tol, thick,
             reach):
    """Samples k0..m of qa -> qb (t = k / m): (first colliding k or -1, i, j, samples checked).
    last: the segment ends at the goal (its t = 1 gets the goal's exemption). Tested: the pairs of
    different rigid bodies (`_bodies`; whole: every pair), the others are as at qa, which the caller
    has checked (at qa every pair is free of collision, by induction from a whole check)."""
    q = np.empty(qa.shape[0])
    T = np.empty((flat.shape[0], 3, 3))
    body = _bodies(qa, qb, whole, order, parent, edge)
    checked = 0
    for k in range(k0, m + 1):
        t = k / m if m > 0 else 1.0
        for e in range(qa.shape[0]):
            q[e] = qa[e] + t * (qb[e] - qa[e]) if k < m else qb[e]
        _fold(q, order, parent, edge, hinge, flat, T)
        checked += 1
        i, j = _first_pair(T, G, piece, body, faces, mesh_faces, tol, thick, reach, last and k == m)
        if i >= 0:
            return k, i, j, checked
    return -1, -1, -1, checked


def faces_collide(a: np.ndarray, b: np.ndarray, tol: float, thickness: float = 0.0) -> bool:
    """The pair test for two faces a, b (3, 3) that share nothing (no crease, no point)."""
    T = np.stack([np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)])
    faces = np.array([[0, 1, 2], [3, 4, 5]], dtype=np.int64)
    i, _ = _first_pair(T, np.empty((0, 3, 3)), np.zeros(2, dtype=np.int64), np.arange(2), faces, np.full((2, 3), -1, dtype=np.int64), float(tol),
                       float(thickness), EXEMPT_REACH * float(thickness), False)
    return bool(i >= 0)


# ----------------------------------------------------------------------------------------------
# The path


def _diagonal(pts: np.ndarray) -> float:
    return float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0))) if len(pts) else 0.0


def check_fold_path(fold: dict, step_deg: float | None = None, tol_rel: float | None = None,
                    thickness: float = 0.0, reach: float | None = None,
                    side_by_side: Callable[[Callable, Callable], tuple] | None = None) -> PathCheck:
    """Re-verify the `polyfold:path` of a FOLD dict (see the module docstring).

    step_deg: largest angle change between samples (default: the file's
    `polyfold:path_resolutionDeg`, else 1); tol_rel: contact tolerance relative to the bounding-box
    diagonal of the foldedForm (default: the file's `polyfold:path_contactTol`, else 1e-7);
    thickness: absolute, in the file's units; reach: the exemption radius around shared points
    (default EXEMPT_REACH x thickness). side_by_side: a function that runs its two arguments at
    once and returns both results (polyfold's `processes.beside`, a forked process: given by the
    caller, as nothing of polyfold is imported here); with it a long path (configurations x faces
    at least PARALLEL_CHECK_WORK) has its later half of segments checked meanwhile, for the same
    verdict."""
    step = float(step_deg if step_deg is not None else fold.get("polyfold:path_resolutionDeg", 1.0))
    tol_rel = float(tol_rel if tol_rel is not None else fold.get("polyfold:path_contactTol", 1e-7))
    coords = np.asarray(fold["vertices_coords"], dtype=np.float64)
    faces = np.asarray(fold["faces_vertices"], dtype=np.int64)
    edges = np.asarray(fold["edges_vertices"], dtype=np.int64)
    assignment = [str(a).upper() for a in fold["edges_assignment"]]
    goal = np.asarray(fold.get("edges_foldAngle", [0.0] * len(edges)), dtype=np.float64)
    frames = np.asarray(fold.get("polyfold:path") or [], dtype=np.float64)
    folded = None
    for fr in fold.get("file_frames", []):
        if "foldedForm" in fr.get("frame_classes", []) and "vertices_coords" in fr:
            folded = np.asarray(fr["vertices_coords"], dtype=np.float64)
    scale = _diagonal(folded if folded is not None else coords)
    tol = tol_rel * scale
    thick = float(thickness)
    r = EXEMPT_REACH * thick if reach is None else float(reach)
    problems: list[str] = []

    def verdict(first=None, segments=0, configs=0) -> PathCheck:
        return PathCheck(not problems and first is None, segments, configs, step, tol, thick, first, tuple(problems))

    if frames.ndim != 2 or len(frames) < 2 or frames.shape[1] != len(edges):
        problems.append(f"the path needs at least 2 frames of {len(edges)} angles")
        return verdict()
    if not np.isfinite(frames).all():
        problems.append("the path has angles that are not finite numbers")
        return verdict()
    cut = np.array([a in CUT for a in assignment])
    if np.abs(frames[0]).max(initial=0.0) > 1e-9:
        problems.append("the path does not start flat")
    if np.abs(frames[-1] - goal).max(initial=0.0) > 1e-6:
        problems.append("the path does not end at the goal angles (edges_foldAngle)")
    if cut.any() and np.abs(frames[:, cut]).max() > 0.0:
        problems.append("the path folds a cut edge")
    if problems:
        return verdict()
    tree = _tree(coords, faces, edges, assignment)
    mesh_vertex = fold.get("polyfold:vertices_meshVertex")
    mesh_faces = (np.asarray(mesh_vertex, dtype=np.int64)[faces] if mesh_vertex is not None
                  else np.full_like(faces, -1))
    G = np.ascontiguousarray(folded[faces]) if folded is not None else np.empty((0, 3, 3))
    args = (tree.order, tree.parent, tree.edge, tree.hinge, tree.flat, G, tree.piece, faces, mesh_faces, tol, thick, r)
    if folded is not None:
        err = _goal_error(frames[-1], tree, faces, folded)
        if err > 1e-6 * max(scale, 1e-300):
            problems.append(f"the last frame does not rebuild the folded form (off by {err / scale:.2g} of its size)")
            return verdict()
    n_segments = len(frames) - 1
    samples = [max(1, int(math.ceil(float(np.abs(frames[s + 1] - frames[s]).max()) / step - 1e-9)))
               for s in range(n_segments)]

    def run(lo: int, hi: int) -> tuple[tuple[int, float, int, int] | None, int, int]:
        """Frame lo (every pair: the base of `_segment`'s induction), then segments lo..hi-1: (the
        first collision or None, the segments checked up to it, the configurations checked)."""
        k, i, j, configs = _segment(frames[lo], frames[lo], 0, 0, lo == len(frames) - 1, True, *args)
        if k >= 0:
            return (lo, 0.0, int(i), int(j)), lo, configs
        for s in range(lo, hi):
            m = samples[s]
            k, i, j, n = _segment(frames[s], frames[s + 1], m, 1, s == len(frames) - 2, False, *args)
            configs += n
            if k >= 0:
                return (s, k / m, int(i), int(j)), s + 1, configs
        return None, hi, configs

    if side_by_side is not None and n_segments > 1 and (1 + sum(samples)) * len(faces) >= PARALLEL_CHECK_WORK:
        # the later segments meanwhile (from a whole check of their first frame); their verdict
        # counts only when the earlier ones pass (so it is the verdict of checking them in order)
        mid = int(np.searchsorted(np.cumsum(samples), sum(samples) / 2)) + 1
        mid = min(max(mid, 1), n_segments - 1)
        (first, segments, configs), (later, later_segments, later_configs) = side_by_side(
            lambda: run(0, mid), lambda: run(mid, n_segments))
        if first is None:  # (frame mid, the earlier half's last, counted once)
            first, segments, configs = later, later_segments, configs + later_configs - 1
        return verdict(first, segments, configs)
    return verdict(*run(0, n_segments))


def _goal_error(goal_deg: np.ndarray, tree: _Tree, faces: np.ndarray, folded: np.ndarray) -> float:
    """Largest distance between the faces folded by the goal and the foldedForm, after one rigid
    motion per piece (Kabsch)."""
    T = _fold(goal_deg, tree.order, tree.parent, tree.edge, tree.hinge, tree.flat, np.empty((len(faces), 3, 3)))
    err = 0.0
    for p in np.unique(tree.piece):
        sel = tree.piece == p
        src = T[sel].reshape(-1, 3)
        dst = folded[faces[sel]].reshape(-1, 3)
        cs, cd = src.mean(axis=0), dst.mean(axis=0)
        u, _, vt = np.linalg.svd((src - cs).T @ (dst - cd))
        d = 1.0 if np.linalg.det(vt.T @ u.T) >= 0 else -1.0
        rot = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
        err = max(err, float(np.abs((src - cs) @ rot.T + cd - dst).max()))
    return err
