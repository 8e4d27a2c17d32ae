"""The contact tolerance shared by every collision test (light: no numba, the CLI reads it).

Faces closer than CONTACT_TOL times the model's bounding-box diagonal touch rather than cross
(ALGORITHMS.md 6.2); `--contact-tol` changes it per run, e.g. to the paper's thickness.
"""

CONTACT_TOL = 1e-7
