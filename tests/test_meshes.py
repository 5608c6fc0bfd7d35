"""Mesh loading through trimesh: every advertised format, normals, tangents, components."""

import numpy as np
import pytest
import trimesh

from envstudio.io.meshes import load_mesh
from envstudio.resources import asset_root

BUNNY = asset_root() / "mesh" / "bunny.ply"


@pytest.mark.parametrize("suffix", [".obj", ".stl", ".off", ".glb"])
def test_every_format_loads_the_same_surface(tmp_path, suffix):
    original = load_mesh(BUNNY)
    path = tmp_path / f"bunny{suffix}"
    trimesh.Trimesh(original.positions, original.indices).export(path)
    loaded = load_mesh(path)
    assert loaded.triangle_count == original.triangle_count
    np.testing.assert_allclose(loaded.bounds(), original.bounds(), atol=1e-5)
    # normals exist (computed where the format has none) and are unit length
    np.testing.assert_allclose(np.linalg.norm(loaded.normals, axis=1), 1.0, atol=1e-5)


def test_normals_point_outwards_and_tangents_are_orthogonal():
    mesh = load_mesh(BUNNY).fitted(1.0)
    centre = mesh.positions.mean(axis=0)
    outward = np.sum(mesh.normals * (mesh.positions - centre), axis=1) > 0
    assert outward.mean() > 0.9, "vertex normals of a closed mesh face out"
    tangents = mesh.tangents()
    np.testing.assert_allclose(np.linalg.norm(tangents, axis=1), 1.0, atol=1e-5)
    assert np.abs(np.sum(tangents * mesh.normals, axis=1)).max() < 1e-5


def test_components_split_the_teapot_lid_from_the_body():
    teapot = asset_root() / "mesh" / "teapot.obj"
    body, lid = load_mesh(teapot, [0, 1, 2]), load_mesh(teapot, [3])
    assert body.triangle_count + lid.triangle_count == load_mesh(teapot).triangle_count
    assert lid.bounds()[0, 1] > body.bounds()[0, 1] + 5.0, "the lid sits on top"
