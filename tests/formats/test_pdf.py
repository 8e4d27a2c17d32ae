"""formats/pdf.py: pages, media boxes, exact geometry (y flipped, in points), colours, dashes and
rotated text of the PDF writer; no pages and a failure while drawing write nothing."""

from __future__ import annotations

import base64
import re
import zlib

import numpy as np
import pytest

from conftest import PAGE_TOL
from polyfold.fabricate.page import Page
from polyfold.formats import pdf as pdf_writer
from polyfold.formats import sheet_style
from polyfold.formats.pdf import write_pdf
from polyfold.formats.sheet_style import MM_TO_PT


def _pdf_content_streams(data: bytes) -> list[bytes]:
    """Decoded content streams of a reportlab PDF (ASCII85 + Flate, or unfiltered)."""
    out = []
    for m in re.finditer(rb"<<(.*?)>>\s*stream\r?\n(.*?)endstream", data, re.S):
        head, body = m.group(1), m.group(2)
        if b"/ASCII85Decode" in head:
            body = base64.a85decode(body.strip().removesuffix(b"~>"))
        if b"/FlateDecode" in head:
            body = zlib.decompress(body)
        out.append(body)
    return out


def test_pdf_pages_mediabox_and_geometry(page: Page, tmp_path) -> None:
    small = Page(50.0, 30.0, cut=([[5, 5], [20, 5], [20, 20]],), mountain=[], valley=[], tab_folds=[], texts=())
    path = tmp_path / "net.pdf"
    write_pdf([page, small, page], path, title="my net")
    data = path.read_bytes()
    assert data.startswith(b"%PDF")
    assert len(re.findall(rb"/Type\s*/Page(?![s\w])", data)) == 3
    boxes = [[float(v) for v in m.split()] for m in re.findall(rb"/MediaBox\s*\[([^\]]*)\]", data)]
    expected = [(p.width * MM_TO_PT, p.height * MM_TO_PT) for p in (page, small, page)]
    assert len(boxes) == 3
    for box, (w, h) in zip(boxes, expected):
        np.testing.assert_allclose(box, [0, 0, w, h], atol=1e-3)
    assert b"(my net)" in data  # title in the document info

    # Geometry: the small page's triangle, in points with y flipped (origin bottom-left).
    content = [s for s in _pdf_content_streams(data) if b" m" in s]
    assert len(content) == 3
    pts = np.array([[float(x), float(y)] for x, y in re.findall(rb"(-?[\d.]+) (-?[\d.]+) [ml]\b", content[1])])
    expect = np.array([[5, 30 - 5], [20, 30 - 5], [20, 30 - 20]]) * MM_TO_PT
    np.testing.assert_allclose(pts, expect, atol=PAGE_TOL * MM_TO_PT)
    # Colours and dashes of the big page: red and blue strokes, two distinct dash arrays.
    big = content[0].decode("latin-1")
    assert re.search(r"\b1 0 0 RG\b", big) and re.search(r"\b0 0 1 RG\b", big)
    dashes = set(re.findall(r"\[([^\]]*)\] 0 d", big))
    assert len({d for d in dashes if d.strip()}) == 2
    # Text is drawn in Helvetica, rotated about its flipped baseline anchor: 90 deg -> (0 1 -1 0).
    assert "/F1 " in big and "(P1) Tj" in big
    m = re.search(r"(?m)^0 1 -1 0 (-?[\d.]+) (-?[\d.]+) cm$", big)
    assert m, "no text rotated by 90 degrees"
    bx, by = sheet_style.text_baseline(page.texts[1])
    np.testing.assert_allclose([float(m.group(1)), float(m.group(2))],
                               [bx * MM_TO_PT, (page.height - by) * MM_TO_PT], atol=PAGE_TOL * MM_TO_PT)


def test_pdf_rejects_no_pages(tmp_path) -> None:
    with pytest.raises(ValueError):
        write_pdf([], tmp_path / "empty.pdf")
    assert not any(tmp_path.iterdir())


def test_failure_while_drawing_writes_nothing(page: Page, tmp_path, monkeypatch) -> None:
    def boom(*_args, **_kwargs):
        raise RuntimeError("renderer crashed")

    monkeypatch.setattr(pdf_writer, "_draw_pdf_page", boom)
    with pytest.raises(RuntimeError):
        write_pdf([page], tmp_path / "x.pdf")
    assert list(tmp_path.iterdir()) == []
