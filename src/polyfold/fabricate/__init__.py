"""Fabrication: pieces on paper, in millimetres (the one sheet pipeline of make and unfold --svg).

    pieces.py     nets' pieces in mm (`build_sheet_pieces`): outline, scored creases, cut edges paired for gluing
    tabs.py       the glue tab of a glued edge (`choose_tab`): which side, which trapezoid
    labels.py     glue labels beside cut edges, piece names and their labels
    fit.py        splitting a net until every piece fits a page (`split_to_fit`, `PieceTooLarge`)
    split.py      cutting creases so that the pieces fill fewer pages (`plan_pages`)
    pack.py       packing pieces onto pages by their real outlines (`pack_outlines`, `PageFiller`); shelves
    page.py       the sheet model (`Page`, `TextItem`, `ScaleBar`, `RegistrationMarks`) the writers of
                  formats/ draw; `place`, `page_of`, `footer`, `registration_marks`
    paper.py      sizes on paper: gaps, footer, scale bar, registration marks (light)
    check.py      independent shapely checks of finished pages (`check_pages`)
    sheet.py      one sheet for a whole net, as `polyfold unfold --svg/--png` draws it (`net_sheet`)
"""
