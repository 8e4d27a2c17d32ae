"""unfold/problem.py: the faces' local frames keep their side lengths."""

import numpy as np

from conftest import single_component, sorted_side_lengths
from polyfold.unfold.problem import local_frames


def test_local_frames_keep_side_lengths(models_dir):
    mesh = single_component(models_dir, "bunny-128")
    loc = local_frames(mesh.vertices, mesh.faces)
    np.testing.assert_allclose(sorted_side_lengths(loc), sorted_side_lengths(mesh.vertices[mesh.faces]), rtol=1e-12)
    assert (loc[:, 2, 1] > 0).all()
