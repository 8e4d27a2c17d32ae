"""pipeline/options.py: paper sizes by name or as WxH in mm / in; --marks (and the packing box
it gives, pipeline/sheets.py)."""

from __future__ import annotations

import pytest

from polyfold.errors import PolyfoldError
from polyfold.fabricate.paper import FOOTER_MM, MARK_CLEAR_MM
from polyfold.pipeline.options import MakeOptions, check_options, paper_size
from polyfold.pipeline.sheets import pack_box


def test_paper_sizes():
    assert paper_size("A4") == (210.0, 297.0)
    assert paper_size("12x12in") == pytest.approx((304.8, 304.8))
    assert paper_size("200x300mm") == (200.0, 300.0)
    assert paper_size("8.5x11in") == pytest.approx((215.9, 279.4))
    with pytest.raises(Exception, match="unknown paper"):
        paper_size("b5")


def test_marks_need_room_and_grow_the_near_margins():
    assert check_options(MakeOptions(marks=True)) == (210.0, 297.0)
    with pytest.raises(PolyfoldError, match="--marks"):
        check_options(MakeOptions(marks=True, paper="50x80mm", margin=5))  # fine without marks
    check_options(MakeOptions(paper="50x80mm", margin=5))
    # pieces are packed below and right of the marked corners, the far margins stay
    assert pack_box(210.0, 297.0, MakeOptions(marks=True)) == (MARK_CLEAR_MM, MARK_CLEAR_MM, 200.0, 297.0 - 10 - FOOTER_MM)
    assert pack_box(210.0, 297.0, MakeOptions()) == (10.0, 10.0, 200.0, 297.0 - 10 - FOOTER_MM)
