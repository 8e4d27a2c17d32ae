"""The files of a segmentation (`polyfold segment`): one OBJ per part, the labels, the whole mesh
coloured by part (PLY, GLB) and a picture."""

from __future__ import annotations

import numpy as np

from ..mesh.mesh import Mesh
from ..segment.segment import Segmentation
from .meshes import obj_text


def input_face_labels(seg: Segmentation, face_source: np.ndarray, n_input_faces: int) -> np.ndarray:
    """Part of every face of the input FILE (length n_input_faces, file order; -1 for faces the
    loader dropped as degenerate or duplicate). face_source: the segmented mesh's face_source."""
    out = np.full(max(int(n_input_faces), int(face_source.max()) + 1 if len(face_source) else 0), -1, dtype=np.int64)
    out[face_source] = seg.labels  # triangles of one polygon share a part (see _Merger.polygon)
    return out


def write_segmentation(seg: Segmentation, mesh: Mesh, out_dir, *, n_input_faces: int | None = None,
                       source_name: str = "mesh", png: bool = True) -> list[str]:
    """Write the parts into `out_dir` and return the file names written.

    part-K.obj (one per part, faces in the part's order), labels.json ({"labels": part of each
    input face, "tau", "concavity": per part, plus "faces" per part}), segments.ply (the whole
    mesh, one colour per part, as face colours), segments.glb (same colours as vertex colours on
    unshared vertices, since glTF has no face colours) and, unless png=False, segments.png.
    Everything is written to a temporary folder beside out_dir first and then moved in, so an
    error never leaves half the files; stale part-K.obj files of an earlier run are removed."""
    import json
    import os
    import shutil
    import tempfile
    from pathlib import Path

    import trimesh

    from .png import write_mesh_png
    from .raster import part_colors

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".polyfold-segment-", dir=out))
    try:
        names = []
        for k, part in enumerate(seg.parts):
            name = f"part-{k}.obj"
            (tmp / name).write_text(obj_text(part.vertices, part.faces, [
                f"part {k} of {seg.n_parts} of {source_name}, segmented by polyfold (tau {seg.tau:.6g})",
                f"{part.n_faces} faces, concavity {seg.concavity[k]:.6g} of the whole mesh's bbox diagonal"]))
            names.append(name)
        n_in = mesh.n_faces if n_input_faces is None else n_input_faces
        labels = input_face_labels(seg, mesh.face_source, n_in)
        doc = {"labels": labels.tolist(), "tau": float(seg.tau), "concavity": [float(c) for c in seg.concavity],
               "faces": [int(p.n_faces) for p in seg.parts], "source": source_name}
        (tmp / "labels.json").write_text(json.dumps(doc) + "\n")
        names.append("labels.json")
        colors = part_colors(seg.n_parts)[seg.labels]
        rgba = np.concatenate([colors, np.full((len(colors), 1), 255, np.uint8)], axis=1)
        tm = trimesh.Trimesh(mesh.vertices, mesh.faces, face_colors=rgba, process=False)
        (tmp / "segments.ply").write_bytes(tm.export(file_type="ply"))
        flat = trimesh.Trimesh(mesh.vertices[mesh.faces].reshape(-1, 3), np.arange(3 * mesh.n_faces).reshape(-1, 3),
                               vertex_colors=np.repeat(rgba, 3, axis=0), process=False)
        (tmp / "segments.glb").write_bytes(flat.export(file_type="glb"))
        names += ["segments.ply", "segments.glb"]
        if png:
            write_mesh_png(tmp / "segments.png", mesh.vertices, mesh.faces, colors)
            names.append("segments.png")
        for old in out.glob("part-*.obj"):
            if old.name not in names:
                old.unlink()
        for name in names:
            os.replace(tmp / name, out / name)
        return names
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
