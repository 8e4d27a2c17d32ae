"""formats/png.py: the PNG page writer (read back by hand): piece colours, tabs, cut and crease
colours, aspect kept, the scale bar and registration marks."""

from __future__ import annotations

import math

import numpy as np

from conftest import read_png, square_net, tetra_net
from polyfold.fabricate.page import Page, footer, registration_marks
from polyfold.fabricate.sheet import net_sheet
from polyfold.formats.png import page_image, piece_colors, write_page_png
from polyfold.formats.sheet_style import STYLES, TAB_RGB


def test_png_piece_colours(tmp_path):
    sheet = net_sheet([tetra_net(), square_net(-0.3)], 100.0)
    path = tmp_path / "net.png"
    write_page_png(sheet.page, path, width_px=400)
    img = read_png(path)
    assert np.array_equal(img, page_image(sheet.page, 400))
    s = 400 / sheet.page.width
    assert img.shape == (math.ceil(sheet.page.height * s), 400, 3)  # aspect kept
    colors = piece_colors(2)
    assert tuple(colors[0]) != tuple(colors[1])
    for k, piece in enumerate(sheet.pieces):
        for tri in piece.faces_xy:
            x, y = tri.mean(axis=0) * s
            assert tuple(img[int(y), int(x)]) == tuple(colors[k])
        for tab in piece.tabs:  # tabs light grey
            x, y = tab.mean(axis=0) * s
            assert tuple(img[int(y), int(x)]) == TAB_RGB
    assert tuple(img[0, 0]) == (255, 255, 255) and tuple(img[-1, -1]) == (255, 255, 255)
    # an open edge of the square (a cut without a tab) is black at its middle; mountains are red
    square = sheet.pieces[1]
    x, y = square.faces_xy[0, :2].mean(axis=0) * s
    assert tuple(img[int(y), int(x)]) == (0, 0, 0)
    red = (img[:, :, 0] > 200) & (img[:, :, 1] < 60) & (img[:, :, 2] < 60)
    assert red.sum() > 50
    assert STYLES["mountain"]["rgb"] == (255, 0, 0)


def test_png_valley_blue(tmp_path):
    path = tmp_path / "sq.png"
    sheet = net_sheet([square_net(0.3)], 50.0)
    write_page_png(sheet.page, path, width_px=100)
    img = read_png(path)
    assert img.shape[1] == 100 and img.shape[0] == math.ceil(sheet.page.height * 100 / sheet.page.width)
    blue = (img[:, :, 2] > 200) & (img[:, :, 0] < 60)
    assert blue.sum() > 20


def test_png_scale_bar_and_marks_black():
    page = Page(210.0, 297.0, cut=(), mountain=[], valley=[], tab_folds=[], texts=(),
                scale_bar=footer("x", 10.0, 200.0, 281.0)[1], marks=registration_marks(210.0, 297.0))
    s = 1000 / 210.0
    img = page_image(page, 1000).astype(int)
    black = lambda x, y: img[int(y * s), int(x * s)].sum() == 0
    assert black(12.5, 12.5) and not black(8.0, 12.5)  # inside the filled square, beside it
    assert black(190.0, 10.0) and black(200.0, 20.0) and black(10.0, 280.0) and black(20.0, 287.0)  # L legs
    bar = page.scale_bar.segments()[0]
    assert black(bar[0, 0] + 1, bar[0, 1]) and black(bar[1, 0] - 1, bar[0, 1]) and not black(bar[1, 0] + 2, bar[0, 1])
