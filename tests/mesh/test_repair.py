"""mesh/repair.py: loading the real models through it: bad inputs rejected with one line naming the
culprit or repaired with warnings (orientation, duplicates, degenerate faces, welding, non-manifold
vertices, components), repaired meshes valid with face_source mapping back to the file, closed
models loaded untouched, and describe()."""

from __future__ import annotations

import json
import math
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import assert_valid_component, bad_cases, closed_meshes, models_path, signed_volume
from polyfold.errors import MeshError
from polyfold.formats.meshes import load_mesh
from polyfold.mesh.repair import LoadedMesh, describe


# ----------------------------------------------------------------------------------------------
# Helpers (independent of the code under test)


def _models_table(root: Path) -> dict[str, dict[str, str]]:
    """MODELS.md's table as {file: {column header: cell}}."""
    header: list[str] | None = None
    rows = {}
    for line in (root / "MODELS.md").read_text().splitlines():
        if not line.startswith("|") or line.startswith("|---"):
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if header is None:
            header = cells
        else:
            rows[cells[0]] = dict(zip(header, cells))
    return rows


def _read_obj(path: Path) -> tuple[np.ndarray, list[list[int]]]:
    """Minimal OBJ reader (plain `v` and `f` lines, positive indices) for cross-checks."""
    verts, faces = [], []
    for line in path.read_text().splitlines():
        tok = line.split()
        if tok[:1] == ["v"]:
            verts.append([float(t) for t in tok[1:4]])
        elif tok[:1] == ["f"]:
            faces.append([int(t.split("/")[0]) - 1 for t in tok[1:]])
    return np.array(verts), faces


def _load(models_dir: Path, rel: str) -> LoadedMesh:
    return load_mesh(models_dir / rel)


# ----------------------------------------------------------------------------------------------
# The bad inputs, per expected.json


@pytest.mark.parametrize("name,spec", [pytest.param(n, s, id=n) for n, s in bad_cases()])
def test_bad_file_outcome(models_dir: Path, name: str, spec: dict) -> None:
    path = models_dir / "bad" / name
    start = time.perf_counter()
    try:
        loaded, error = load_mesh(path), None
    except MeshError as exc:
        loaded, error = None, exc
    elapsed = time.perf_counter() - start
    assert elapsed < 5.0, f"{name} took {elapsed:.1f} s"
    expect = spec["expect"]
    if expect == "reject":
        assert error is not None, f"{name} should be rejected"
        text = str(error)
        assert "\n" not in text and text.startswith(name + ": ")
        return
    if expect == "either":
        assert loaded is not None or (error is not None and "\n" not in str(error))
    else:
        assert error is None, f"{name} should load, got: {error}"
    if loaded is None:
        return
    if expect == "repair":
        assert len(loaded.warnings) >= 1
    if "pieces" in spec:
        assert len(loaded.components) == spec["pieces"]
    assert all("\n" not in w for w in loaded.warnings)
    for comp in loaded.components:
        assert_valid_component(comp)


def test_reject_messages_name_the_culprit(models_dir: Path) -> None:
    bad = models_dir / "bad"
    with pytest.raises(MeshError, match=r"^nan-vertex\.obj: vertex 3 has a non-finite coordinate"):
        load_mesh(bad / "nan-vertex.obj")
    with pytest.raises(MeshError, match=r"^index-out-of-range\.obj: face 2 .*vertex 8\b.*4-vertex"):
        load_mesh(bad / "index-out-of-range.obj")
    with pytest.raises(MeshError, match=r"^nonmanifold-edge\.obj: edge between vertices 0 and 1 .* 4 faces \(0, 1, 4, 5\)"):
        load_mesh(bad / "nonmanifold-edge.obj")
    with pytest.raises(MeshError, match=r"^empty\.obj: no faces$"):
        load_mesh(bad / "empty.obj")


def test_repair_warnings(models_dir: Path) -> None:
    def warnings(name: str) -> tuple[str, ...]:
        return load_mesh(models_dir / "bad" / name).warnings

    assert warnings("flipped-face-cube.obj") == ("flipped 1 face to make the orientation consistent (e.g. face 3)",)
    assert len(warnings("inverted-cube.obj")) == 1 and "inverted 1 closed component" in warnings("inverted-cube.obj")[0]
    assert warnings("duplicate-face-cube.obj") == ("dropped 1 duplicate face (e.g. face 12 repeats face 0)",)
    assert warnings("unused-vertex-cube.obj") == ("dropped 1 unused vertex (e.g. vertex 8)",)
    assert "dropped 2 degenerate faces" in warnings("degenerate-faces-cube.obj")[0]
    assert warnings("quad-cube.obj") == ("triangulated 6 polygons with more than 3 corners",)
    assert warnings("soup-cube.obj")[0].startswith("welded 28 vertices")
    assert any("intersect" in w for w in warnings("intersecting-cubes.obj"))
    assert not any("intersect" in w for w in warnings("two-cubes.obj"))
    assert any(w.startswith("2 components") for w in warnings("two-cubes.obj"))
    split = warnings("nonmanifold-vertex.obj")
    assert any(w.startswith("split 1 non-manifold vertex (e.g. vertex 0)") for w in split)


def test_open_surface_touching_itself_splits_silently(models_dir: Path) -> None:
    for rel in ("bad/bunny-128-holes.obj", "paper-parts/horse/part-6.obj"):
        loaded = _load(models_dir, rel)
        assert loaded.warnings == ()
        assert len(loaded.components) == 1
        assert loaded.manifold is False  # a vertex was split, silently
        assert_valid_component(loaded.components[0])
    # The split gives the pinched vertex one copy per fan.
    _, faces = _read_obj(models_dir / "paper-parts/horse/part-6.obj")
    assert _load(models_dir, "paper-parts/horse/part-6.obj").mesh.n_vertices == len({i for f in faces for i in f}) + 1


def test_pinched_cow_is_fast_and_one_piece(models_dir: Path) -> None:
    start = time.perf_counter()
    loaded = _load(models_dir, "bad/cow-5520-pinched.obj")
    assert time.perf_counter() - start < 3.0
    assert loaded.mesh.n_faces == 5520 and len(loaded.components) == 1
    assert_valid_component(loaded.components[0])
    # The two vertices sharing a position stay two vertices: the surface is unchanged.
    assert loaded.mesh.n_vertices == 2762


# ----------------------------------------------------------------------------------------------
# Repaired meshes are valid; face_source maps back to the file


def _loadable(root: Path | None) -> list[str]:
    if root is None:
        return []
    rels = [f"bad/{n}" for n, s in bad_cases() if s["expect"] != "reject"]
    rels += [str(p.relative_to(root)) for p in sorted(root.glob("open/*.obj")) + sorted(root.glob("paper-parts/*/*.obj"))]
    return rels


@pytest.mark.parametrize("rel", _loadable(models_path()))
def test_components_valid_and_sources_map_back(models_dir: Path, rel: str) -> None:
    loaded = _load(models_dir, rel)
    verts, polygons = _read_obj(models_dir / rel)
    assert sum(c.n_faces for c in loaded.components) == loaded.mesh.n_faces
    for comp in loaded.components:
        assert_valid_component(comp)
        # Every face's corners are corners of the file face it claims to come from.
        for tri, src in zip(comp.vertices[comp.faces], comp.face_source):
            allowed = {tuple(verts[i]) for i in polygons[src]}
            assert {tuple(p) for p in tri} <= allowed


def test_face_source_of_repairs(models_dir: Path) -> None:
    quad = _load(models_dir, "bad/quad-cube.obj").mesh
    assert quad.n_faces == 12
    assert sorted(quad.face_source.tolist()) == sorted(list(range(6)) * 2)
    degenerate = _load(models_dir, "bad/degenerate-faces-cube.obj").mesh
    assert sorted(degenerate.face_source.tolist()) == list(range(12))  # faces 12 and 13 dropped
    duplicate = _load(models_dir, "bad/duplicate-face-cube.obj").mesh
    assert sorted(duplicate.face_source.tolist()) == list(range(12))
    bowtie = _load(models_dir, "bad/nonmanifold-vertex.obj").components
    assert [sorted(c.face_source.tolist()) for c in bowtie] == [[0, 1, 2, 3], [4, 5, 6, 7]]


def test_orientation_repairs_restore_the_cube(models_dir: Path) -> None:
    good = _load(models_dir, "cube-12.obj").mesh
    for name in ("flipped-face-cube.obj", "inverted-cube.obj"):
        loaded = _load(models_dir, f"bad/{name}")
        assert loaded.oriented is False
        assert signed_volume(loaded.mesh) == pytest.approx(signed_volume(good))
        # Same outward normals as the well-formed cube, face by face.
        assert sorted(map(tuple, loaded.mesh.face_normals.round(9).tolist())) == sorted(
            map(tuple, good.face_normals.round(9).tolist())
        )


# ----------------------------------------------------------------------------------------------
# Closed benchmark meshes load untouched


@pytest.mark.parametrize("path", closed_meshes(), ids=lambda p: p.name)
def test_closed_models_load_cleanly(models_dir: Path, path: Path) -> None:
    loaded = load_mesh(path)
    assert loaded.warnings == ()
    assert len(loaded.components) == 1
    info = describe(loaded)
    assert info["closed"] and info["manifold"] and info["oriented"]
    row = _models_table(models_dir)[path.name]
    assert info["faces"] == int(row["faces"]) and info["vertices"] == int(row["vertices"])
    assert info["genus"] == int(row["genus"])
    assert signed_volume(loaded.mesh) > 0
    # Loading keeps the file's faces, in file order (orientation was already outward).
    _, polygons = _read_obj(path)
    assert np.array_equal(loaded.mesh.face_source, np.arange(len(polygons)))


# ----------------------------------------------------------------------------------------------
# describe()


def test_describe_reports(models_dir: Path) -> None:
    cube = describe(_load(models_dir, "cube-12.obj"))
    assert cube["genus"] == 0 and cube["closed"] is True and cube["hyperbolic_vertices"] == 0
    assert cube["concavity"] == pytest.approx(0.0, abs=1e-9)
    assert (cube["faces"], cube["vertices"], cube["edges"], cube["components"]) == (12, 8, 18, 1)
    assert cube["bbox_diagonal"] == pytest.approx(math.sqrt(3))  # unit cube
    json.dumps(cube)  # JSON-serializable
    assert describe(_load(models_dir, "torus-8x4-64.obj"))["genus"] == 1
    tube = describe(_load(models_dir, "open/tube-132.obj"))
    assert tube["boundary_loops"] == 2 and tube["closed"] is False and tube["boundary_edges"] == 12
    hemi = describe(_load(models_dir, "open/hemisphere-152.obj"))
    assert hemi["boundary_loops"] == 1 and hemi["closed"] is False and hemi["genus"] == 0
    assert describe(_load(models_dir, "l-prism-20.obj"))["concavity"] > 0.05
    bowtie = describe(_load(models_dir, "bad/nonmanifold-vertex.obj"))
    assert bowtie["manifold"] is False and bowtie["components"] == 2 and len(bowtie["warnings"]) == 2
    assert describe(_load(models_dir, "bad/flipped-face-cube.obj"))["oriented"] is False


def test_describe_hyperbolic_matches_models_md(models_dir: Path) -> None:
    table = _models_table(models_dir)
    column = "hyperbolic vertices"
    assert column in table["cube-12.obj"], "MODELS.md column header changed"
    for rel in ("cube-12.obj", "torus-8x4-64.obj", "l-prism-20.obj", "bunny-128.obj", "spiky-icosahedron-60.obj",
                "moneybox-128.obj", "open/tube-132.obj", "paper-parts/horse/part-3.obj"):
        assert describe(_load(models_dir, rel))["hyperbolic_vertices"] == int(table[rel][column]), rel


# ----------------------------------------------------------------------------------------------
# Orientation: a Moebius strip, random flips (synthetic files)


def test_moebius_strip_is_rejected(tmp_path: Path) -> None:
    n = 8
    lines = []
    for i in range(n):
        t = 2 * math.pi * i / n
        for s in (-0.3, 0.3):  # width direction turns by half a turn over the loop
            r = 1 + s * math.cos(t / 2)
            lines.append(f"v {r * math.cos(t)} {r * math.sin(t)} {s * math.sin(t / 2)}")
    for i in range(n):
        a, b = 2 * i, 2 * i + 1
        c, d = (2 * (i + 1), 2 * (i + 1) + 1) if i < n - 1 else (1, 0)  # the half twist
        lines += [f"f {a + 1} {c + 1} {d + 1}", f"f {a + 1} {d + 1} {b + 1}"]
    (tmp_path / "moebius.obj").write_text("\n".join(lines) + "\n")
    with pytest.raises(MeshError, match=r"^moebius\.obj: .*not orientable"):
        load_mesh(tmp_path / "moebius.obj")


@settings(max_examples=25, deadline=None)
@given(st.data())
def test_random_flips_are_undone(data) -> None:
    root = models_path()
    if root is None:
        pytest.skip("no models")
    name = data.draw(st.sampled_from(["torus-8x4-64.obj", "icosphere-l1-80.obj", "l-prism-20.obj"]))
    verts, faces = _read_obj(root / name)
    flip = data.draw(st.lists(st.booleans(), min_size=len(faces), max_size=len(faces)))
    lines = ["v " + " ".join(repr(float(c)) for c in v) for v in verts]
    lines += ["f " + " ".join(str(i + 1) for i in (f[::-1] if fl else f)) for f, fl in zip(faces, flip)]
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / name
        path.write_text("\n".join(lines) + "\n")
        loaded = load_mesh(path)
    # The repaired faces are exactly the file's outward faces (up to rotation of the corners).
    def canon(f):
        k = int(np.argmin(f))
        return tuple(f[k:]) + tuple(f[:k])

    assert sorted(canon(list(f)) for f in loaded.mesh.faces) == sorted(canon(f) for f in faces)
    k = sum(flip)
    assert loaded.oriented is (k == 0)
    if 0 < k < len(faces) - k:
        assert loaded.warnings[0].startswith(f"flipped {k} face")


def _cube_obj(path: Path, boxes: list[tuple[float, float]]) -> Path:
    """An OBJ of axis-aligned cubes, each (side, x offset), coordinates written exactly (repr)."""
    corners = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
    tris = [(0, 2, 1), (1, 2, 3), (4, 5, 6), (5, 7, 6), (0, 1, 4), (1, 5, 4),
            (2, 6, 3), (3, 6, 7), (0, 4, 2), (2, 4, 6), (1, 3, 5), (3, 7, 5)]
    lines = []
    for k, (side, dx) in enumerate(boxes):
        lines += [f"v {x * side + dx!r} {y * side!r} {z * side!r}" for x, y, z in corners]
        lines += [f"f {a + 1 + 8 * k} {b + 1 + 8 * k} {c + 1 + 8 * k}" for a, b, c in tris]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_tolerances_follow_each_part_not_the_whole_file(tmp_path: Path) -> None:
    # a 1 mm cube beside a 1 km one: neither is degenerate, nor welded into a point
    loaded = load_mesh(_cube_obj(tmp_path / "two.obj", [(1e-3, 0.0), (1e6, 1e7)]))
    assert loaded.mesh.n_faces == 24 and len(loaded.components) == 2
    assert not [w for w in loaded.warnings if "degenerate" in w or "welded" in w]
    for comp, side in zip(sorted(loaded.components, key=lambda c: np.ptp(c.vertices)), (1e-3, 1e6)):
        assert signed_volume(comp) == pytest.approx(side ** 3, rel=1e-9)
    # a face whose corners lie on one line is still dropped, whatever its size
    bad = tmp_path / "sliver.obj"
    bad.write_text(_cube_obj(tmp_path / "c.obj", [(1.0, 0.0)]).read_text() + "v 5 0 0\nv 6 0 0\nv 7 0 0\nf 9 10 11\n")
    assert any("dropped 1 degenerate face" in w for w in load_mesh(bad).warnings)


@pytest.mark.parametrize("side", [1e300, 1e-300, 1e150, 1e-150])
def test_a_model_of_extreme_size_is_scaled_not_dropped(side: float, tmp_path: Path) -> None:
    loaded = load_mesh(_cube_obj(tmp_path / "cube.obj", [(side, 0.0)]))
    assert loaded.mesh.n_faces == 12 and len(loaded.components) == 1
    (note,) = [w for w in loaded.warnings if "scaled by 2^" in w]
    k = int(note.split("2^")[1].split()[0])
    assert np.ptp(loaded.mesh.vertices, axis=0).max() == pytest.approx(side * 2.0 ** k)  # exactly rescaled
    assert 0.5 <= np.ptp(loaded.mesh.vertices, axis=0).max() <= 2.0
