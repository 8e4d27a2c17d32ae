"""apps/cli/make_commands.py: `polyfold make` with its defaults (every output, every sheet checked
independently, every piece a verified net and folding path), and its errors (a model too large for
the paper, bad options). (`polyfold view`, `batch`, `bench paper`: tests/apps/test_view.py,
test_batch.py, test_benchpaper.py.)"""

from __future__ import annotations

import json
import math
import re
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from conftest import check_sheet, one_line, read_sheet, run_cli
from fold_checker import check_fold, read_mesh
from path_checker import check_path


REPORT_KEYS = {"polyfold_report", "input", "options", "stages", "pieces", "checks", "outputs", "seconds"}


STAGES = {"load", "inflate", "segment", "unfold", "fold", "layout", "export"}


def piece_files(fold_path: Path, mesh_path: Path, tmp_path: Path) -> tuple[str, str]:
    """A piece covers some of the mesh's faces: write those faces as their own OBJ (file order
    kept) and the FOLD with faces_meshFace renumbered into it, for the whole-net checker."""
    verts, polys = read_mesh(str(mesh_path))
    fold = json.loads(fold_path.read_text())
    src = sorted(set(fold["polyfold:faces_meshFace"]))
    new = {f: k for k, f in enumerate(src)}
    obj = tmp_path / f"{fold_path.stem}.obj"
    obj.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in verts.tolist())
                   + "".join("f " + " ".join(str(v + 1) for v in polys[f]) + "\n" for f in src))
    fold["polyfold:faces_meshFace"] = [new[f] for f in fold["polyfold:faces_meshFace"]]
    out = tmp_path / fold_path.name
    out.write_text(json.dumps(fold))
    return str(out), str(obj)


def test_make_bunny_default_cli(models_dir, tmp_path):
    src = models_dir / "bunny-128.obj"
    out = tmp_path / "bunny"
    (out).mkdir()
    (out / "sheet-09.svg").write_text("stale")
    (out / "cut-09.svg").write_text("stale")
    (out / ".polyfold-manifest.json").write_text('{"files": ["sheet-09.svg", "cut-09.svg"]}')  # an earlier run's
    (out / "notes.svg").write_text("mine")  # the user's: kept
    proc = run_cli("make", src, "-o", out)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    report = json.loads((out / "report.json").read_text())
    assert REPORT_KEYS <= set(report) and STAGES <= set(report["stages"])
    n_pages = report["stages"]["layout"]["pages"]
    pieces = report["pieces"]
    assert set(report["outputs"]) | {"notes.svg"} == {p.name for p in out.iterdir() if not p.name.startswith(".")}
    assert not (out / "sheet-09.svg").exists() and not (out / "cut-09.svg").exists()
    assert (out / "notes.svg").read_text() == "mine"
    assert json.loads((out / ".polyfold-manifest.json").read_text())["files"] == report["outputs"]
    assert not [p for p in out.iterdir() if p.is_dir()]  # no staged folder left
    # sheets in every format, one per page
    svgs = sorted(out.glob("sheet-*.svg"))
    assert len(svgs) == n_pages == len(list(out.glob("sheet-*.dxf"))) == len(list(out.glob("cut-*.svg")))
    pdf = (out / "sheets.pdf").read_bytes()
    assert pdf.startswith(b"%PDF") and len(re.findall(rb"/Type /Page\b", pdf)) == n_pages
    labels = Counter()
    for svg in svgs:
        sheet = read_sheet(svg)
        assert {"cut", "mountain", "valley", "labels"} <= sheet["layers"]
        assert (sheet["width"], sheet["height"]) == (210.0, 297.0)
        assert check_sheet(sheet, 10.0) == []
        labels.update(text for kind, text in sheet["labels"] if kind == "edge-label")
    # every glue label printed exactly twice; every glue pair of the assembly is labelled
    assembly = json.loads((out / "assembly.json").read_text())
    assert set(labels.values()) == {2}
    assert set(labels) == {g["label"] for g in assembly["glue"]}
    assert sum(g["tab_on"] is None for g in assembly["glue"]) == len(report["stages"]["layout"]["untabbed_edges"])
    # every piece: a verified net and a verified folding path, checked independently
    assert report["checks"]["paths_verified"] == len(pieces)
    for row in pieces:
        fold = out / row["fold_file"]
        net = check_fold(*piece_files(fold, src, tmp_path))
        assert net.ok and net.pieces == 1, f"{row['piece']}:\n{net}"
        path = check_path(fold)
        assert path.ok, f"{row['piece']}:\n{path}"
    assert sum(r["faces"] for r in pieces) == 128
    html = (out / "instructions.html").read_text()
    assert all(f"<b>{r['piece']}</b>" in html for r in pieces) and "data:image/png;base64," in html
    assert all(f"src='{s.name}'" in html for s in svgs)
    assert "cut-NN.svg" in html and "sheet-NN.svg" in html


def test_too_large_and_bad_options(models_dir, tmp_path):
    out = tmp_path / "t"
    proc = run_cli("make", models_dir / "tetrahedron-4.obj", "-o", out, "--size", 150)
    assert proc.returncode == 2
    line = one_line(proc.stderr.strip().splitlines()[-1] + "\n")
    assert "largest size that fits is 144 mm" in line  # and it does (the tab room does not scale):
    assert not out.exists() or not any(out.iterdir())
    assert run_cli("make", models_dir / "tetrahedron-4.obj", "-o", out, "--size", 144, "--no-fold", "-q").returncode == 0
    assert run_cli("make", models_dir / "tetrahedron-4.obj", "-o", out, "--size", 144.4, "--no-fold", "-q").returncode == 2
    proc = run_cli("make", models_dir / "tetrahedron-4.obj", "-o", out, "--paper", "b5", "-q")
    assert proc.returncode == 2 and "unknown paper" in one_line(proc.stderr)
    proc = run_cli("make", models_dir / "tetrahedron-4.obj", "-o", out, "--tau", 0.1, "--parts", 2, "-q")
    assert proc.returncode == 2 and "--tau or --parts" in one_line(proc.stderr)
    proc = run_cli("make", models_dir / "tetrahedron-4.obj", "-o", out, "--paper", "50x80mm", "--marks", "-q")
    assert proc.returncode == 2 and "--marks" in one_line(proc.stderr)


def _smallest_edge_mm(mesh_path: Path, size: float) -> float:
    """The shortest face edge of a mesh file at the printed size (longest box side = size mm)."""
    verts, polys = read_mesh(str(mesh_path))
    used = sorted({v for p in polys for v in p})
    scale = size / float(np.ptp(verts[used], axis=0).max())
    return scale * min(float(np.linalg.norm(verts[p[k]] - verts[p[k - 1]])) for p in polys for k in range(len(p)))


def test_small_edges_are_said(models_dir, tmp_path):
    """The summary line and report.json give the smallest printed edge and face; under 5 mm, one
    warning line names the --size that reaches 5 mm, and at that size there is no warning."""
    src = models_dir / "bumpy-528.obj"
    proc = run_cli("make", src, "-o", tmp_path / "a", "--no-guide")
    assert proc.returncode == 0, proc.stderr
    lay = json.loads((tmp_path / "a" / "report.json").read_text())["stages"]["layout"]
    edge = _smallest_edge_mm(src, 150.0)
    assert edge < 5.0 and lay["smallest_edge_mm"] == pytest.approx(edge, rel=1e-9)
    assert 0 < lay["smallest_face_mm"] <= lay["smallest_edge_mm"]
    warnings = [ln for ln in proc.stderr.splitlines() if "smallest printed edge" in ln]
    size = math.ceil(150.0 * 5.0 / edge)
    assert len(warnings) == 1 and warnings[0].startswith("polyfold: warning:"), proc.stderr
    assert f"is {edge:.3g} mm" in warnings[0] and f"--size {size} would" in warnings[0]
    assert lay["faces_for_size"] == 0 and "--faces" not in warnings[0]  # (its faces are no finer than 12 mm ones)
    summary = proc.stderr.strip().splitlines()[-1]
    assert (f"smallest edge {lay['smallest_edge_mm']:.3g} mm, narrowest face {lay['smallest_face_mm']:.3g} mm"
            in summary)
    proc = run_cli("make", src, "-o", tmp_path / "b", "--size", size, "--no-guide")
    assert proc.returncode == 0, proc.stderr
    assert "smallest printed edge" not in proc.stderr
    lay = json.loads((tmp_path / "b" / "report.json").read_text())["stages"]["layout"]
    assert 5.0 <= lay["smallest_edge_mm"] < 5.0 * (size + 1) / size


def test_slivers_are_told_to_simplify(models_dir, tmp_path):
    """hull-ellipsoid-rand-236 has vertices 0.25 mm apart at 150 mm: its warning names --faces
    for faces about 12 mm across (`auto_face_count`, fewer than it has) beside the --size that
    no sheet holds, and at that face count its smallest printed edge is ten times longer."""
    from polyfold.formats.meshes import load_mesh
    from polyfold.mesh.simplify import auto_face_count

    src = models_dir / "hull-ellipsoid-rand-236.obj"
    proc = run_cli("make", src, "-o", tmp_path / "a", "--no-guide")
    assert proc.returncode == 0, proc.stderr
    lay = json.loads((tmp_path / "a" / "report.json").read_text())["stages"]["layout"]
    fewer = auto_face_count(load_mesh(src).mesh, 150.0)
    assert lay["faces_for_size"] == fewer < 236
    warning = [ln for ln in proc.stderr.splitlines() if "smallest printed edge" in ln]
    assert len(warning) == 1 and warning[0].endswith(f"faces about 12 mm across: --faces {fewer}"), proc.stderr
    proc = run_cli("make", src, "-o", tmp_path / "b", "--no-guide", "--faces", fewer)
    assert proc.returncode == 0, proc.stderr
    simpler = json.loads((tmp_path / "b" / "report.json").read_text())["stages"]["layout"]
    assert simpler["smallest_edge_mm"] > 10 * lay["smallest_edge_mm"] and simpler["faces_for_size"] == 0


def test_a_mesh_too_fine_for_the_time_limit_stops_at_it(tmp_path):
    # a 5,120-face noisy sphere: its labels alone take longer than 3 s to place (issue 20: an 82k-face
    # mesh ran 286 s through --time-limit 60); make stops at the limit with one line, exit 1, writes
    # nothing. bench/bench_big.py measures the stop on 20k-100k faces.
    import time

    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=4)
    rng = np.random.default_rng(0)
    sphere.vertices *= 1.0 + 0.02 * rng.standard_normal((len(sphere.vertices), 1))
    src, out = tmp_path / "fine.obj", tmp_path / "out"
    sphere.export(src)
    out.mkdir()
    t0 = time.perf_counter()
    proc = run_cli("make", src, "-o", out, "--time-limit", 3, "--faces", "none", "-q")
    elapsed = time.perf_counter() - t0
    assert proc.returncode == 1, proc.stderr
    line = one_line(proc.stderr)
    assert "fine.obj: stopped at --time-limit 3 s while" in line and "5,120 faces" in line and "simplify" in line
    assert not any(out.iterdir())  # nothing written, no temp folder left
    # the stop is a check between steps, not a kill: it comes at the limit, not minutes later (the
    # margin is the interpreter's start and loading, and one step of work)
    assert elapsed < 3 + 20


def test_the_same_seed_makes_the_same_files(models_dir, tmp_path):
    """README "Same --seed, same files": two makes of the bunny, in processes of other hash seeds,
    write every file but report.json (its seconds) byte for byte alike."""
    outs = []
    for seed in ("1", "2"):
        out = tmp_path / seed
        proc = run_cli("make", models_dir / "bunny-128.obj", "-o", out, "-q", env={"PYTHONHASHSEED": seed})
        assert proc.returncode == 0, proc.stderr
        outs.append(out)
    names = sorted(p.name for p in outs[0].iterdir())
    assert names == sorted(p.name for p in outs[1].iterdir()) and len(names) > 20
    differ = [n for n in names if (outs[0] / n).read_bytes() != (outs[1] / n).read_bytes()]
    assert differ == ["report.json"]
