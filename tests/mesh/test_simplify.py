"""mesh/simplify.py: --faces (issue 21): a fine mesh reduced to about N faces, closed and manifold
where the input was, the distance to the input measured, the face count of `auto` from the
printed size; and make through it."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from polyfold.errors import PolyfoldError
from polyfold.formats.meshes import load_mesh
from polyfold.mesh.geometry import face_areas
from polyfold.mesh.simplify import (AUTO_ABOVE, AUTO_EDGE_MM, auto_face_count, face_target, hausdorff,
                                    min_angles_deg, simplify)


def _noisy_sphere(tmp_path, level: int, noise: float = 0.01, seed: int = 0):
    sphere = trimesh.creation.icosphere(subdivisions=level)
    sphere.vertices *= 1.0 + noise * np.random.default_rng(seed).standard_normal((len(sphere.vertices), 1))
    path = tmp_path / f"sphere-{level}.obj"
    sphere.export(path)
    return load_mesh(path)


def test_a_fine_sphere_comes_down_to_about_n_faces_closed_and_near(tmp_path):
    loaded = _noisy_sphere(tmp_path, 5)  # 20,480 faces
    done = simplify(loaded, 600)
    out = done.loaded.mesh
    assert done.faces_before == 20480 and abs(done.faces_after - 600) <= 6 and out.n_faces == done.faces_after
    assert len(done.loaded.components) == 1 and not out.topology.boundary.any()  # closed, one piece
    # still the sphere: every simplified vertex within a few percent of the unit radius (the
    # input's noise is 1 %), and the measured distance says so too
    r = np.linalg.norm(out.vertices, axis=1)
    assert np.all(np.abs(r - 1.0) < 0.05)
    assert 0.0 < done.hausdorff < 0.03
    assert done.min_angle_deg == pytest.approx(float(min_angles_deg(out.vertices, out.faces).min()))


def test_a_mesh_already_small_enough_is_left_alone(models_dir):
    loaded = load_mesh(models_dir / "bunny-128.obj")
    done = simplify(loaded, 500)
    assert done.loaded is loaded and done.faces_after == done.faces_before == 128 and done.hausdorff == 0.0


def test_hausdorff_sees_a_moved_surface(tmp_path):
    a = _noisy_sphere(tmp_path, 3, noise=0.0).mesh
    moved = type(a)(a.vertices * 1.1, a.faces)
    assert hausdorff(a, moved) == pytest.approx(0.1, rel=0.05)  # radius 1 -> 1.1
    assert hausdorff(a, a) < 1e-12


def test_auto_count_gives_faces_of_the_stated_printed_size(tmp_path):
    mesh = _noisy_sphere(tmp_path, 5, noise=0.0).mesh
    size = 150.0
    n = auto_face_count(mesh, size)
    scale = size / float(np.max(np.ptp(mesh.vertices, axis=0)))
    mean_area = float(face_areas(mesh.vertices, mesh.faces).sum()) * scale ** 2 / n
    assert mean_area == pytest.approx(math.sqrt(3) / 4 * AUTO_EDGE_MM ** 2, rel=0.01)
    assert face_target("auto", mesh, size) == n and face_target("none", mesh, size) is None
    assert face_target("700", mesh, size) == 700 and face_target("50000", mesh, size) is None


def test_auto_leaves_meshes_up_to_a_few_thousand_faces(models_dir):
    mesh = load_mesh(models_dir / "bumpy-528.obj").mesh
    assert mesh.n_faces <= AUTO_ABOVE and face_target("auto", mesh, 10_000.0) is None


@pytest.mark.parametrize("spec", ["3", "-5", "many", "1e3", ""])
def test_a_bad_face_count_is_one_line(spec, models_dir):
    mesh = load_mesh(models_dir / "bunny-128.obj").mesh
    with pytest.raises(PolyfoldError, match="--faces"):
        face_target(spec, mesh, 150.0)
