"""fabricate/page.py: the Page and TextItem model coerces its inputs and rejects bad ones; the
footer's scale bar and the registration marks."""

from __future__ import annotations

import numpy as np
import pytest

from polyfold.fabricate.page import Page, TextItem, footer, registration_marks
from polyfold.fabricate.paper import FOOTER_MM, MARK_INSET_MM, MARK_LEG_MM, MARK_SQUARE_MM, SCALE_BAR_MM


def test_page_coerces_and_validates() -> None:
    p = Page(50, 40, cut=([[0, 0], [10, 0], [10, 10], [0, 0]],), mountain=[], valley=np.zeros((0, 2, 2)),
             tab_folds=[[[0, 0], [1, 1]]], texts=())
    assert p.cut[0].shape == (3, 2) and p.cut[0].dtype == np.float64  # repeated closing point dropped
    assert p.mountain.shape == (0, 2, 2) and p.tab_folds.shape == (1, 2, 2)
    with pytest.raises(ValueError):
        Page(50, 40, cut=([[0, 0], [1, 1]],), mountain=[], valley=[], tab_folds=[], texts=())
    with pytest.raises(ValueError):
        Page(50, 40, cut=(), mountain=[[[0, 0], [np.nan, 1]]], valley=[], tab_folds=[], texts=())
    with pytest.raises(ValueError):
        Page(0, 40, cut=(), mountain=[], valley=[], tab_folds=[], texts=())
    with pytest.raises(ValueError):
        TextItem("x", 0, 0, 0, 2, "caption")


def test_footer_puts_the_scale_bar_right_and_the_text_left_of_it() -> None:
    text, bar = footer("bunny - sheet 1/3", 10.0, 200.0, 281.0)
    assert bar is not None and bar.length == SCALE_BAR_MM and bar.x + bar.length == 200.0
    segs = bar.segments()
    assert np.hypot(*(segs[0, 1] - segs[0, 0])) == SCALE_BAR_MM  # the bar itself
    assert (segs[1:, :, 0] == [[bar.x, bar.x], [200.0, 200.0]]).all()  # ticks at both ends
    assert 281.0 < segs[..., 1].min() and segs[..., 1].max() <= 281.0 + FOOTER_MM  # inside the strip
    assert bar.label.text == "50 mm" and bar.label.x == bar.x + bar.length / 2
    assert bar.label.y + bar.label.size / 2 < segs[1:, :, 1].min()  # the label sits above the ticks
    assert text.kind == "title" and text.x == (10.0 + bar.x - 3.0) / 2 and text.y == 281.0 + FOOTER_MM / 2
    # narrow strips get a shorter bar, tiny ones none
    assert footer("x", 0.0, 60.0, 0.0)[1].length == 20.0
    _, none = footer("x", 0.0, 19.0, 0.0)
    assert none is None


def test_registration_marks_are_silhouette_type_1() -> None:
    m = registration_marks(210.0, 297.0)
    assert m.square.min(axis=0).tolist() == [MARK_INSET_MM] * 2
    assert (m.square.max(axis=0) - m.square.min(axis=0)).tolist() == [MARK_SQUARE_MM] * 2
    top_right, bottom_left = m.corners
    assert top_right[1].tolist() == [210.0 - MARK_INSET_MM, MARK_INSET_MM]
    assert bottom_left[1].tolist() == [MARK_INSET_MM, 297.0 - MARK_INSET_MM]
    for c in m.corners:
        assert sorted(np.hypot(*(c[[0, 2]] - c[1]).T).tolist()) == [MARK_LEG_MM] * 2
    page = Page(210, 297, cut=(), mountain=[], valley=[], tab_folds=[], texts=(), marks=m,
                scale_bar=footer("x", 10, 200, 281)[1])
    assert page.marks is m
    with pytest.raises(ValueError):
        Page(50, 40, cut=(), mountain=[], valley=[], tab_folds=[], texts=(), marks="square")
