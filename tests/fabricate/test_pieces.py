"""fabricate/pieces.py: a drawing's glue tabs chosen ahead in a forked process (`_glue`, for the
later pairs, as if the earlier ones were not there, taken where their memo key is the pair's) are
the tabs chosen here, one pair after another."""

from __future__ import annotations

import numpy as np

import polyfold.fabricate.pieces as pieces_module
from conftest import fitted_parts
from polyfold.fabricate.pieces import build_sheet_pieces
from polyfold.pipeline.sheets import part_piece_inputs
from polyfold.processes import can_fork, usable_cores


def _drawn(inputs, scale, monkeypatch, ahead_pairs: int, memo: dict | None):
    glued = []
    glue = pieces_module._glue

    def keep(*args, **kwargs):
        out = glue(*args, **kwargs)
        glued.append(out[0])
        return out

    monkeypatch.setattr(pieces_module, "AHEAD_PAIRS", ahead_pairs)
    monkeypatch.setattr(pieces_module, "_glue", keep)
    drawing = build_sheet_pieces(inputs, scale, memo=memo)
    monkeypatch.undo()
    return drawing, glued[0]


def test_tabs_chosen_ahead_in_a_forked_process_are_the_tabs_chosen_here(models_dir, monkeypatch):
    mesh, _opts, scale, _w, _h, fitted = fitted_parts(models_dir, "fish-472")
    inputs = part_piece_inputs(mesh, fitted)
    (here, glue_here, stats_here), alone = _drawn(inputs, scale, monkeypatch, 10**9, None)
    memo: dict = {}
    (ahead, glue_ahead, stats_ahead), split = _drawn(inputs, scale, monkeypatch, 1, memo)
    assert alone.ahead_tabs == 0
    if can_fork() and usable_cores() > 1:
        # most of the later half came from the forked process; some had to be chosen here again
        later = len(glue_here) - int(pieces_module.AHEAD_SHARE * len(glue_here))
        assert later // 2 < split.ahead_tabs < later
        # a first drawing: every tab new; the memo holds too those chosen there for keys not met here
        assert split.new_tabs == len(glue_here) < len(memo["tabs"])
    assert glue_ahead == glue_here and stats_ahead == stats_here
    for p, q in zip(ahead, here, strict=True):
        assert len(p.tabs) == len(q.tabs) and all(np.array_equal(a, b) for a, b in zip(p.tabs, q.tabs))
        assert np.array_equal(p.tab_folds, q.tab_folds) and p.texts == q.texts
        assert p.outline.equals_exact(q.outline, 0.0) and p.footprint.equals_exact(q.footprint, 0.0)
