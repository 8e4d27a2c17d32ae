"""Pictures on the sheets (the model's texture): the PDF and the print SVG place each picture where
its page says, show it only inside its clip, give lines and labels a white halo, and keep it out
of the cut files."""

from __future__ import annotations

import base64
import io
import shutil
import subprocess
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from PIL import Image

from polyfold.fabricate.page import Page, PageImage, TextItem
from polyfold.formats.dxf import dxf_document
from polyfold.formats.pdf import write_pdf
from polyfold.formats.svg import cut_svg_string, svg_page_string

RED, BLUE = (220, 20, 20), (20, 20, 220)


def picture_page() -> Page:
    """A 100 x 80 mm page with one 60 x 40 mm picture at (20, 20): left half red, right half
    blue, clipped to a triangle; one piece outline around the triangle and a label in it."""
    pixels = np.zeros((200, 300, 3), np.uint8)
    pixels[:, :150] = RED
    pixels[:, 150:] = BLUE
    tri = np.array([[20.0, 60.0], [80.0, 60.0], [50.0, 20.0]])
    image = PageImage(20.0, 20.0, 60.0, 40.0, pixels, (tri,))
    return Page(width=100.0, height=80.0, cut=(tri,), mountain=np.zeros((0, 2, 2)),
                valley=np.array([[[35.0, 40.0], [65.0, 40.0]]]), tab_folds=np.zeros((0, 2, 2)),
                texts=(TextItem("12", 50.0, 50.0, 0.0, 4.0, "edge-label"),), faces=(tri[None],),
                face_colors=(np.array([[128, 128, 128]], np.uint8),), images=(image,))


def render(pdf_path, tmp_path, dpi: int = 100) -> np.ndarray:
    if shutil.which("pdftoppm") is None:
        pytest.skip("pdftoppm is not installed (apt-get install poppler-utils)")
    subprocess.run(["pdftoppm", "-png", "-r", str(dpi), "-singlefile", str(pdf_path), str(tmp_path / "page")],
                   check=True)
    return np.asarray(Image.open(tmp_path / "page.png").convert("RGB"), dtype=int)


def test_the_pdf_prints_the_picture_in_place_and_only_inside_its_clip(tmp_path):
    page = picture_page()
    write_pdf([page], tmp_path / "p.pdf")
    img = render(tmp_path / "p.pdf", tmp_path)
    px = lambda x, y: img[int(y / 25.4 * 100), int(x / 25.4 * 100)]  # page mm -> pixel
    assert np.abs(px(40, 55) - RED).max() < 30  # inside the triangle, left of the picture's middle
    assert np.abs(px(60, 55) - BLUE).max() < 30  # right of it
    assert (px(25, 25) > 240).all()  # in the picture's box but outside the clip: paper white
    assert (px(90, 70) > 240).all()
    # the picture is embedded as a JPEG (DCT), not as raw pixels
    assert b"/DCTDecode" in (tmp_path / "p.pdf").read_bytes()


def test_the_print_svg_embeds_the_clipped_picture_and_halos(tmp_path):
    page = picture_page()
    root = ET.fromstring(svg_page_string(page))
    ns = {"s": "http://www.w3.org/2000/svg"}
    (image,) = root.iter("{http://www.w3.org/2000/svg}image")
    assert [float(image.get(k)) for k in ("x", "y", "width", "height")] == [20, 20, 60, 40]
    href = image.get("{http://www.w3.org/1999/xlink}href")
    assert href.startswith("data:image/jpeg;base64,")
    decoded = np.asarray(Image.open(io.BytesIO(base64.b64decode(href.split(",", 1)[1]))).convert("RGB"), dtype=int)
    assert decoded.shape == (200, 300, 3) and np.abs(decoded[100, 50] - RED).max() < 12
    clip_id = image.get("clip-path")[5:-1]
    clip = root.find(f".//s:clipPath[@id='{clip_id}']", ns)
    assert clip is not None and clip.find("s:path", ns).get("d").startswith("M20,60 L80,60 L50,20")
    layers = [g.get("id") for g in root.findall("s:g", ns)]
    assert layers.index("texture") < layers.index("halo") < layers.index("labels") < layers.index("cut")
    (label,) = root.iter("{http://www.w3.org/2000/svg}text")
    assert label.get("stroke") == "#ffffff" and label.get("paint-order") == "stroke"


def test_cut_files_carry_no_picture(tmp_path):
    page = picture_page()
    cut = cut_svg_string(page)
    assert "<image" not in cut and "halo" not in cut and "base64" not in cut
    doc = dxf_document(page)
    assert not [e for e in doc.modelspace() if e.dxftype() in ("IMAGE", "HATCH")]


def test_a_plain_page_has_no_halo():
    page = picture_page()
    from dataclasses import replace

    plain = replace(page, images=(), face_colors=())
    svg = svg_page_string(plain)
    assert "halo" not in svg and "paint-order" not in svg
