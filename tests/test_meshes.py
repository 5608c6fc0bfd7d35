"""Mesh loading through trimesh: every advertised format, normals, tangents, components."""

import numpy as np
import pytest
import trimesh

from envstudio.errors import InputFileError
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


def test_a_draco_compressed_glb_loads_the_same_surface(tmp_path):
    """KHR_draco_mesh_compression (web assets) decodes through DracoPy: not placeholder zeros."""
    original = load_mesh(BUNNY)
    path = tmp_path / "bunny.glb"
    scene = trimesh.Scene(trimesh.Trimesh(original.positions, original.indices))
    path.write_bytes(trimesh.exchange.gltf.export_glb(scene, extension_draco=True))
    assert b"KHR_draco_mesh_compression" in path.read_bytes()
    loaded = load_mesh(path)
    assert loaded.triangle_count == original.triangle_count
    np.testing.assert_allclose(loaded.bounds(), original.bounds(), atol=1e-3)  # 14-bit positions


BAD_MESHES = {
    "nan": (
        "v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\n",
        ["1 vertices are NaN", "1 of 2 faces"],
    ),
    "inf": ("v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n", ["NaN or Inf", "1 of 1 faces"]),
    "flat": (
        "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
        ["every triangle has no area", "1 degenerate"],
    ),
    "point": ("v 1 1 1\nv 1 1 1\nv 1 1 1\nf 1 2 3\n", ["all its vertices coincide"]),
    "huge": ("v 0 0 0\nv 1e30 0 0\nv 0 1 0\nf 1 2 3\n", ["1e+30", "out of range"]),
}


@pytest.mark.parametrize("name", list(BAD_MESHES))
def test_a_mesh_without_a_usable_surface_is_one_line(tmp_path, name):
    text, fragments = BAD_MESHES[name]
    path = tmp_path / f"{name}.obj"
    path.write_text(text)
    with pytest.raises(InputFileError) as info:
        load_mesh(path)
    message = str(info.value)
    assert "\n" not in message and message.startswith(f"{path}: ")
    for fragment in fragments:
        assert fragment in message, message


def test_degenerate_faces_are_dropped_and_counted(tmp_path, capsys):
    path = tmp_path / "some.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n")
    mesh = load_mesh(path)
    assert mesh.triangle_count == 1
    assert "1 of 2 faces have no area, dropped" in capsys.readouterr().err
