"""Convex approximation: every part of a segmentation replaced by a closed convex polyhedron, the
polyhedra pairwise interior-disjoint (issue 24).

    hulls.py    `approximate_hulls` -> `HullApproximation`: part hulls as halfspaces, the clipping
                of overlapping pairs (plane choice), facets made whole and small ones dropped
    error.py    Hausdorff distances and volumes per part; the disjointness checks (an LP per pair,
                scipy only; manifold3d's boolean intersection volumes, the `test` extra)
    kernels.py  numba: the volume of a closed convex surface beyond a plane
"""
