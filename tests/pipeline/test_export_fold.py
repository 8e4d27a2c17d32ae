"""pipeline/export.py, its FOLD pieces (the rest of export: test_export.py): in mm where they are
printed (their sheet transform puts every net vertex on the printed lines of their page, their
folded frame is the part at the printed scale), and the FOLD project's own ORIPA converter (npm
`fold`) keeps every vertex of them."""

from __future__ import annotations

import json
import shutil
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from fold_checker import read_obj
from sheet_reader import read_svg

from polyfold.pipeline.make import make
from polyfold.pipeline.options import MakeOptions

NODE_MODULES = Path(__file__).resolve().parents[1] / ".node" / "node_modules"
ON_LINE_MM = 1e-3  # the SVG keeps coordinates to 1e-4 mm


@pytest.fixture(scope="module")
def bunny(models_dir, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("export") / "bunny-128"
    make(models_dir / "bunny-128.obj", out, MakeOptions(time_limit=30))
    return out


def _on_segments(points: np.ndarray, segs: np.ndarray) -> np.ndarray:
    """Distance (n,) of each point to the nearest of the segments (k, 2, 2)."""
    a, b = segs[None, :, 0], segs[None, :, 1]
    ab = b - a
    t = np.clip(np.einsum("nki,nki->nk", points[:, None] - a, ab) / np.maximum(np.einsum("nki,nki->nk", ab, ab), 1e-300),
                0.0, 1.0)
    return np.linalg.norm(a + t[..., None] * ab - points[:, None], axis=2).min(axis=1)


def test_pieces_are_in_mm_where_printed(bunny: Path) -> None:
    assembly = json.loads((bunny / "assembly.json").read_text())
    report = json.loads((bunny / "report.json").read_text())
    scale = report["stages"]["layout"]["scale_mm_per_unit"]
    verts, _ = read_obj(str(bunny / "part-0.obj"))
    for row in assembly["pieces"]:
        fold = json.loads((bunny / row["fold"]).read_text())
        assert fold["frame_unit"] == "mm" and fold["polyfold:page"] == row["page"]
        assert fold["polyfold:mmPerModelUnit"] == scale
        m = np.asarray(fold["polyfold:sheet_transform"], dtype=float)
        assert m.shape == (2, 3)
        xy = np.asarray(fold["vertices_coords"], dtype=float)
        page = xy @ m[:, :2].T + m[:, 2]
        sheet = read_svg(bunny / f"sheet-{row['page']:02d}.svg")
        # every crease lands on a printed fold line of its kind, every cut edge on the outline
        # (or on a tab's fold line), and every vertex on the page
        edges = np.asarray(fold["edges_vertices"])
        kinds = np.asarray(fold["edges_assignment"])
        for code, where in (("M", sheet.folds["mountain"]), ("V", sheet.folds["valley"]), ("B", sheet.lines())):
            ends = page[edges[kinds == code]].reshape(-1, 2)
            mids = page[edges[kinds == code]].mean(axis=1)
            assert len(ends) or code != "B", row  # a small piece may have no mountain or no valley crease
            if len(ends):
                assert _on_segments(np.concatenate([ends, mids]), where).max() < ON_LINE_MM, (row, code)
        assert (page >= 0).all() and (page <= [sheet.width, sheet.height]).all()
        # printed faces are the model's faces at the printed scale, not mirrored (CCW in FOLD's y up)
        tri = xy[np.asarray(fold["faces_vertices"])]
        u, w = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
        assert (u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0] > 0).all()
        folded = np.asarray(fold["file_frames"][0]["vertices_coords"], dtype=float)
        flat_len = np.linalg.norm(xy[edges[:, 0]] - xy[edges[:, 1]], axis=1)
        np.testing.assert_allclose(np.linalg.norm(folded[edges[:, 0]] - folded[edges[:, 1]], axis=1), flat_len,
                                   rtol=1e-9)
        # the folded frame is the part (model units) times the printed scale
        gap = np.linalg.norm(folded[:, None] - (verts * scale)[None], axis=2).min(axis=1)
        assert gap.max() < 1e-9 * scale


ROUND_TRIP = """
const fs = require('fs');
const FOLD = require('fold');
const out = [];
for (const name of process.argv.slice(2)) {
  const opx = FOLD.convert.convertFromTo(fs.readFileSync(name, 'utf-8'), '.fold', '.opx');
  fs.writeFileSync(name + '.opx', opx);
  // read back as ORIPA reads it: points closer than ORIPA's epsilon (1 unit) are one vertex
  const back = FOLD.convert.convertFromTo(opx, '.opx', '.fold');
  out.push({file: name, vertices: back.vertices_coords.length});
}
console.log(JSON.stringify(out));
"""


def test_oripa_conversion_keeps_every_vertex(bunny: Path, tmp_path: Path) -> None:
    """npm `fold` (pinned 0.12.0, installed into tests/.node by .ci/run) converts every piece to
    ORIPA's .opx; reading the .opx back as ORIPA does (vertices closer than 1 unit merged) keeps
    every vertex: in mm they are far enough apart (in model units the bunny collapsed to 2)."""
    node = shutil.which("node")
    if node is None:
        pytest.skip("node is not installed (the npm fold package needs Node.js)")
    if not (NODE_MODULES / "fold" / "package.json").is_file():
        pytest.skip(f"npm package fold is not installed in {NODE_MODULES.parent} "
                    "(.ci/run installs it: npm install --prefix tests/.node fold@0.12.0)")
    names = sorted(p.name for p in bunny.glob("piece-*.fold"))
    for name in names:
        shutil.copy(bunny / name, tmp_path / name)
    script = tmp_path / "round_trip.js"
    script.write_text(ROUND_TRIP)
    proc = subprocess.run([node, str(script), *names], cwd=tmp_path, capture_output=True, text=True, timeout=120,
                          env={"NODE_PATH": str(NODE_MODULES), "PATH": ""})
    assert proc.returncode == 0, proc.stderr
    results = json.loads(proc.stdout)
    assert [r["file"] for r in results] == names
    for r in results:
        fold = json.loads((tmp_path / r["file"]).read_text())
        n_v = len(fold["vertices_coords"])
        # the .opx holds every edge with its vertices' exact coordinates
        lines = ET.parse(tmp_path / f"{r['file']}.opx").getroot().iter("object")
        ends = set()
        n_lines = 0
        for obj in lines:
            if obj.get("class") != "oripa.OriLineProxy":
                continue
            n_lines += 1
            value = {p.get("property"): float(p[0].text) for p in obj.findall("void") if p.get("property") != "type"}
            ends |= {(value["x0"], value["y0"]), (value["x1"], value["y1"])}
        assert n_lines == len(fold["edges_vertices"]) and len(ends) == n_v, r["file"]
        assert r["vertices"] == n_v, f"{r['file']}: ORIPA's reading merges {n_v} vertices into {r['vertices']}"
