"""Fabrication: pieces on paper, in millimetres (the one sheet pipeline of make and unfold --svg).

    layout.py     pieces in mm: cut outline, scored creases, glue tabs, labels; splitting to fit a page
    pack.py       packing pieces onto pages by their real outlines
    page.py       the sheet model (`Page`, `TextItem`) the writers of formats/ draw
"""
