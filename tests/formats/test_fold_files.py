"""formats/fold.py, reading FOLD nets (`fold_tree`): a malformed net is one PolyfoldError of one
line that names the problem (faces, vertices, edges, assignments, parents, pieces, angles)."""

import pytest

from conftest import small_fold
from polyfold.errors import PolyfoldError
from polyfold.formats.fold import fold_tree


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda f: f.update(faces_vertices=[[0, 1, 2, 3], [0, 2, 3]]), "face 0 is not a triangle"),
        (lambda f: f.update(faces_vertices=[[0, 1, 2], [0, 2, 9]]), "face 1 refers to a vertex"),
        (lambda f: f.update(faces_vertices=[[0, 2, 1], [0, 2, 3]]), "face 0 is clockwise"),
        (lambda f: f["edges_assignment"].__setitem__(2, "B"), "face 1 is joined to its parent face 0 by cut edge 2"),
        (lambda f: f.update({"polyfold:faces_parent": [1, 0]}), "cycle"),
        (lambda f: f.update({"polyfold:faces_parent": [-1, 5]}), "face 1 has invalid parent 5"),
        (lambda f: f.update(edges_vertices=[[0, 1], [1, 2], [2, 0], [2, 3]]), "'edges_assignment' must have one entry"),
        (lambda f: f.update(edges_foldAngle=[0, 0, 90, 0, 0]), "edge 2 is a mountain with fold angle 90"),
        (lambda f: f.update({"polyfold:faces_piece": [0, 1]}), "face 1 (piece 1) has its parent face 0 in piece 0"),
    ],
)
def test_malformed_nets_name_the_problem(edit, message):
    fold = small_fold()
    edit(fold)
    with pytest.raises(PolyfoldError, match=message.replace("(", r"\(").replace(")", r"\)")) as info:
        fold_tree(fold)
    assert "\n" not in str(info.value)


def test_side_not_an_edge():
    fold = small_fold()
    fold["edges_vertices"] = [[0, 1], [1, 2], [2, 0], [2, 3], [3, 1]]
    with pytest.raises(PolyfoldError, match="side 3-0 of face 1 is not in 'edges_vertices'"):
        fold_tree(fold)
