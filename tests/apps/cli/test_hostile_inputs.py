"""Issue 20: every bad input and option gets one line and exit 2 (never a traceback, never exit 3
"internal error", never a library's message without the file). A generated corpus of hostile
files through the CLI, bad options, absurd parameters, and property-based tests (hypothesis) that
the readers raise nothing but PolyfoldError on arbitrary text, bytes and JSON."""

from __future__ import annotations

import json
import math
import struct
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import one_line, run_cli
from polyfold.errors import PolyfoldError
from polyfold.formats.fold import fold_tree, read_fold
from polyfold.formats.meshes import load_mesh


def _fan_fold() -> dict:
    """A fan of seven 60-degree triangles around one vertex: 420 degrees, the last over the first."""
    pts = [[0.0, 0.0]] + [[math.cos(math.radians(60 * k)), math.sin(math.radians(60 * k))] for k in range(8)]
    edges = [[0, k] for k in range(1, 9)] + [[k, k + 1] for k in range(1, 8)]
    assign = ["M" if 2 <= k <= 7 else "B" for k in range(1, 9)] + ["B"] * 7
    return {"vertices_coords": pts, "faces_vertices": [[0, k, k + 1] for k in range(1, 8)], "edges_vertices": edges,
            "edges_assignment": assign, "edges_foldAngle": [-10.0 if a == "M" else 0.0 for a in assign]}


TRI = struct.pack("<12fH", *([0.0] * 12), 0)
# name -> (content, words the one line must hold)
CORPUS: dict[str, tuple[bytes, str]] = {
    "huge-index.obj": (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 1000000000000000000000000000000\n", "line 4: face 0"),
    "nul-byte.obj": (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n\0f 1 2 3\n", "line 5: a NUL byte"),
    "index-zero.obj": (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "index 0"),
    "letters.obj": (b"v 0 0 x\n", "not a number"),
    "empty.obj": (b"", "no faces"),
    "short-off.off": (b"OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1\n", "file ends early"),
    "truncated.stl": (b"\0" * 80 + struct.pack("<I", 12) + TRI * 2, "promises 12 triangles, the file holds 2"),
    "empty.stl": (b"", "no faces"),
    "short.stl": (b"x" * 34, "no faces"),  # (34 = 84 - 50: once taken for a binary file of -1 triangles)
    "ascii-broken.stl": (b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\nendloop\nendfacet\nendsolid\n",
                         "no faces"),
    "short-count.ply": (b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                        b"property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
                        b"0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1 3\n", "promises 4 vertices and 4 faces"),
    "garbage.glb": (b"glTF\x02\x00\x00\x00" + b"\xff" * 40, "not a readable GLB"),
    "text.glb": (b"hello", "GLB"),
    "null.fold": (b"null", "holds null"),
    "number.fold": (b"42", "holds a number"),
    "list.fold": (b"[1, 2, 3]", "holds a list"),
    "nested.fold": (b"[" * 100000 + b"]" * 100000, "nested too deeply"),
    "not-json.fold": (b"{nope", "not a readable FOLD"),
    "no-faces.fold": (b'{"vertices_coords": [[0, 0]], "edges_vertices": [], "edges_assignment": []}', "faces_vertices"),
    "overlap.fold": (json.dumps(_fan_fold()).encode(), "faces 0 and 6 overlap"),
}


@pytest.mark.parametrize("name", sorted(CORPUS))
def test_a_hostile_file_gets_one_line_and_exit_2(name: str, tmp_path: Path) -> None:
    data, words = CORPUS[name]
    path = tmp_path / name
    path.write_bytes(data)
    args = ("fold", path, "-o", tmp_path / "out.fold") if name.endswith(".fold") else ("info", path)
    proc = run_cli(*args, timeout=120)
    line = one_line(proc.stderr)
    assert proc.returncode == 2, line
    assert line.startswith("polyfold: error: ") and name in line and words in line, line
    assert "internal error" not in line
    assert not (tmp_path / "out.fold").exists()


@pytest.mark.parametrize(("args", "words"), [
    (("unfold", "{mesh}", "-o", "{tmp}/x.fold", "--seed", "-1"), "--seed"),
    (("unfold", "{mesh}", "-o", "{tmp}/x.fold", "--size", "abc"), "--size"),
    (("unfold", "{mesh}"), "Missing option '-o'"),
    (("unfold", "{mesh}", "-o", "{tmp}/x.fold", "--bogus"), "No such option: --bogus"),
    (("nosuchverb",), "No such command"),
    (("inflate", "{mesh}", "-o", "{tmp}/i.obj", "--stiffness-ratio", "1e308"), "stiffness_ratio must be at most"),
    (("inflate", "{mesh}", "-o", "{tmp}/i.obj", "--pressure", "inf"), "pressure"),
    (("make", "{mesh}", "-o", "{tmp}/m", "--faces", "5"), "--faces 5: too few"),
    (("segment", "{mesh}", "-o", "{tmp}/s", "--faces", "many"), "--faces 'many'"),
])
def test_a_bad_option_gets_one_line_and_exit_2(args, words: str, models_dir: Path, tmp_path: Path) -> None:
    filled = [a.format(mesh=models_dir / "bunny-128.obj", tmp=tmp_path) for a in args]
    proc = run_cli(*filled, timeout=120)
    line = one_line(proc.stderr)
    assert proc.returncode == 2 and line.startswith("polyfold: error: ") and words in line, line
    assert not list(tmp_path.iterdir())  # nothing written


# ----------------------------------------------------------------------------------------------
# Property-based: arbitrary input never escapes as anything but a PolyfoldError


OBJ_LINES = st.lists(st.one_of(
    st.builds(lambda xs: "v " + " ".join(xs), st.lists(st.sampled_from(["0", "1", "-1", "1e308", "nan", "x", "0.5"]),
                                                       max_size=4)),
    st.builds(lambda ks: "f " + " ".join(ks), st.lists(st.sampled_from(["1", "2", "3", "4", "-1", "0", "9", "2/3",
                                                                        "1//2", "a", str(10 ** 30)]), max_size=5)),
    st.text(max_size=20),
), max_size=12)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(lines=OBJ_LINES)
def test_any_obj_text_loads_or_fails_with_one_line(lines: list[str], tmp_path: Path) -> None:
    path = tmp_path / "fuzz.obj"
    path.write_text("\n".join(lines), encoding="utf-8", errors="surrogatepass")
    try:
        load_mesh(path)
    except PolyfoldError as exc:
        assert "\n" not in str(exc).strip()


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.binary(max_size=400), suffix=st.sampled_from([".stl", ".ply", ".off", ".obj", ".glb"]))
def test_any_bytes_load_or_fail_with_one_line(data: bytes, suffix: str, tmp_path: Path) -> None:
    path = tmp_path / f"fuzz{suffix}"
    path.write_bytes(data)
    try:
        load_mesh(path)
    except PolyfoldError as exc:
        assert "\n" not in str(exc).strip()


JSON = st.recursive(st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=5),
                    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=5), inner, max_size=4),
                    max_leaves=20)
KEYS = ["vertices_coords", "faces_vertices", "edges_vertices", "edges_assignment", "edges_foldAngle",
        "polyfold:faces_parent", "file_frames"]


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(doc=st.one_of(JSON, st.dictionaries(st.sampled_from(KEYS), JSON, max_size=7)))
def test_any_json_is_a_net_or_one_line(doc, tmp_path: Path) -> None:
    path = tmp_path / "fuzz.fold"
    path.write_text(json.dumps(doc))
    try:
        fold_tree(read_fold(path))
    except PolyfoldError as exc:
        assert "\n" not in str(exc).strip()


def test_a_file_system_that_says_no_is_one_line_and_exit_2(capsys) -> None:
    import errno

    import typer

    from polyfold.apps.cli.app import guard

    @guard
    def full_disk() -> None:
        raise OSError(errno.ENOSPC, "No space left on device", "/out/sheet-01.svg")

    with pytest.raises(typer.Exit) as exit_:
        full_disk()
    assert exit_.value.exit_code == 2
    assert one_line(capsys.readouterr().err) == "polyfold: error: /out/sheet-01.svg: No space left on device"
