"""The files of a segmentation (`polyfold segment`): one OBJ per part, the labels, the whole mesh
coloured by part (PLY, GLB) and a picture."""

from __future__ import annotations

import numpy as np

from ..mesh.mesh import Mesh
from ..segment.segment import Segmentation
from .files import StagedFolder, check_folder
from .meshes import mesh_bytes, obj_text
from .png import png_bytes


def input_face_labels(seg: Segmentation, face_source: np.ndarray, n_input_faces: int) -> np.ndarray:
    """Part of every face of the input FILE (length n_input_faces, file order; -1 for faces the
    loader dropped as degenerate or duplicate). face_source: the segmented mesh's face_source."""
    out = np.full(max(int(n_input_faces), int(face_source.max()) + 1 if len(face_source) else 0), -1, dtype=np.int64)
    out[face_source] = seg.labels  # triangles of one polygon share a part (see _Merger.polygon)
    return out


OUTPUTS = ("part-*.obj", "labels.json", "segments.ply", "segments.glb", "segments.png")  # every name it may write


def check_segmentation_folder(out_dir, inputs: tuple) -> None:
    """Before segmenting: `files.check_folder` for the names `write_segmentation` may write."""
    check_folder(out_dir, OUTPUTS, inputs)


def write_segmentation(seg: Segmentation, mesh: Mesh, out_dir, *, n_input_faces: int | None = None,
                       source_name: str = "mesh", png: bool = True, inputs: tuple = ()) -> list[str]:
    """Write the parts into `out_dir` and return the file names written.

    part-K.obj (one per part, faces in the part's order), labels.json ({"labels": part of each
    input face, "tau", "concavity": per part, plus "faces" per part}), segments.ply (the whole
    mesh, one colour per part, as face colours), segments.glb (same colours as vertex colours on
    unshared vertices, since glTF has no face colours) and, unless png=False, segments.png.
    Everything is staged (`files.StagedFolder`) and moved in together, so an error never leaves
    half the files; the files of an earlier run that this one does not write are removed, no
    other file is touched and none of `inputs` (the files read) is replaced."""
    import json

    from .raster import part_colors, render_mesh

    colors = part_colors(seg.n_parts)[seg.labels]
    with StagedFolder(out_dir, "segment", inputs=inputs) as stage:
        for k, part in enumerate(seg.parts):
            stage.write(f"part-{k}.obj", obj_text(part.vertices, part.faces, [
                f"part {k} of {seg.n_parts} of {source_name}, segmented by polyfold (tau {seg.tau:.6g})",
                f"{part.n_faces} faces, concavity {seg.concavity[k]:.6g} of the whole mesh's bbox diagonal"]))
        n_in = mesh.n_faces if n_input_faces is None else n_input_faces
        labels = input_face_labels(seg, mesh.face_source, n_in)
        doc = {"labels": labels.tolist(), "tau": float(seg.tau), "concavity": [float(c) for c in seg.concavity],
               "faces": [int(p.n_faces) for p in seg.parts], "source": source_name}
        stage.write("labels.json", json.dumps(doc) + "\n")
        for name in ("segments.ply", "segments.glb"):
            stage.write(name, mesh_bytes(name[-4:], mesh.vertices, mesh.faces, face_colors=colors))
        if png:
            stage.write("segments.png", png_bytes(render_mesh(mesh.vertices, mesh.faces, colors)))
        return list(stage.commit())
