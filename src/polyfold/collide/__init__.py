"""Collision tests, shared by unfold (2D), inflate and fold (3D).

    tolerance.py       CONTACT_TOL: faces closer than this (times the model size) touch, not cross
    flat.py            exact 2D triangle overlap of a net's faces, sort-and-sweep broad phase
    triangles.py       the 3D triangle pair test (touching allowed, crossing not)
    sweep.py           the 3D broad phase: `sweep_pairs`, the one plain sort-and-sweep over face
                       boxes (skip rule as data), the fold reports `first_collision` /
                       `all_collisions` on it, and the planners' own hot sweep `sweep_collides`
    self_intersect.py  a mesh's crossing face pairs (`self_intersections`, `crossing_pairs`:
                       faces sharing an edge skipped), through `sweep_pairs`
"""
