"""formats/dxf.py: the DXF page writer's layers, units, entities and y flip (read back by ezdxf)."""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import time

import ezdxf
import numpy as np

from conftest import PAGE_TOL
from polyfold.fabricate.page import Page
from polyfold.formats import sheet_style
from polyfold.formats.dxf import dxf_string, write_dxf_page


def test_dxf_layers_units_entities_and_flip(page: Page, tmp_path) -> None:
    path = tmp_path / "page.dxf"
    write_dxf_page(page, path)
    doc = ezdxf.readfile(path)
    assert doc.header["$INSUNITS"] == 4
    for name, color, linetype in (("CUT", 7, "CONTINUOUS"), ("MOUNTAIN", 1, "DASHDOT"),
                                  ("VALLEY", 5, "DASHED"), ("LABELS", None, None)):
        layer = doc.layers.get(name)
        assert layer is not None
        if color is not None:
            assert layer.color == color and layer.dxf.linetype.upper() == linetype

    msp = doc.modelspace()
    by_layer: dict[tuple[str, str], int] = {}
    for e in msp:
        key = (e.dxf.layer, e.dxftype())
        by_layer[key] = by_layer.get(key, 0) + 1
    assert by_layer == {
        ("CUT", "LWPOLYLINE"): len(page.cut),
        ("MOUNTAIN", "LINE"): len(page.mountain),
        ("VALLEY", "LINE"): len(page.valley) + len(page.tab_folds),
        ("LABELS", "TEXT"): len(page.texts),
    }

    flip = np.array([1.0, -1.0])
    shift = np.array([0.0, page.height])
    polys = msp.query('LWPOLYLINE[layer=="CUT"]')
    for e, poly in zip(polys, page.cut):
        assert e.closed
        got = np.array([(x, y) for x, y, *_ in e.get_points()])
        np.testing.assert_allclose(got, poly * flip + shift, atol=PAGE_TOL)
    line = msp.query('LINE[layer=="MOUNTAIN"]')[0]
    ends = [(line.dxf.start.x, line.dxf.start.y), (line.dxf.end.x, line.dxf.end.y)]
    np.testing.assert_allclose(ends, page.mountain[0] * flip + shift, atol=PAGE_TOL)
    texts = msp.query("TEXT")
    assert [t.dxf.text for t in texts] == [t.text for t in page.texts]
    assert [t.dxf.rotation for t in texts] == [t.angle for t in page.texts]  # flip keeps CCW sense
    anchor = np.array([texts[0].dxf.align_point.x, texts[0].dxf.align_point.y])
    bx, by = sheet_style.text_baseline(page.texts[0])
    np.testing.assert_allclose(anchor, [bx, page.height - by], atol=PAGE_TOL)


def test_the_same_page_gives_the_same_dxf_text(page: Page, tmp_path) -> None:
    """No time of writing, no random GUID, no order from a set of strings: a make run again writes
    the same DXF files (as it writes the same PDF bytes), in processes of other hash seeds too; and
    ezdxf's own option is left as it was."""
    first = dxf_string(page)
    time.sleep(0.01)  # (ezdxf's stamp holds microseconds)
    assert dxf_string(page) == first
    assert not ezdxf.options.write_fixed_meta_data_for_testing
    (tmp_path / "page.pkl").write_bytes(pickle.dumps(page))
    code = ("import pickle, sys; from polyfold.formats.dxf import dxf_string; "
            "sys.stdout.write(dxf_string(pickle.loads(open(sys.argv[1], 'rb').read())))")
    for seed in ("1", "2", "3"):
        out = subprocess.run([sys.executable, "-c", code, str(tmp_path / "page.pkl")], capture_output=True,
                             text=True, check=True, env={**os.environ, "PYTHONHASHSEED": seed}).stdout
        assert out == first, f"PYTHONHASHSEED={seed}"


def test_dxf_header_is_the_page_in_mm(page: Page, tmp_path) -> None:
    path = tmp_path / "page.dxf"
    write_dxf_page(page, path)
    doc = ezdxf.readfile(path)
    w, h = page.width, page.height
    assert doc.header["$INSUNITS"] == 4 and doc.header["$MEASUREMENT"] == 1
    assert tuple(doc.header["$LIMMIN"])[:2] == (0, 0) and tuple(doc.header["$LIMMAX"])[:2] == (w, h)
    assert tuple(doc.header["$EXTMIN"]) == (0, 0, 0) and tuple(doc.header["$EXTMAX"]) == (w, h, 0)
    assert tuple(doc.header["$PLIMMAX"])[:2] == (w, h)
    layout = doc.layouts.get("Layout1").dxf_layout.dxf  # what a CAD program plots on
    assert (layout.paper_width, layout.paper_height) == (w, h) and layout.plot_paper_units == 1  # mm
    assert (layout.left_margin, layout.top_margin, layout.scale_numerator, layout.scale_denominator) == (0, 0, 1, 1)
    # every drawn point lies within the extents
    for e in doc.modelspace():
        pts = [(x, y) for x, y, *_ in e.get_points()] if e.dxftype() == "LWPOLYLINE" else \
              [tuple(e.dxf.start)[:2], tuple(e.dxf.end)[:2]] if e.dxftype() == "LINE" else [tuple(e.dxf.align_point)[:2]]
        assert all(0 <= x <= w and 0 <= y <= h for x, y in pts)


def test_dxf_short_creases_show_a_gap(tmp_path) -> None:
    """Creases of 3 mm (and shorter) show at least one gap between two dashes of their own
    linetype, as ezdxf's linetype renderer draws them, and hold one whole pattern (AutoCAD draws a
    line shorter than its pattern solid); long ones keep the SVG's dash lengths."""
    from ezdxf.render.linetypes import LineTypeRenderer

    crease = lambda x, y, length: [[x, y], [x + length, y]]
    page = Page(100.0, 60.0, cut=([[5, 5], [95, 5], [95, 55], [5, 55]],),
                mountain=[crease(10, 10, 3.0), crease(10, 20, 40.0)], valley=[crease(10, 30, 3.0)],
                tab_folds=[crease(10, 40, 1.0), crease(10, 50, 3.0)], tab_mountain=[False, True], texts=())
    path = tmp_path / "short.dxf"
    write_dxf_page(page, path)
    doc = ezdxf.readfile(path)
    ltscale = doc.header["$LTSCALE"]
    lines = doc.modelspace().query('LINE[layer=="MOUNTAIN" | layer=="VALLEY"]')
    assert len(lines) == 5
    for e in lines:
        linetype = doc.layers.get(e.dxf.layer).dxf.linetype
        dashes = np.array(doc.linetypes.get(linetype).pattern_tags.compile()) * ltscale * e.dxf.get("ltscale", 1.0)
        length = e.dxf.start.distance(e.dxf.end)
        dash_pieces = list(LineTypeRenderer(dashes.tolist()).line_segment(e.dxf.start, e.dxf.end))
        assert len(dash_pieces) >= 2, (e.dxf.layer, length)  # at least one gap, between two dashes
        assert dashes.sum() <= length + 1e-9
        if length >= 10:
            np.testing.assert_allclose(dashes, sheet_style.STYLES["mountain"]["dash"])
