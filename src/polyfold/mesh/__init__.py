"""Load & check, the first stage: the `Mesh` record and everything every other stage computes on it.

    mesh.py       `Mesh` (vertices, CCW faces, source face of each triangle) and its edge `Topology`
    geometry.py   normals, areas, corner and fold angles (the one sign convention), angle sums, convex
                  hull planes, concavity
    repair.py     checks and repairs of a loaded mesh (`LoadedMesh`), the `info` report
    kernels.py    numba: face normals, fold-angle vectors, texture sampling (imported where used:
                  loading and checking a mesh, `polyfold info`, compiles and loads nothing)
    hull_kernels.py numba: an incremental 3D convex hull and the depth of points below it (a mesh's
                  or a part's concavity)

Files are read by `formats/meshes.py` (`load_mesh`), which calls `repair.repair`.
"""
