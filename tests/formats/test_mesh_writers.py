"""The mesh writer table: every suffix writes a file the readers load back as the same mesh."""

from __future__ import annotations

import numpy as np
import pytest

from polyfold.errors import PolyfoldError
from polyfold.formats.meshes import WRITERS, load_mesh, write_mesh


@pytest.mark.parametrize("suffix", sorted(WRITERS))
def test_written_mesh_loads_back(models_dir, tmp_path, suffix):
    mesh = load_mesh(models_dir / "bunny-128.obj").mesh
    colors = np.tile(np.array([[200, 30, 30]], np.uint8), (mesh.n_faces, 1))
    path = tmp_path / f"bunny{suffix}"
    write_mesh(path, mesh.vertices, mesh.faces, face_colors=colors, header="a bunny")
    back = load_mesh(path).mesh
    assert back.n_faces == mesh.n_faces
    # same surface: the same triangles as point triples (GLB stores its own vertex order)
    key = lambda m: np.sort(np.round(m.vertices[m.faces], 5).reshape(len(m.faces), -1), axis=0)  # noqa: E731
    assert np.allclose(np.sort(key(back), axis=0), np.sort(key(mesh), axis=0), atol=1e-5)


def test_unknown_suffix_is_one_clear_error(tmp_path):
    with pytest.raises(PolyfoldError, match="cannot write '.xyz' meshes"):
        write_mesh(tmp_path / "m.xyz", np.zeros((3, 3)), np.array([[0, 1, 2]]))
    assert not list(tmp_path.iterdir())
