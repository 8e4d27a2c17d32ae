"""fabricate/page.py: the Page and TextItem model coerces its inputs and rejects bad ones."""

from __future__ import annotations

import numpy as np
import pytest

from polyfold.fabricate.page import Page, TextItem


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
