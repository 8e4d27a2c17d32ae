"""Mesh files: readers of OBJ, OFF, STL, PLY, GLB and GLTF, the OBJ writer, and `load_mesh`
(read, then `mesh.repair.repair`).

Every message names indices in the INPUT file's numbering, 0-based (faces in file order, before
triangulation), so a user can find the culprit in their file.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable

import numpy as np

from ..errors import PolyfoldError
from ..mesh.appearance import Appearance
from ..mesh.geometry import face_normals
from ..mesh.mesh import Mesh
from ..mesh.repair import LoadedMesh, RawMesh, check_input, mesh_error, repair
from .files import atomic_write
from .materials import Looks, obj_appearance, trimesh_appearance


MAX_INDEX = 2**40  # a vertex index beyond this is a broken file, not a mesh (numpy's int64 holds it)


def _triangulate(polygons: list[list[int]], vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Triangulate polygons; returns (tris, source polygon per tri, the polygon corner (0..k-1) of
    every triangle corner, number of polygons > 3). A convex polygon is fanned from its first
    corner; a concave one (seen in the plane of its Newell normal) is cut into triangles inside it
    (`_concave`), never into triangles that fold back over each other as a fan would."""
    corners: list[tuple[int, int, int]] = []
    source: list[int] = []
    n_big = 0
    for i, p in enumerate(polygons):
        if len(p) < 3:
            # Keep it as a face with a repeated index so it is dropped (and counted) as degenerate.
            polygons[i] = p = p + [p[-1]] * (3 - len(p))
        elif len(p) > 3:
            n_big += 1
            inside = _concave(p, vertices)
            if inside is not None:
                corners += inside
                source += [i] * len(inside)
                continue
        for j in range(1, len(p) - 1):
            corners.append((0, j, j + 1))
            source.append(i)
    corner = np.array(corners, dtype=np.int64).reshape(-1, 3)
    src = np.array(source, dtype=np.int64)
    tris = np.array([[polygons[s][k] for k in c] for s, c in zip(source, corners)], dtype=np.int64).reshape(-1, 3)
    return tris, src, corner, n_big


def _concave(poly: list[int], vertices: np.ndarray) -> list[tuple[int, int, int]] | None:
    """The triangles (as corner positions in poly) of a concave, simple polygon (vertex ids in
    poly), inside it and turning as it
    does: shapely's constrained Delaunay triangulation in the polygon's plane. None when the
    polygon is convex, degenerate or not simple (then it is fanned), or an index is out of range
    (reported later with its face)."""
    if max(poly) >= len(vertices) or min(poly) < 0 or len(set(poly)) != len(poly):
        return None
    pts = vertices[poly]
    if not np.isfinite(pts).all():
        return None
    nxt = np.roll(pts, -1, axis=0)
    normal = np.array([((pts[:, 1] - nxt[:, 1]) * (pts[:, 2] + nxt[:, 2])).sum(),
                       ((pts[:, 2] - nxt[:, 2]) * (pts[:, 0] + nxt[:, 0])).sum(),
                       ((pts[:, 0] - nxt[:, 0]) * (pts[:, 1] + nxt[:, 1])).sum()])  # Newell: area-weighted
    length = float(np.linalg.norm(normal))
    if length == 0.0:
        return None
    n = normal / length
    u = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    xy = np.stack([pts @ u, pts @ np.cross(n, u)], axis=1)  # counter-clockwise seen along n
    e1, e2 = np.roll(xy, -1, axis=0) - xy, np.roll(xy, -2, axis=0) - np.roll(xy, -1, axis=0)
    turn = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    if (turn >= -1e-12 * float(np.abs(turn).max(initial=0.0))).all():
        return None  # convex: the fan is inside it
    import shapely

    outline = shapely.Polygon(xy)
    if not outline.is_valid:
        return None
    parts = shapely.get_parts(shapely.constrained_delaunay_triangles(outline))
    if len(parts) != len(poly) - 2:
        return None
    out = []
    for tri in parts:
        corners = shapely.get_coordinates(tri)[:3]
        ids = [int(np.argmin(((xy - c) ** 2).sum(axis=1))) for c in corners]
        a, b, c = (xy[k] for k in ids)
        if (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) < 0:
            ids[1], ids[2] = ids[2], ids[1]  # turn as the polygon turns
        out.append(tuple(ids))
    return out


def _logical_lines(text: str):
    """(line number, tokens) of the non-empty lines, comments stripped, '\\' continuations joined."""
    if "\\" not in text:  # (no continuations: the common case, a third faster on big files)
        for lineno, line in enumerate(text.splitlines(), 1):
            tokens = (line.split("#", 1)[0] if "#" in line else line).split()
            if tokens:
                yield lineno, tokens
        return
    pending: list[str] = []
    start = 0
    for lineno, line in enumerate(text.splitlines(), 1):
        line = line.split("#", 1)[0]
        if not pending:
            start = lineno
        if line.rstrip().endswith("\\"):
            pending.append(line.rstrip()[:-1])
            continue
        tokens = " ".join(pending + [line]).split()
        pending = []
        if tokens:
            yield start, tokens
    if pending:
        tokens = " ".join(pending).split()
        if tokens:
            yield start, tokens


def _parse_obj(text: str, name: str, path: str = "") -> RawMesh:
    verts: list[list[float]] = []
    vlines: list[int] = []
    colors: list[list[float] | None] = []  # "v x y z r g b" (MeshLab, scanners): 0..1
    uvs: list[list[float]] = []
    polys: list[list[int]] = []
    poly_vt: list[list[int]] = []
    poly_mtl: list[str | None] = []
    flines: list[int] = []
    mtllibs: list[str] = []
    material: str | None = None
    looks = Looks()
    for lineno, tokens in _logical_lines(text):
        tag = tokens[0]
        if tag == "v":
            if len(tokens) < 4:
                raise mesh_error(name, f"line {lineno}: vertex {len(verts)} needs 3 coordinates")
            try:
                verts.append([float(t) for t in tokens[1:4]])
            except ValueError:
                raise mesh_error(name, f"line {lineno}: vertex {len(verts)} has a coordinate that is not a number") from None
            vlines.append(lineno)
            rgb = None
            if len(tokens) >= 7:
                try:
                    rgb = [float(t) for t in tokens[4:7]]
                except ValueError:
                    looks.warn(f"{name}: line {lineno}: a vertex colour that is not 3 numbers: ignored")
            colors.append(rgb)
        elif tag == "vt":
            try:
                uvs.append([float(t) for t in tokens[1:3]] + [0.0] * (3 - len(tokens)))
            except ValueError:
                looks.warn(f"{name}: line {lineno}: texture coordinate {len(uvs)} is not a number")
                uvs.append([math.nan, math.nan])
        elif tag in ("f", "fo"):
            face = len(polys)
            if len(tokens) < 2:
                raise mesh_error(name, f"line {lineno}: face {face} has no vertices")
            idx, vts = [], []
            for tok in tokens[1:]:
                refs = tok.split("/") if "/" in tok else (tok,)
                try:
                    k = int(refs[0])
                except ValueError:
                    raise mesh_error(name, f"line {lineno}: face {face} has a bad vertex reference {tok!r}") from None
                if k == 0:
                    raise mesh_error(name, f"line {lineno}: face {face} uses vertex index 0 (OBJ indices start at 1)")
                if abs(k) > MAX_INDEX:
                    raise mesh_error(name, f"line {lineno}: face {face} uses vertex index {refs[0]}, "
                                           f"far beyond the file's vertices")
                # Negative indices count back from the last vertex defined so far.
                j = k - 1 if k > 0 else len(verts) + k
                if j < 0:
                    raise mesh_error(name, f"line {lineno}: face {face} uses relative index {k} before that many vertices exist")
                idx.append(j)
                vts.append(_vt_index(refs, len(uvs)) if len(refs) > 1 else -1)
            polys.append(idx)
            poly_vt.append(vts)
            poly_mtl.append(material)
            flines.append(lineno)
        elif tag == "mtllib" and len(tokens) > 1:
            whole = " ".join(tokens[1:])  # one name with spaces, or several names
            here = os.path.dirname(path)
            mtllibs += [whole] if os.path.exists(os.path.join(here, whole)) or len(tokens) == 2 else tokens[1:]
        elif tag == "usemtl":
            material = " ".join(tokens[1:]) or None
        # Other tags (vn, g, o, s, l, p, ...) carry nothing a net needs.
    vertices = np.array(verts, dtype=np.float64).reshape(-1, 3)
    tris, source, corner, n_big = _triangulate(polys, vertices)
    appearance = None
    if path and (mtllibs or any(c is not None for c in colors)):
        vt = np.array([[poly_vt[s][k] for k in c] for s, c in zip(source.tolist(), corner.tolist())],
                      dtype=np.int64).reshape(-1, 3)
        vc = None
        if any(c is not None for c in colors):
            vc = np.array([c if c is not None else [1.0, 1.0, 1.0] for c in colors], dtype=np.float64)
            if np.nanmax(vc) > 1.0:  # some writers use 0..255
                vc = vc / 255.0
        safe = np.where((tris >= 0) & (tris < len(vertices)), tris, 0)
        appearance = obj_appearance(len(tris), safe, vt, [poly_mtl[s] for s in source.tolist()],
                                    np.array(uvs, dtype=np.float64).reshape(-1, 2), vc, mtllibs, path, looks)
    return RawMesh(vertices, tris, source, n_big, flines, vlines, appearance=appearance,
                   warnings=tuple(looks.warnings))


def _vt_index(refs: list[str] | tuple[str, ...], n_uvs: int) -> int:
    """The 0-based texture coordinate of a face corner `v/vt/vn` split at "/" (-1: none or bad;
    negative OBJ indices count back from the last vt so far)."""
    if len(refs) < 2 or not refs[1]:
        return -1
    try:
        k = int(refs[1])
    except ValueError:
        return -1
    j = k - 1 if k > 0 else n_uvs + k
    return j if 0 <= j < MAX_INDEX else -1


def _parse_off(text: str, name: str, path: str = "") -> RawMesh:
    rows = list(_logical_lines(text))
    if not rows:
        raise mesh_error(name, "no faces (empty file)")
    lineno, tokens = rows[0]
    header = tokens[0]
    if not header.upper().endswith("OFF"):
        raise mesh_error(name, f"line {lineno}: expected an OFF header, found {header!r}")
    if header[:-3].startswith("4") or "n" in header[:-3]:
        raise mesh_error(name, f"line {lineno}: OFF variant {header!r} (not 3D) is not supported")
    counts = tokens[1:]
    pos = 1
    if not counts:
        if len(rows) < 2:
            raise mesh_error(name, "no faces (missing vertex and face counts)")
        lineno, counts = rows[1]
        pos = 2
    try:
        nv, nf = int(counts[0]), int(counts[1])
    except (ValueError, IndexError):
        raise mesh_error(name, f"line {lineno}: expected vertex and face counts") from None
    if len(rows) < pos + nv + nf:
        raise mesh_error(name, f"file ends early: header promises {nv} vertices and {nf} faces")
    verts, vlines = [], []
    for i in range(nv):
        lineno, tokens = rows[pos + i]
        try:
            verts.append([float(t) for t in tokens[:3]])
            if len(tokens) < 3:
                raise ValueError
        except ValueError:
            raise mesh_error(name, f"line {lineno}: vertex {i} needs 3 numeric coordinates") from None
        vlines.append(lineno)
    polys, flines = [], []
    for i in range(nf):
        lineno, tokens = rows[pos + nv + i]
        try:
            k = int(tokens[0])
            idx = [int(t) for t in tokens[1 : 1 + k]]
            if k < 1 or len(idx) != k:
                raise ValueError
        except ValueError:
            raise mesh_error(name, f"line {lineno}: face {i} should be a vertex count followed by that many indices") from None
        polys.append(idx)
        flines.append(lineno)
    vertices = np.array(verts, dtype=np.float64).reshape(-1, 3)
    tris, source, _, n_big = _triangulate(polys, vertices)
    return RawMesh(vertices, tris, source, n_big, flines, vlines)


# A binary STL triangle: normal, three corners, two bytes some writers use for a colour (50 bytes)
STL_RECORD = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attributes", "<u2")])
_STL_VERTEX = None  # (the pattern of an ASCII STL's "vertex x y z" line, compiled at the first need)


def _parse_stl(data: bytes, name: str, path: str = "") -> RawMesh:
    """An STL file: binary (an 80-byte header, the triangle count, 50-byte records) when its length
    is exactly what its count says, else ASCII (every "vertex x y z" line, three a facet, all
    solids in file order) -- trimesh's rules, read here because importing trimesh costs a command
    about a second. A binary file whose count is 0 or that has bytes after its triangles, which
    trimesh refuses, is read with a warning; one shorter than its count is a MeshError. A
    triangle soup: every corner a vertex of its own (repair welds them)."""
    global _STL_VERTEX
    binary = False
    warnings: tuple[str, ...] = ()
    if len(data) >= 84:
        promised = int.from_bytes(data[80:84], "little")
        held, rest = divmod(len(data) - 84, STL_RECORD.itemsize)
        binary = held == promised and rest == 0  # (trimesh's rule)
        if not binary and not _ascii_stl(data):
            if held < promised:
                raise mesh_error(name, f"file ends early: the header promises {promised} triangles, the file holds {held}")
            # The count is off: a writer that could not go back to fill it in leaves 0; some
            # append bytes after the triangles.
            if promised == 0 and held > 0 and rest == 0:
                binary, promised = True, held
                warnings = (f"the header says 0 triangles: read the {held} the file holds",)
            elif promised > 0:
                binary = True
                warnings = (f"ignored {len(data) - 84 - promised * STL_RECORD.itemsize} bytes after the {promised} triangles",)
    if binary:
        records = np.frombuffer(data, dtype=STL_RECORD, count=promised, offset=84)
        vertices = records["corners"].reshape(-1, 3).astype(np.float64)
    else:
        if _STL_VERTEX is None:
            import re

            _STL_VERTEX = re.compile(rb"vertex[ \t]+(\S+)[ \t]+(\S+)[ \t]+(\S+)", re.IGNORECASE)
        try:
            vertices = np.array([float(x) for row in _STL_VERTEX.findall(data) for x in row], dtype=np.float64)
        except ValueError:
            raise mesh_error(name, "not a readable STL file (a vertex coordinate that is not a number)") from None
        if len(vertices) % 9:
            raise mesh_error(name, "not a readable STL file (a facet without 3 vertices)")
        vertices = vertices.reshape(-1, 3)
    if len(vertices) == 0:
        raise mesh_error(name, "no faces could be read (not a valid STL file?)")
    n = len(vertices) // 3
    return RawMesh(vertices, np.arange(3 * n, dtype=np.int64).reshape(-1, 3), np.arange(n), 0, warnings=warnings)


def _ascii_stl(data: bytes) -> bool:
    """Whether an STL file reads as ASCII: "solid" first and a facet soon after (a binary file's
    80-byte header may begin with "solid" too)."""
    return data[:5].lower() == b"solid" and b"facet" in data[:1024]


def _ply_counts(data: bytes, name: str) -> None:
    """An ASCII PLY whose data lines are fewer than its header's element counts: MeshError naming
    them (trimesh reads what is there without a word)."""
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0 or b"format ascii" not in data[:end]:
        return
    counts = []
    for line in data[:end].decode("ascii", errors="replace").splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[0] == "element" and parts[2].isdigit():
            counts.append((parts[1], int(parts[2])))
    rows = [ln for ln in data[end:].split(b"\n")[1:] if ln.strip()]
    need = sum(n for _, n in counts)
    if len(rows) < need:
        plural = {"vertex": "vertices"}
        promised = " and ".join(f"{n} {kind if n == 1 else plural.get(kind, kind + 's')}" for kind, n in counts)
        raise mesh_error(name, f"file ends early: the header promises {promised}, the file has {len(rows)} data lines")


def _load_trimesh(path: str, name: str, data: bytes) -> RawMesh:
    import trimesh  # imported lazily: slow to import, and only needed for these formats

    ext = os.path.splitext(path)[1].lower()
    if ext == ".ply":
        _ply_counts(data, name)
    try:
        # process=False keeps vertices and faces exactly in file order; force='mesh' concatenates
        # the geometries of a scene (GLB/GLTF).
        tm = trimesh.load(path, process=False, force="mesh")
    except Exception as exc:  # trimesh raises many kinds of errors on broken files: say what, not how
        why = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise mesh_error(name, f"not a readable {ext[1:].upper()} file ({why})") from None
    if not hasattr(tm, "faces") or tm.faces is None or len(tm.faces) == 0:
        raise mesh_error(name, f"no faces could be read (not a valid {ext[1:].upper()} file?)")
    faces = np.asarray(tm.faces, dtype=np.int64).reshape(-1, 3)
    looks = Looks()
    appearance = trimesh_appearance(tm, len(faces), name, looks)
    return RawMesh(np.asarray(tm.vertices, dtype=np.float64).reshape(-1, 3), faces, np.arange(len(faces)), 0,
                   appearance=appearance, warnings=tuple(looks.warnings))


def _read(path: str, name: str) -> RawMesh:
    ext = os.path.splitext(path)[1].lower()
    if ext not in READERS:
        known = ", ".join(sorted(READERS))
        raise mesh_error(name, f"unknown format {ext or '(no extension)'!r} (expected one of {known})")
    parse = READERS[ext]
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as exc:
        raise mesh_error(name, f"cannot read: {exc.strerror or exc}") from None
    if parse is None:
        return _load_trimesh(path, name, data)
    return parse(data, name, path)


def _text(parse: Callable[[str, str, str], RawMesh], kind: str) -> Callable[[bytes, str, str], RawMesh]:
    """A reader of a file's bytes from a parser of its text: binary data refused, the text decoded."""
    def read(data: bytes, name: str, path: str) -> RawMesh:
        nul = data.find(b"\0")
        if nul >= 0:  # binary data in a text format: no guessing what the rest means
            line = data.count(b"\n", 0, nul) + 1
            raise mesh_error(name, f"line {line}: a NUL byte (binary data in a text {kind} file?)")
        # Comments may hold any encoding; the data we need is ASCII.
        return parse(data.decode("utf-8", errors="replace"), name, path)
    return read


# The readers by file suffix: (bytes, file name, path) -> RawMesh, or None for trimesh's loader.
READERS = {".obj": _text(_parse_obj, "OBJ"), ".off": _text(_parse_off, "OFF"), ".stl": _parse_stl, ".ply": None,
           ".glb": None, ".gltf": None}


def obj_text(vertices: np.ndarray, faces: np.ndarray, header: list[str] | str = ()) -> str:
    """Wavefront OBJ text of a triangle mesh: header comment lines, then v and f (1-based) lines.
    Coordinates are written with repr so reading the file back gives the same floats."""
    header = [header] if isinstance(header, str) else list(header)
    lines = [f"# {h}" for h in header]
    lines += [f"v {x!r} {y!r} {z!r}" for x, y, z in np.asarray(vertices, dtype=np.float64).tolist()]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in np.asarray(faces).tolist()]
    return "\n".join(lines) + "\n"


def _obj(vertices: np.ndarray, faces: np.ndarray, face_colors: np.ndarray | None, header: list[str]) -> bytes:
    return obj_text(vertices, faces, header).encode("utf-8")  # (OBJ has no standard face colours)


# The writers below are polyfold's own: importing trimesh costs a command about a second (1.4-1.8 s
# on a slow machine), and these formats' triangle meshes are a few lines each. Files are checked
# by reading them back with trimesh in the tests.

def _ply(vertices: np.ndarray, faces: np.ndarray, face_colors: np.ndarray | None, header: list[str]) -> bytes:
    """Binary little-endian PLY: float x y z, faces as uchar counts of int indices, RGBA face
    colours when given (as trimesh writes it)."""
    fields = [("n", "u1"), ("v", "<i4", (3,))] + ([("rgba", "u1", (4,))] if face_colors is not None else [])
    rows = np.zeros(len(faces), dtype=np.dtype(fields))
    rows["n"], rows["v"] = 3, faces
    if face_colors is not None:
        rows["rgba"][:, :3], rows["rgba"][:, 3] = face_colors, 255
    head = ["ply", "format binary_little_endian 1.0", *(f"comment {' '.join(h.split())}" for h in header),
            f"element vertex {len(vertices)}", "property float x", "property float y", "property float z",
            f"element face {len(faces)}", "property list uchar int vertex_indices"]
    head += [f"property uchar {c}" for c in ("red", "green", "blue", "alpha")] if face_colors is not None else []
    return ("\n".join(head + ["end_header"]) + "\n").encode("ascii", "replace") + \
        vertices.astype("<f4").tobytes() + rows.tobytes()


def _off(vertices: np.ndarray, faces: np.ndarray, face_colors: np.ndarray | None, header: list[str]) -> bytes:
    """OFF text (no colours: the format's face colours are read by few programs); coordinates in
    repr, so reading the file back gives the same floats."""
    lines = ["OFF", *(f"# {' '.join(h.split())}" for h in header), f"{len(vertices)} {len(faces)} 0"]
    lines += [f"{x!r} {y!r} {z!r}" for x, y, z in vertices.tolist()]
    lines += [f"3 {a} {b} {c}" for a, b, c in np.asarray(faces).tolist()]
    return ("\n".join(lines) + "\n").encode("utf-8")


def _stl(vertices: np.ndarray, faces: np.ndarray, face_colors: np.ndarray | None, header: list[str]) -> bytes:
    """Binary STL: the first header line in the 80-byte header, unit normals (zero for degenerate
    triangles), no colours (STL has no standard for them)."""
    rows = np.zeros(len(faces), dtype=STL_RECORD)
    rows["normal"], rows["corners"] = face_normals(vertices, faces), vertices[np.asarray(faces)]
    title = (header[0] if header else "polyfold").encode("ascii", "replace")[:80].ljust(80, b" ")
    return title + len(rows).to_bytes(4, "little") + rows.tobytes()


def _glb(vertices: np.ndarray, faces: np.ndarray, face_colors: np.ndarray | None, header: list[str]) -> bytes:
    """Binary glTF 2.0 (GLB) of one triangle mesh: float positions, uint32 indices; glTF has no
    face colours, so with them every face gets corners of its own, coloured as the face (RGBA
    bytes, COLOR_0)."""
    import json

    faces = np.asarray(faces)
    if face_colors is not None:
        vertices, faces = vertices[faces].reshape(-1, 3), np.arange(3 * len(faces)).reshape(-1, 3)
    position = vertices.astype("<f4")
    parts = [position.tobytes()]
    accessors = [{"bufferView": 0, "componentType": 5126, "count": len(position), "type": "VEC3",
                  "min": position.min(axis=0).tolist(), "max": position.max(axis=0).tolist()}]
    attributes = {"POSITION": 0}
    if face_colors is not None:
        rgba = np.full((len(face_colors), 4), 255, np.uint8)
        rgba[:, :3] = face_colors
        parts.append(np.repeat(rgba, 3, axis=0).tobytes())
        accessors.append({"bufferView": 1, "componentType": 5121, "normalized": True, "count": len(position),
                          "type": "VEC4"})
        attributes["COLOR_0"] = 1
    parts.append(faces.astype("<u4").tobytes())
    accessors.append({"bufferView": len(parts) - 1, "componentType": 5125, "count": faces.size, "type": "SCALAR"})
    views, offset = [], 0
    for k, part in enumerate(parts):  # (every part's length a multiple of 4: no padding between them)
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(part),
                      "target": 34963 if k == len(parts) - 1 else 34962})
        offset += len(part)
    doc = {"asset": {"version": "2.0", "generator": "polyfold", **({"copyright": header[0]} if header else {})},
           "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
           "meshes": [{"primitives": [{"attributes": attributes, "indices": len(parts) - 1, "mode": 4}]}],
           "accessors": accessors, "bufferViews": views, "buffers": [{"byteLength": offset}]}
    text = json.dumps(doc, separators=(",", ":")).encode("utf-8")
    text += b" " * (-len(text) % 4)
    blob = b"".join(parts)
    total = 12 + 8 + len(text) + 8 + len(blob)
    return (b"glTF" + (2).to_bytes(4, "little") + total.to_bytes(4, "little")
            + len(text).to_bytes(4, "little") + b"JSON" + text + len(blob).to_bytes(4, "little") + b"BIN\0" + blob)


# The writers by file suffix: (vertices, faces, face colours (F, 3) uint8 or None, header lines) -> bytes.
WRITERS = {".obj": _obj, ".ply": _ply, ".glb": _glb, ".off": _off, ".stl": _stl}


def mesh_bytes(suffix: str, vertices: np.ndarray, faces: np.ndarray, *, face_colors: np.ndarray | None = None,
               header: list[str] | str = ()) -> bytes:
    """A triangle mesh as the file a suffix names (.obj, .ply, .glb, .off, .stl); face colours are
    kept where the format has them (PLY faces, GLB vertices)."""
    writer = WRITERS.get(suffix.lower())
    if writer is None:
        raise PolyfoldError(f"cannot write {suffix or 'a file without suffix'!r} meshes: use one of {', '.join(WRITERS)}")
    return writer(np.asarray(vertices, dtype=np.float64), np.asarray(faces), face_colors,
                  [header] if isinstance(header, str) else list(header))


def look_glb(vertices: np.ndarray, faces: np.ndarray, look: Appearance) -> bytes:
    """A GLB of a triangle mesh in its look: every face with corners of its own (UV seams), the
    texture with its UVs when the look has one texture, else the colours per corner (several
    textures: each face's mean colour)."""
    import trimesh
    from PIL import Image

    corners = np.asarray(vertices, dtype=np.float64)[np.asarray(faces)].reshape(-1, 3)
    tris = np.arange(len(corners)).reshape(-1, 3)
    # paper: matte, not metal, seen from both sides; the texture as it is (factor white), where
    # trimesh's default material would show it at 40 %
    paper = dict(baseColorFactor=[255, 255, 255, 255], metallicFactor=0.0, roughnessFactor=1.0, doubleSided=True)
    if len(look.images) == 1 and look.textured.all():
        material = trimesh.visual.material.PBRMaterial(baseColorTexture=Image.fromarray(look.images[0]), **paper)
        visual = trimesh.visual.TextureVisuals(uv=look.uv.reshape(-1, 2), material=material)
        mesh = trimesh.Trimesh(corners, tris, visual=visual, process=False)
    else:
        rgb = look.colors if not look.textured.any() else np.repeat(look.mean_colors[:, None, :], 3, axis=1)
        rgba = np.concatenate([rgb.reshape(-1, 3), np.full((len(corners), 1), 255, np.uint8)], axis=1)
        mesh = trimesh.Trimesh(corners, tris, vertex_colors=rgba, process=False)
    # (colours go without a material: trimesh, reading a GLB back, drops COLOR_0 beside one)
    return mesh.export(file_type="glb")


def write_mesh(path: str | os.PathLike, vertices: np.ndarray, faces: np.ndarray, *,
               face_colors: np.ndarray | None = None, header: list[str] | str = ()) -> None:
    """Write a mesh file, its format by the path's suffix (`mesh_bytes`), atomically."""
    atomic_write(path, mesh_bytes(os.path.splitext(os.fspath(path))[1], vertices, faces, face_colors=face_colors,
                                  header=header))


def read_mesh_as_is(path: str | os.PathLike) -> Mesh:
    """The mesh of a file exactly as written, without repairs (for files polyfold wrote itself,
    e.g. a make folder's part-K.obj); MeshError (one line) when it has no faces, an index out of
    range or a non-finite coordinate."""
    path = os.fspath(path)
    name = os.path.basename(path)
    raw = _read(path, name)
    check_input(raw, name)
    return Mesh(raw.vertices, raw.tris)


def load_mesh(path: str | os.PathLike) -> LoadedMesh:
    """Read, check and repair a mesh file (OBJ, OFF, STL, PLY, GLB, GLTF).

    Raises MeshError (one line, starting with the file name) when the file cannot be used.
    """
    path = os.fspath(path)
    return repair(_read(path, os.path.basename(path)), path)
