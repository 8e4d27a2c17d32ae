"""pipeline/folder.py: a make folder loaded back (parts welded into the input mesh, pieces
verified), the folding poses along each piece's path, path_degrees, and make_folder from a mesh."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from polyfold.pipeline.folder import load_folder, make_folder, path_degrees, pose_piece
from polyfold.pipeline.options import MakeOptions


def _edge_lengths(corners: np.ndarray) -> np.ndarray:
    return np.linalg.norm(corners - np.roll(corners, -1, axis=1), axis=2)


def test_load_folder(make_dir: Path, models_dir: Path) -> None:
    from polyfold.formats.meshes import load_mesh

    folder = load_folder(make_dir)
    assembly = json.loads((make_dir / "assembly.json").read_text())
    assert len(folder.parts) == len(assembly["parts"]) >= 2
    assert [p.name for p in folder.pieces] == [r["piece"] for r in assembly["pieces"]]
    assert all(p.verified for p in folder.pieces)
    original = load_mesh(models_dir / "bunny-128.obj").mesh
    # the parts welded back are the input mesh again (same faces, same saddles)
    assert folder.whole.n_faces == original.n_faces and folder.whole.n_vertices == original.n_vertices
    assert int(folder.whole.hyperbolic.sum()) == int(original.hyperbolic.sum())
    assert folder.options.parts == 3


def test_pose_follows_the_path(make_dir: Path) -> None:
    folder = load_folder(make_dir)
    size = float(np.ptp(folder.whole.vertices, axis=0).max())
    moved = 0
    for piece in folder.pieces:
        fold = piece.fold
        # make's pieces are in mm; poses are in the model's units (those of the part OBJs)
        assert fold["frame_unit"] == "mm" and piece.unit == 1 / fold["polyfold:mmPerModelUnit"]
        folded = np.asarray(fold["file_frames"][0]["vertices_coords"])[np.asarray(fold["faces_vertices"])] * piece.unit
        goal = piece.pose(1.0)
        # t = 1 lands exactly on the model (the foldedForm), in the model's own frame
        assert np.abs(goal - folded).max() < 1e-9 * size, piece.name
        assert piece.fit_error < 1e-9 * size
        flat = piece.pose(0.0)
        # t = 0 is the flat net: every corner in one plane, the same triangles as the crease pattern
        centred = flat.reshape(-1, 3) - flat.reshape(-1, 3).mean(axis=0)
        assert np.linalg.svd(centred, compute_uv=False)[2] < 1e-9 * size
        xy = np.asarray(fold["vertices_coords"])[np.asarray(fold["faces_vertices"])] * piece.unit
        np.testing.assert_allclose(piece.flat_xy[np.asarray(fold["faces_vertices"])], xy)
        flat_xy = np.concatenate([xy, np.zeros(xy.shape[:2] + (1,))], axis=2)
        np.testing.assert_allclose(_edge_lengths(flat), _edge_lengths(flat_xy), atol=1e-9 * size)
        # in between: rigid faces (paper does not stretch)
        np.testing.assert_allclose(_edge_lengths(piece.pose(0.37)), _edge_lengths(folded), atol=1e-9 * size)
        moved += np.abs(flat - goal).max() > 1e-3 * size
        # the function form gives the same poses
        np.testing.assert_allclose(pose_piece(fold, 0.37), piece.pose(0.37), atol=1e-12 * size)
    assert moved >= 1


def test_path_degrees() -> None:
    frames = np.array([[0.0, 0.0], [10.0, -20.0], [30.0, -20.0]])
    np.testing.assert_allclose(path_degrees(frames, 0.0), [0, 0])
    np.testing.assert_allclose(path_degrees(frames, 0.25), [5, -10])
    np.testing.assert_allclose(path_degrees(frames, 0.75), [20, -20])
    np.testing.assert_allclose(path_degrees(frames, 1.0), [30, -20])
    np.testing.assert_allclose(path_degrees(frames, 7.0), [30, -20])  # clamped


def test_make_folder_from_mesh(models_dir: Path, tmp_path: Path) -> None:
    """The MESH form of `polyfold view`: make into a folder (with progress), then load it."""
    stages = []
    folder = make_folder(models_dir / "octahedron-8.obj", tmp_path / "out", MakeOptions(time_limit=20),
                         lambda stage, msg: stages.append(stage))
    assert {"load", "unfold", "export"} <= set(stages)
    assert folder.whole.n_faces == 8 and len(folder.pieces) >= 1
    assert all(p.verified for p in folder.pieces)
