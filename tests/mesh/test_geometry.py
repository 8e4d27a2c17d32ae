"""mesh/geometry.py: `merged_edges`, the edges inside flat regions (coplanar faces, or the triangles
of one input polygon) that every net keeps as creases."""

from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import single_component, subdivided_box
from polyfold.formats.meshes import load_mesh
from polyfold.mesh.geometry import FLAT_REGION_RAD, merged_edges
from polyfold.mesh.mesh import Mesh


def test_cube_merges_the_diagonal_of_every_square(models_dir):
    mesh = single_component(models_dir, "cube-12")
    merged = merged_edges(mesh)
    assert merged.sum() == 6
    f0, f1 = mesh.topology.edge_faces[merged].T
    # the two triangles of one square: the same normal; every triangle is in exactly one square
    np.testing.assert_allclose(mesh.face_normals[f0], mesh.face_normals[f1], atol=1e-12)
    assert sorted(np.concatenate([f0, f1]).tolist()) == list(range(12))
    # the 12 cube edges are right angles, none merged
    assert np.allclose(np.abs(mesh.fold_angles[~merged]), math.pi / 2)


def test_quads_of_the_input_file_are_merged(models_dir):
    loaded = load_mesh(models_dir / "bad" / "quad-cube.obj")
    (mesh,) = loaded.components
    merged = merged_edges(mesh)
    src = mesh.face_source[mesh.topology.edge_faces[merged]]
    assert merged.sum() == 6 and (src[:, 0] == src[:, 1]).all()
    assert sorted(src[:, 0].tolist()) == list(range(6))


def test_triangles_of_one_input_polygon_are_merged_even_when_folded():
    # a tetrahedron whose faces 0 and 1 claim to be one polygon of the input file (a non-planar
    # quad, triangulated): their edge is merged although it folds by more than a radian
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    mesh = Mesh(v, f, face_source=np.array([0, 0, 1, 2]))
    merged = merged_edges(mesh)
    (e,) = np.flatnonzero(merged)
    assert sorted(mesh.topology.edge_faces[e].tolist()) == [0, 1]
    assert abs(mesh.fold_angles[e]) > 1.0
    assert not merged_edges(Mesh(v, f)).any()  # four input triangles: nothing merged


@pytest.mark.parametrize("factor, want", [(0.5, True), (2.0, False)])
def test_coplanar_means_below_the_flat_region_tolerance(factor, want):
    # two triangles hinged on the x axis, the second tilted by factor * FLAT_REGION_RAD
    t = factor * FLAT_REGION_RAD
    v = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, -math.cos(t), math.sin(t)]])
    mesh = Mesh(v, np.array([[0, 1, 2], [1, 0, 3]]))
    merged = merged_edges(mesh)
    hinge = np.flatnonzero(mesh.topology.interior)
    assert len(hinge) == 1 and math.isclose(abs(mesh.fold_angles[hinge[0]]), t, rel_tol=1e-6)
    assert merged[hinge[0]] == want
    assert not merged[mesh.topology.boundary].any()  # boundary edges: never


def test_subdivided_box_merges_everything_but_the_box_edges():
    mesh = subdivided_box(2)
    merged = merged_edges(mesh)
    f0, f1 = mesh.topology.edge_faces.T
    same_side = np.isclose((mesh.face_normals[f0] * mesh.face_normals[f1]).sum(axis=1), 1.0)
    assert np.array_equal(merged, same_side)
    # the 12 box edges, each cut into 4 by the two subdivisions, are the only edges left
    assert (~merged).sum() == 12 * 4
