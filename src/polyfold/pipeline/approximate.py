"""make's `--approximate hulls` stage: the mesh segmented into nearly convex parts, every part
replaced by a closed convex polyhedron (`approximate.hulls`), the polyhedra interior-disjoint.

In: the (simplified, inflated) Mesh and make's options. Out: the approximated model as one Mesh
whose connected components are the parts' polyhedra (part order = component order; make unfolds
every component whole, as for any mesh of several closed solids), with the segmentation's and
the approximation's reports. Every pair of polyhedra is checked apart by an LP of its own
(`approximate.error.lp_overlap_depths`, not the clipping that made them) and the sides where two
parts touch are measured (`contacts`): those are glued face to face when the model is assembled.
"""

from __future__ import annotations

import math
import time
from typing import Callable

import numpy as np

from ..approximate.error import LP_TOL, lp_overlap_depths
from ..approximate.hulls import approximate_hulls, plane_basis
from ..deadline import Deadline
from ..errors import PolyfoldError
from ..mesh.mesh import Mesh
from ..segment.segment import DEFAULT_TAU, segment
from .options import MakeOptions
from .report import ApproximateReport, SegmentReport

# a side within this angle (cosine) and distance (x diagonal) of another part's side lies on it
CONTACT_COS = math.cos(1e-4)
CONTACT_DIST = 1e-7


def joined(meshes: tuple[Mesh, ...] | list[Mesh]) -> Mesh:
    """The meshes as one Mesh (vertices and faces one after another; face_source continued so that
    facet ids stay apart between meshes)."""
    offsets = np.cumsum([0] + [m.n_vertices for m in meshes])
    src_offsets = np.cumsum([0] + [int(m.face_source.max()) + 1 for m in meshes])
    return Mesh(np.concatenate([m.vertices for m in meshes]),
                np.concatenate([m.faces + o for m, o in zip(meshes, offsets)]),
                np.concatenate([m.face_source + o for m, o in zip(meshes, src_offsets)]))


def glued_sides(meshes: tuple[Mesh, ...] | list[Mesh], diag: float) -> list[tuple[int, int, int, int, float]]:
    """(i, side of i, j, side of j, area) for every two flat sides (faces of one face_source) of
    meshes i < j on one plane, facing each other, that overlap with positive area (model units
    squared): where part i is glued onto part j. Candidates by their planes (numpy), areas by
    shapely."""
    from shapely import Polygon, unary_union

    owner, source, normal, offset, tris = [], [], [], [], []
    for k, m in enumerate(meshes):
        src, first = np.unique(m.face_source, return_index=True)
        n = m.face_normals[first]
        owner.append(np.full(len(src), k))
        source.append(src)
        normal.append(n)
        offset.append(np.einsum("ij,ij->i", n, m.vertices[m.faces[first, 0]]))
        tris += [m.vertices[m.faces[m.face_source == s]] for s in src]
    owner, source = np.concatenate(owner), np.concatenate(source)
    normal, offset = np.concatenate(normal), np.concatenate(offset)
    facing = (normal @ normal.T < -CONTACT_COS) & (np.abs(offset[:, None] + offset[None, :]) <= CONTACT_DIST * diag)
    out = []
    for a, b in np.argwhere(facing & (owner[:, None] < owner[None, :])):
        basis = plane_basis(normal[a])
        flat = [unary_union([Polygon(t @ basis.T) for t in tris[x]]) for x in (a, b)]
        area = float(flat[0].intersection(flat[1]).area)
        if area > 0.0:
            out.append((int(owner[a]), int(source[a]), int(owner[b]), int(source[b]), area))
    return out


def contact_areas(meshes: tuple[Mesh, ...] | list[Mesh], diag: float, sides: list | None = None
                  ) -> list[tuple[int, int, float]]:
    """(i, j, area) for every pair of meshes glued together (`glued_sides`, or the given ones,
    summed per pair)."""
    found: dict[tuple[int, int], float] = {}
    for i, _, j, _, area in glued_sides(meshes, diag) if sides is None else sides:
        found[(i, j)] = found.get((i, j), 0.0) + area
    return [(i, j, a) for (i, j), a in sorted(found.items())]


def glued_faces(meshes: tuple[Mesh, ...] | list[Mesh], sides: list) -> np.ndarray:
    """(F,) for every face of `joined(meshes)`: a face of the side it is glued onto (sides: of
    `glued_sides`), -1 for none (the sheets print "glue to X" there, `pieces.with_side_notes`)."""
    start = np.cumsum([0] + [m.n_faces for m in meshes])
    out = np.full(int(start[-1]), -1, dtype=np.int64)
    for i, si, j, sj, _ in sides:
        fi = start[i] + np.flatnonzero(meshes[i].face_source == si)
        fj = start[j] + np.flatnonzero(meshes[j].face_source == sj)
        out[fi], out[fj] = fj[0], fi[0]
    return out


def contacts_of_parts(report: ApproximateReport, part_faces: list[np.ndarray]) -> tuple[tuple[int, int], ...]:
    """The report's contacts as pairs of make's parts (part_faces: each part's faces in the joined
    mesh; a polyhedron whose net needed cutting into several parts is named by its first)."""
    owner = np.repeat(np.arange(report.parts), report.faces_after)
    part_of = {}
    for k, faces in enumerate(part_faces):
        part_of.setdefault(int(owner[faces[0]]), k)
    return tuple((part_of[i], part_of[j]) for i, j, _ in report.contacts if i in part_of and j in part_of)


def approximate_mesh(mesh: Mesh, opts: MakeOptions, deadline: Deadline, say: Callable[[str, str], None]
                     ) -> tuple[Mesh, SegmentReport, ApproximateReport, np.ndarray]:
    """(the approximated model, the segmentation's report, the approximation's, `glued_faces` of
    the model) of `mesh` under `--approximate hulls` (`--tau` / `--parts` as for make's
    segmentation; default tau)."""
    ts = time.perf_counter()
    mode = "parts" if opts.parts is not None else "tau"
    say("segment", f"segmenting into nearly convex parts ({mode})")
    seg = segment(mesh, tau=DEFAULT_TAU if opts.tau is None else opts.tau, parts=opts.parts, seed=0,
                  deadline=deadline)
    seg_report = SegmentReport(mode=mode, tau=seg.tau, parts=seg.n_parts,
                               concavity=tuple(float(c) for c in seg.concavity),
                               seconds=time.perf_counter() - ts, segmented_components=())
    ta = time.perf_counter()
    say("approximate", f"{seg.n_parts} part(s): convex hulls, cut apart where they overlap")
    approx = approximate_hulls(mesh, seg, seed=opts.seed)
    diag = mesh.bbox_diagonal
    depth = lp_overlap_depths(approx.parts)
    pairs = np.argwhere(np.triu(depth > LP_TOL * diag, 1))  # (the bound the tests hold it to)
    if len(pairs):  # the clipping's own guarantee failed: never build parts that cannot be assembled
        i, j = (int(x) + 1 for x in pairs[0])
        raise PolyfoldError(f"the convex parts {i} and {j} overlap (by {depth[i - 1, j - 1] / diag:.2g} of the "
                            f"diagonal, independent check): try another --tau or --parts")
    overlapping = len(pairs)
    sides = glued_sides(approx.parts, diag)
    contacts = contact_areas(approx.parts, diag, sides)
    report = ApproximateReport(
        mode="hulls", parts=approx.n_parts, faces_before=tuple(int(x) for x in approx.faces_before),
        faces_after=tuple(int(x) for x in approx.faces_after), facets=tuple(int(x) for x in approx.facets),
        hausdorff_out=tuple(round(float(x), 6) for x in approx.hausdorff_out),
        hausdorff_in=tuple(round(float(x), 6) for x in approx.hausdorff_in),
        hausdorff_max=round(float(approx.hausdorff_max), 6),
        volume_ratio=None if math.isnan(approx.volume_ratio) else round(float(approx.volume_ratio), 6),
        clip_planes=len(approx.planes), overlapping_pairs=overlapping,
        contacts=tuple((i, j, round(a, 9)) for i, j, a in contacts), seconds=time.perf_counter() - ta)
    return joined(approx.parts), seg_report, report, glued_faces(approx.parts, sides)
