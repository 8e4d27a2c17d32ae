"""formats/guide_pdf.py: guide.pdf embeds every picture's JPEG as it is (DCTDecode), one image
per picture however often it is shown, though reportlab is not let decode the JPEGs to name them
(`guide_pdf._image`)."""

from __future__ import annotations

import io

import numpy as np
from pypdf import PdfReader

from polyfold.formats.guide_pdf import _image
from polyfold.formats.pdf import binary_streams
from polyfold.guide.guide import Picture


def test_every_picture_is_embedded_once_as_its_own_jpeg():
    from reportlab.platypus import SimpleDocTemplate

    pictures = []
    for k in range(3):
        img = np.full((60, 80 + 8 * k, 3), 255, dtype=np.uint8)
        img[10:40, 5 + 10 * k:50 + 10 * k] = (200, 30 * k, 90)
        pictures.append(Picture(img, f"picture {k}"))
    buf = io.BytesIO()
    with binary_streams():  # (as guide_pdf_bytes writes them)
        SimpleDocTemplate(buf, invariant=1).build([_image(p, 100.0) for p in pictures] + [_image(pictures[0], 50.0)])
    page = PdfReader(io.BytesIO(buf.getvalue())).pages[0]
    xobjects = page["/Resources"]["/XObject"]
    images = [xobjects[name].get_object() for name in xobjects]
    assert len(images) == 3  # (the first picture, shown twice, once)
    by_jpeg = {p.jpeg: p for p in pictures}
    assert {im.get_data() for im in images} == set(by_jpeg)
    for im in images:
        assert list(im["/Filter"]) == ["/DCTDecode"]
        h, w = by_jpeg[im.get_data()].shape
        assert (im["/Width"], im["/Height"]) == (w, h)
