"""pipeline/options.py: paper sizes by name or as WxH in mm / in."""

from __future__ import annotations

import pytest

from polyfold.pipeline.options import paper_size


def test_paper_sizes():
    assert paper_size("A4") == (210.0, 297.0)
    assert paper_size("12x12in") == pytest.approx((304.8, 304.8))
    assert paper_size("200x300mm") == (200.0, 300.0)
    assert paper_size("8.5x11in") == pytest.approx((215.9, 279.4))
    with pytest.raises(Exception, match="unknown paper"):
        paper_size("b5")
