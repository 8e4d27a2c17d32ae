"""formats/meshes.py: the readers (OBJ with negative indices and slashes, OFF, STL / PLY / GLB
through trimesh), parse errors with line numbers, unreadable and unknown files, and the mesh
writer table (every suffix writes a file the readers load back as the same mesh)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from conftest import assert_valid_component, signed_volume
from polyfold.errors import MeshError, PolyfoldError
from polyfold.formats.meshes import WRITERS, load_mesh, write_mesh
from polyfold.mesh.repair import describe


# ----------------------------------------------------------------------------------------------
# Readers and parsing details (synthetic files)


CUBE_V = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]


CUBE_QUADS = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]


def test_off_quads(tmp_path: Path) -> None:
    lines = ["OFF", "# a cube", f"{len(CUBE_V)} {len(CUBE_QUADS)} 0"]
    lines += [" ".join(map(str, v)) for v in CUBE_V]
    lines += ["4 " + " ".join(map(str, q)) for q in CUBE_QUADS]
    (tmp_path / "cube.off").write_text("\n".join(lines) + "\n")
    loaded = load_mesh(tmp_path / "cube.off")
    assert loaded.mesh.n_faces == 12 and len(loaded.components) == 1
    assert loaded.warnings == ("triangulated 6 polygons with more than 3 corners",)
    assert signed_volume(loaded.mesh) == pytest.approx(1.0)


def test_a_concave_polygon_is_cut_into_triangles_inside_it(tmp_path: Path) -> None:
    # an L-shaped prism: its two hexagonal caps are concave at one corner; fanned from their first
    # corner, some triangles would lie outside the L and fold back over the others
    ring = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]
    lines = [f"v {x} {y} {z}" for z in (0, 1) for x, y in ring]
    lines += ["f " + " ".join(str(k) for k in (6, 5, 4, 3, 2, 1)), "f " + " ".join(str(k) for k in range(7, 13))]
    lines += [f"f {k + 1} {(k + 1) % 6 + 1} {(k + 1) % 6 + 7} {k + 7}" for k in range(6)]
    (tmp_path / "l.obj").write_text("\n".join(lines) + "\n")
    loaded = load_mesh(tmp_path / "l.obj")
    mesh = loaded.mesh
    assert mesh.n_faces == 2 * 4 + 6 * 2 and len(loaded.components) == 1
    assert signed_volume(mesh) == pytest.approx(3.0)  # the L's area (3) times its height (1)
    from shapely.geometry import Polygon

    for cap in (0, 1):  # each cap's triangles tile the L exactly, none outside it
        tris = [t for t, src in zip(mesh.faces, mesh.face_source) if src == cap]
        polys = [Polygon(mesh.vertices[t][:, :2]) for t in tris]
        assert len(polys) == 4 and sum(p.area for p in polys) == pytest.approx(3.0)
        assert all(Polygon(ring).buffer(1e-9).contains(p) for p in polys)


def test_obj_negative_indices_and_slashes(tmp_path: Path) -> None:
    lines = ["o cube", "vt 0 0", "vn 0 0 1"]
    lines += ["v " + " ".join(map(str, v)) for v in CUBE_V]
    # relative indices: -8 is vertex 0 once all 8 vertices exist
    lines += ["f " + " ".join(f"{i - 8}/1/1" for i in q) for q in CUBE_QUADS]
    (tmp_path / "rel.obj").write_text("\n".join(lines) + "\n")
    loaded = load_mesh(tmp_path / "rel.obj")
    assert loaded.mesh.n_faces == 12 and describe(loaded)["closed"]
    assert signed_volume(loaded.mesh) == pytest.approx(1.0)


def test_obj_parse_errors_have_line_numbers(tmp_path: Path) -> None:
    (tmp_path / "zero.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n")
    with pytest.raises(MeshError, match=r"^zero\.obj: line 4: face 0 uses vertex index 0"):
        load_mesh(tmp_path / "zero.obj")
    (tmp_path / "word.obj").write_text("v 0 0 0\nv 1 zero 0\n")
    with pytest.raises(MeshError, match=r"^word\.obj: line 2: vertex 1"):
        load_mesh(tmp_path / "word.obj")


def test_unreadable_and_unknown(tmp_path: Path) -> None:
    with pytest.raises(MeshError, match=r"^missing\.obj: cannot read"):
        load_mesh(tmp_path / "missing.obj")
    (tmp_path / "mesh.xyz").write_text("1 2 3\n")
    with pytest.raises(MeshError, match=r"^mesh\.xyz: unknown format"):
        load_mesh(tmp_path / "mesh.xyz")
    (tmp_path / "junk.stl").write_bytes(b"\x00\x01junk")
    with pytest.raises(MeshError, match=r"^junk\.stl: "):
        load_mesh(tmp_path / "junk.stl")


def test_trimesh_formats(tmp_path: Path) -> None:
    import trimesh

    trimesh.creation.icosahedron().export(tmp_path / "ico.stl")
    trimesh.creation.icosahedron().export(tmp_path / "ico.ply")
    a, b = trimesh.creation.box(), trimesh.creation.box()
    b.apply_translation([3, 0, 0])
    trimesh.Scene([a, b]).export(tmp_path / "boxes.glb")
    stl = load_mesh(tmp_path / "ico.stl")  # STL is a triangle soup: welded
    assert (stl.mesh.n_faces, stl.mesh.n_vertices, len(stl.components)) == (20, 12, 1)
    assert stl.warnings[0].startswith("welded")
    ply = load_mesh(tmp_path / "ico.ply")
    assert ply.warnings == () and describe(ply)["closed"]
    glb = load_mesh(tmp_path / "boxes.glb")  # a scene: concatenated, one component per box
    assert len(glb.components) == 2 and glb.mesh.n_faces == 24
    for comp in glb.components:
        assert_valid_component(comp)


def test_stl_reads_as_trimesh_reads_it(models_dir: Path, tmp_path: Path) -> None:
    """polyfold reads STL itself (importing trimesh costs a command about a second): the same
    vertices and triangles as trimesh's loader, binary (also with a header that begins "solid", as
    some CAD tools write) and ASCII, on shared models; an ASCII file of two solids gives both."""
    import trimesh

    from polyfold.formats.meshes import _parse_stl

    checked = 0
    for name in ("bunny-128", "horse-302", "fish-472", "periscope-28", "cube-12", "torus-12x6-144"):
        tm = trimesh.load(models_dir / f"{name}.obj", force="mesh", process=False)
        binary = trimesh.exchange.stl.export_stl(tm)
        for kind, data in (("binary", binary), ("solid-header", b"solid exported by CAD" + binary[21:]),
                           ("ascii", trimesh.exchange.stl.export_stl_ascii(tm).encode())):
            path = tmp_path / f"{name}-{kind}.stl"
            path.write_bytes(data)
            ref = trimesh.load(path, force="mesh", process=False)
            raw = _parse_stl(data, path.name, str(path))
            assert np.array_equal(raw.vertices, np.asarray(ref.vertices, dtype=np.float64)), (name, kind)
            assert np.array_equal(raw.tris, ref.faces) and np.array_equal(raw.source, np.arange(len(ref.faces)))
            checked += 1
    assert checked == 18
    box, ico = trimesh.creation.box(), trimesh.creation.icosahedron()
    two = trimesh.exchange.stl.export_stl_ascii(box) + "\n" + trimesh.exchange.stl.export_stl_ascii(ico)
    (tmp_path / "two.stl").write_text(two)
    loaded = load_mesh(tmp_path / "two.stl")
    assert loaded.mesh.n_faces == 32 and len(loaded.components) == 2
    for bad, why in ((b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 zero\nendloop\nendfacet\nendsolid\n", "not a number"),
                     (b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid\n",
                      "without 3 vertices")):
        (tmp_path / "bad.stl").write_bytes(bad)
        with pytest.raises(MeshError, match=f"^bad\\.stl: .*{why}"):
            load_mesh(tmp_path / "bad.stl")


# ----------------------------------------------------------------------------------------------
# Writers


@pytest.mark.parametrize("suffix", sorted(WRITERS))
def test_written_mesh_loads_back(models_dir, tmp_path, suffix):
    mesh = load_mesh(models_dir / "bunny-128.obj").mesh
    colors = np.tile(np.array([[200, 30, 30]], np.uint8), (mesh.n_faces, 1))
    path = tmp_path / f"bunny{suffix}"
    write_mesh(path, mesh.vertices, mesh.faces, face_colors=colors, header="a bunny")
    back = load_mesh(path).mesh
    assert back.n_faces == mesh.n_faces
    # same surface: the same triangles as point triples (GLB stores its own vertex order)
    key = lambda m: np.sort(np.round(m.vertices[m.faces], 5).reshape(len(m.faces), -1), axis=0)  # noqa: E731
    assert np.allclose(np.sort(key(back), axis=0), np.sort(key(mesh), axis=0), atol=1e-5)


def test_binary_stl_with_its_count_off_is_read_and_said(models_dir: Path, tmp_path: Path) -> None:
    """A binary STL whose count is 0 (a writer that could not go back to fill it in) or that has
    bytes after its triangles loads (trimesh refuses both) with a warning saying what was read."""
    mesh = load_mesh(models_dir / "bunny-128.obj").mesh
    write_mesh(tmp_path / "ok.stl", mesh.vertices, mesh.faces)
    data = (tmp_path / "ok.stl").read_bytes()
    ok = load_mesh(tmp_path / "ok.stl")
    assert not any("header" in w or "ignored" in w for w in ok.warnings)
    for name, bad, said in (("zero.stl", data[:80] + bytes(4) + data[84:], "the header says 0 triangles: read the 128"),
                            ("tail.stl", data + b"\x00" * 37, "ignored 37 bytes after the 128 triangles"),
                            ("tail2.stl", data + b"x" * 120, "ignored 120 bytes after the 128 triangles")):
        (tmp_path / name).write_bytes(bad)
        loaded = load_mesh(tmp_path / name)
        assert np.array_equal(loaded.mesh.vertices, ok.mesh.vertices) and np.array_equal(loaded.mesh.faces, ok.mesh.faces)
        assert any(w.startswith(said) for w in loaded.warnings), (name, loaded.warnings)


@pytest.mark.parametrize("suffix", [".ply", ".glb", ".off", ".stl"])
def test_written_mesh_reads_in_trimesh(models_dir, tmp_path, suffix):
    """polyfold's own writers (not trimesh's: its import costs a command about a second), read back
    by trimesh: the same triangles (float32 where the format stores it, exact in OFF), the face
    colours where the format holds them (PLY faces; GLB corners, a face's own), the STL's unit
    normals, header lines as comments."""
    import trimesh

    mesh = load_mesh(models_dir / "bunny-128.obj").mesh
    colors = np.random.default_rng(4).integers(0, 256, (mesh.n_faces, 3)).astype(np.uint8)
    for face_colors in (colors, None):
        path = tmp_path / f"bunny{suffix}"
        write_mesh(path, mesh.vertices, mesh.faces, face_colors=face_colors, header=["a bunny", "two\nlines"])
        tm = trimesh.load(path, force="mesh", process=False)
        corners = np.asarray(tm.vertices)[np.asarray(tm.faces)]
        if suffix == ".off":
            assert np.array_equal(corners, mesh.vertices[mesh.faces]) and b"# two lines" in path.read_bytes()
        else:
            assert np.array_equal(corners, mesh.vertices[mesh.faces].astype(np.float32))
        if suffix == ".stl":
            stored = np.frombuffer(path.read_bytes(), dtype=[("n", "<f4", (3,)), ("c", "<f4", (9,)), ("a", "<u2")],
                                   offset=84)["n"]
            assert np.allclose(stored, trimesh.Trimesh(mesh.vertices, mesh.faces, process=False).face_normals, atol=1e-6)
        if suffix == ".ply":
            assert b"comment a bunny" in path.read_bytes()[:400]
        if face_colors is not None and suffix in (".ply", ".glb"):
            shown = tm.visual.face_colors if suffix == ".ply" else tm.visual.vertex_colors[np.asarray(tm.faces)[:, 0]]
            assert np.array_equal(np.asarray(shown)[:, :3], colors) and (np.asarray(shown)[:, 3] == 255).all()


VALIDATE_GLB = """
const validator = require('gltf-validator'); const fs = require('fs');
(async () => {
  const out = {};
  for (const f of process.argv.slice(2)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(f)));
    out[f] = [report.issues.numErrors, report.issues.numWarnings, report.issues.messages.slice(0, 3)];
  }
  console.log(JSON.stringify(out));
})();
"""


def test_written_glb_passes_khronos_validator(models_dir, tmp_path):
    """The GLB files polyfold writes (face colours or none) have no error and no warning in the
    Khronos glTF validator (npm gltf-validator, installed into tests/.node by .ci/run)."""
    import json
    import shutil
    import subprocess

    node, modules = shutil.which("node"), Path(__file__).resolve().parents[1] / ".node" / "node_modules"
    if node is None or not (modules / "gltf-validator" / "package.json").is_file():
        pytest.skip("node or npm gltf-validator missing (.ci/run installs it into tests/.node)")
    mesh = load_mesh(models_dir / "bunny-128.obj").mesh
    colors = np.random.default_rng(5).integers(0, 256, (mesh.n_faces, 3)).astype(np.uint8)
    write_mesh(tmp_path / "colored.glb", mesh.vertices, mesh.faces, face_colors=colors, header="a bunny")
    write_mesh(tmp_path / "plain.glb", mesh.vertices, mesh.faces)
    (tmp_path / "validate.js").write_text(VALIDATE_GLB)
    proc = subprocess.run([node, "validate.js", "colored.glb", "plain.glb"], cwd=tmp_path, capture_output=True,
                          text=True, timeout=120, env={"NODE_PATH": str(modules), "PATH": ""})
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout) == {"colored.glb": [0, 0, []], "plain.glb": [0, 0, []]}


def test_unknown_suffix_is_one_clear_error(tmp_path):
    with pytest.raises(PolyfoldError, match="cannot write '.xyz' meshes"):
        write_mesh(tmp_path / "m.xyz", np.zeros((3, 3)), np.array([[0, 1, 2]]))
    assert not list(tmp_path.iterdir())
