"""polyfold: verified paper nets (edge unfoldings) of triangle meshes.

Pipeline (one module per stage): `io` (load & check) -> `unfold` -> `foldfile` (FOLD) -> `sheet`
(SVG/PNG). Heavy modules are imported lazily so the CLI starts fast.
"""

__version__ = "0.1.0"
