"""guide/motion.py: when creases reach their goal along a path, the stages they close in, and
when a seam's two faces stop moving relative to each other; and guide/order.py's opening rims
on a box built face by face."""

from __future__ import annotations

import numpy as np

from polyfold.guide.motion import crease_done_frames, fold_stages, seam_meet_frame
from polyfold.guide.order import Seam, opening_rims, plan_build
from polyfold.mesh.mesh import Mesh


def test_done_frames_and_stages() -> None:
    # 4 edges: a cut (never moves), one crease closing in the first move, one in the second, one
    # that reaches its goal early, leaves it and comes back last
    frames = np.array([[0, 0, 0, 0], [0, 1.0, 0, 0.5], [0, 1.0, 2.0, 0.2], [0, 1.0, 2.0, 0.5]], dtype=float)
    done = crease_done_frames(frames)
    assert done.tolist() == [0, 1, 2, 3]
    stages = fold_stages(frames)
    assert [(s.frame, s.creases) for s in stages] == [(1, (1,)), (2, (2,)), (3, (3,))]
    merged = fold_stages(frames, max_stages=2)
    assert [(s.frame, s.creases) for s in merged] == [(2, (1, 2)), (3, (3,))]
    straight = np.array([[0, 0, 0], [1.0, -0.5, 0]])
    assert [(s.frame, s.creases) for s in fold_stages(straight)] == [(1, (0, 1))]


def test_seam_meets_when_the_creases_between_its_faces_are_done() -> None:
    # a chain of faces 0 - 1 - 2 - 3 (face f's crease is edge f - 1), and a branch 4 off face 1
    parent = np.array([-1, 0, 1, 2, 1])
    crease = np.array([-1, 0, 1, 2, 3])
    done = np.array([1, 4, 2, 3])
    assert seam_meet_frame(parent, crease, done, 0, 3) == 4  # creases 0, 1, 2
    assert seam_meet_frame(parent, crease, done, 3, 0) == 4
    assert seam_meet_frame(parent, crease, done, 2, 3) == 2  # crease 2 only
    assert seam_meet_frame(parent, crease, done, 3, 4) == 4  # 2, 1 up to face 1, then 3 down to 4
    assert seam_meet_frame(parent, crease, done, 0, 4) == 3  # creases 0 and 3
    assert seam_meet_frame(parent, crease, done, 4, 4) == 0


def _box() -> Mesh:
    v = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    faces = [t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))]
    return Mesh(v, np.array(faces))


def test_a_box_closes_last_around_its_lid() -> None:
    """Six pieces, one per side of a 100 mm box (two triangles each): every seam between sides
    is glued once both sides are in, the openings shrink as the box closes, the last seam closes
    it (rim 0) and the seams glued when no finger fits any more are marked hard."""
    box = _box()
    piece_faces = [np.array([2 * k, 2 * k + 1]) for k in range(6)]
    topo = box.topology
    face_piece = np.repeat(np.arange(6), 2)
    seams = []
    for e, (f0, f1) in enumerate(topo.edge_faces):
        if face_piece[f0] != face_piece[f1]:
            u, v = (int(x) for x in topo.edges[e])
            seams.append(Seam(pieces=(int(face_piece[f0]), int(face_piece[f1])), faces=(int(f0), int(f1)),
                              mesh_edge=(u, v), edge=e, length_mm=100.0, run=str(len(seams) + 1)))
    assert len(seams) == 12
    plan = plan_build(box, [0] * 6, piece_faces, seams, mm_per_unit=100.0, max_seams=4)
    assert sorted(plan.piece_order) == list(range(6))
    glued = [k for st in plan.steps for k in st.seams]
    assert sorted(glued) == list(range(12))
    rims = plan.opening_mm[glued]
    assert rims[-1] == 0.0  # the last seam closes the box
    assert rims[0] > rims[-2] > 0.0
    hard = {k for st in plan.steps for k in st.hard}
    assert hard == {k for k in glued if plan.opening_mm[k] < 90.0} and glued[-1] in hard
    # the last piece is the lid: its seams are the last glued
    lid_piece = plan.piece_order[-1]
    last4 = glued[-4:]
    assert all(lid_piece in seams[k].pieces for k in last4)
    # by hand: sides 0 (x = 0) and 2 (y = 0) placed and glued along their common edge leave one
    # hole, the other three edges of each square: 600 mm
    k = next(i for i, sm in enumerate(seams) if set(sm.pieces) == {0, 2})
    rim = opening_rims(box, piece_faces, seams, [dict(placed=(0, 2), seams=(k,))], 100.0)
    assert rim[k] == 600.0
