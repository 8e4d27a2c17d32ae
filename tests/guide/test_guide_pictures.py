"""guide/pictures.py and its rasteriser: triangles drawn in batches, in any order, over one another
(`raster.triangle_index`'s ids and into) give the picture drawn at once, ties to the smaller id;
the step pictures' growing sets of faces drawn once for all (`growing_face_ids`) give each set's
`draw_faces`, pixel for pixel."""

from __future__ import annotations

import numpy as np

from polyfold.formats.meshes import load_mesh
from polyfold.formats.raster import triangle_index
from polyfold.guide import pictures as P


def test_triangles_drawn_in_batches_in_any_order_are_the_triangles_drawn_at_once():
    rng = np.random.default_rng(5)
    tris = rng.uniform(0, 60, size=(300, 3, 2))
    depth = rng.uniform(0, 10, size=(300, 3))
    # ties: copies of some triangles at the same depths (the smaller index wins, as drawn first)
    tris[250:], depth[250:] = tris[:50], depth[:50]
    at_once = triangle_index((50, 64), tris, depth)
    order = rng.permutation(300)
    drawn = None
    for batch in np.array_split(order, 7):
        drawn = triangle_index((50, 64), tris[batch], depth[batch], batch, into=drawn)
    assert np.array_equal(drawn[0], at_once[0]) and np.array_equal(drawn[1], at_once[1])
    assert not np.isin(at_once[0], np.arange(250, 300)).any()  # (every copy lost its tie)


def test_growing_sets_of_faces_are_drawn_as_each_set_alone(models_dir):
    mesh = load_mesh(models_dir / "bunny-348.obj").mesh
    tris = mesh.vertices[mesh.faces]
    rng = np.random.default_rng(2)
    order = rng.permutation(mesh.n_faces)
    cuts = np.sort(rng.choice(np.arange(1, mesh.n_faces), 5, replace=False))
    placed = [np.sort(order[:c]) for c in cuts] + [np.arange(mesh.n_faces)]  # the last: every face, no ghost
    palette = P.piece_palette(mesh.n_faces)
    for rotation in P.corner_rotations(mesh.vertices)[:3]:
        cam = P.fit_camera(tris, rotation, 300, 225)
        for faces, (ids, zbuf, ghost) in zip(placed, P.growing_face_ids(cam, tris, placed), strict=True):
            rest = np.setdiff1d(np.arange(mesh.n_faces), faces)
            want_img, want_ids, want_zbuf = P.draw_faces(cam, tris[faces], palette[faces], None, tris[rest])
            assert np.array_equal(ids, want_ids) and np.array_equal(zbuf, want_zbuf)
            assert np.array_equal(P.paint_faces(cam, tris[faces], palette[faces], None, ids, ghost), want_img)
            assert ghost.any() == (len(rest) > 0)
