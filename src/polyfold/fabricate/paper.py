"""Sizes on paper shared by the sheet code and the front ends, in mm (light: the command line
reads them at start-up)."""

GAP_MM = 3.0  # minimum distance between pieces on a page, tabs included (room for scissors)
FOOTER_MM = 6.0  # strip at the bottom of the printable area for the footer line
FOOTER_FONT_MM = 2.5  # the footer line's font size
