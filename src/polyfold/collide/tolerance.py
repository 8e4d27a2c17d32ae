"""The contact tolerance and paper thickness shared by every collision test (light: no numba, the
CLI reads it).

Faces closer than CONTACT_TOL times the model's bounding-box diagonal touch rather than cross
(ALGORITHMS.md 6.2); `--contact-tol` changes it per run, e.g. to the paper's thickness.
"""

CONTACT_TOL = 1e-7
THICKNESS_MM = 0.2  # make's default paper thickness (printer paper 0.1, card 0.3-0.5)
THICKNESS_REL = 1e-3  # fold / unfold --fold: the thickness as a fraction of the model size (0.15 mm at 150 mm)
EXEMPT_REACH = 10.0  # faces sharing a point may come within the thickness this many thicknesses from it
