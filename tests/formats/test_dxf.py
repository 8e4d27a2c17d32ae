"""formats/dxf.py: the DXF page writer's layers, units, entities and y flip (read back by ezdxf)."""

from __future__ import annotations

import ezdxf
import numpy as np

from conftest import PAGE_TOL
from polyfold.fabricate.page import Page
from polyfold.formats import sheet_style
from polyfold.formats.dxf import write_dxf_page


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
