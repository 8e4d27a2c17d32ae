"""unfold/tabroom.py: edge swaps open the narrow notches of a net (corners too narrow for a glue
tab) while the net stays one overlap-free piece; the result is re-checked by the independent
tests/fold_checker.py against the mesh file."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from conftest import assert_flat_regions_whole
from fold_checker import check_fold
from polyfold.formats.fold import net_to_fold, write_fold
from polyfold.formats.meshes import load_mesh
from polyfold.mesh.geometry import corner_angles
from polyfold.mesh.mesh import Mesh
from polyfold.unfold.search import unfold
from polyfold.unfold.tabroom import NOTCH_DEG, open_notches


def _free_angles(net) -> list[float]:
    """Free angle (degrees) of every outline corner of a single-piece net, counted here again: at
    each vertex, 360 minus the face angles held between a cut edge and the next one."""
    mesh = net.mesh
    crease = net.crease_mask
    angles = corner_angles(mesh.vertices, mesh.faces)
    topo = mesh.topology
    out = []
    for v in range(mesh.n_vertices):
        fan = [(f, int(np.flatnonzero(mesh.faces[f] == v)[0])) for f in np.flatnonzero((mesh.faces == v).any(axis=1))]
        cut_in = [(f, j) for f, j in fan if not crease[topo.face_edges[f, (j + 2) % 3]]]
        for f, j in cut_in:  # turn around v through creases to the next cut edge
            held = 0.0
            for _ in range(len(fan)):
                held += angles[f, j]
                e = topo.face_edges[f, j]
                if not crease[e]:
                    break
                a, b = topo.edge_faces[e]
                f = b if a == f else a
                j = int(np.flatnonzero(mesh.faces[f] == v)[0])
            out.append(360.0 - math.degrees(held))
    return out


@pytest.mark.parametrize("name", ["fish-472", "bunny-128"])
def test_open_notches_keeps_one_overlap_free_piece_with_fewer_notches(models_dir, tmp_path, name):
    path = models_dir / f"{name}.obj"
    mesh = load_mesh(path).mesh
    net, _ = unfold(mesh, seed=1, time_limit=20, max_pieces=1)
    opened, stats = open_notches(net)
    narrow_before = sum(a < NOTCH_DEG for a in _free_angles(net))
    narrow_after = sum(a < NOTCH_DEG for a in _free_angles(opened))
    assert stats.notches_before == narrow_before and stats.notches_after == narrow_after
    assert stats.swaps > 0 and narrow_after < 0.5 * narrow_before
    assert opened.n_pieces == 1 and np.count_nonzero(opened.crease_mask) == mesh.n_faces - 1
    fold = tmp_path / "opened.fold"
    write_fold(fold, net_to_fold([opened]))
    report = check_fold(str(fold), str(path))
    assert report.ok, report.problems[:3]


def test_kept_creases_are_never_cut(models_dir):
    mesh = load_mesh(models_dir / "bunny-128.obj").mesh
    net, _ = unfold(mesh, seed=1, time_limit=20, max_pieces=1)
    keep = net.crease_mask.copy()
    opened, stats = open_notches(net, keep=keep)
    assert stats.swaps == 0 and np.array_equal(opened.crease_mask, net.crease_mask)


@pytest.mark.parametrize("name", ["fish-472", "l-prism-div-44", "cylinder"])
def test_flat_regions_are_never_cut(models_dir, name):
    # issue 18: the merged edges of flat regions stay creases whatever `keep` says
    if name == "cylinder":
        cyl = trimesh.creation.cylinder(radius=0.5, height=1.2, sections=24)
        mesh = Mesh(cyl.vertices, cyl.faces)
    else:
        mesh = load_mesh(models_dir / f"{name}.obj").mesh
    net, _ = unfold(mesh, seed=1, time_limit=20, max_pieces=1)
    opened, stats = open_notches(net)
    assert opened.n_pieces == 1
    assert_flat_regions_whole(opened)
