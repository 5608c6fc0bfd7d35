"""Scene files: the Banks material keys (sharpness, tangent field, model) and the brushed scene."""

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

from envstudio.engine.session import material_values
from envstudio.errors import InputFileError
from envstudio.io.scene_file import MODELS, load_scene, shipped_scenes
from envstudio.scene.tangents import TangentField

SCENE = """[environment]
file = "hdr/studio.exr"
[[object]]
primitive = "sphere"
[object.material]
{material}
"""


def write_scene(tmp_path, material: str):
    path = tmp_path / "scene.toml"
    path.write_text(SCENE.format(material=material))
    return path


def test_brushed_scene_is_a_banks_teapot_around_y():
    assert "brushed" in shipped_scenes()
    scene = load_scene("brushed")
    (teapot,) = scene.reflectors()
    assert teapot.material.tangent_field == TangentField("axis", "y")
    assert teapot.material.model == "banks"
    values = material_values(scene)
    assert values["model"] == "banks"
    assert values["sharpness"] == pytest.approx(0.9)
    assert (values["tangent_field"], values["tangent_axis"]) == ("axis", "y")


def test_material_keys_are_read_and_default(tmp_path):
    material = load_scene(write_scene(tmp_path, "")).reflectors()[0].material
    assert material.sharpness == pytest.approx(0.9)
    assert material.tangent_field == TangentField()
    assert material.model is None
    assert "model" not in material_values(load_scene("studio"))


@pytest.mark.parametrize(
    ("text", "sharpness", "field"),
    [
        (
            'sharpness = 0.5\ntangent_field = "direction"\ntangent_axis = "x"',
            0.5,
            ("direction", "x"),
        ),
        ('sharpness = 0\ntangent_field = "radial"\ntangent_axis = "z"', 0.0, ("radial", "z")),
        ('sharpness = 0.99\ntangent_field = "uv"', 0.99, ("uv", "y")),
    ],
)
def test_tangent_fields(tmp_path, text, sharpness, field):
    material = load_scene(write_scene(tmp_path, text)).reflectors()[0].material
    assert material.sharpness == pytest.approx(sharpness)
    assert material.tangent_field == TangentField(*field)


def test_models_match_the_reference():
    from envstudio.methods.reference.method import MODELS as REFERENCE_MODELS

    assert MODELS == REFERENCE_MODELS


@pytest.mark.parametrize(
    ("text", "fragments"),
    [
        ("sharpness = 1.0", ["material.sharpness = 1.0", "[0, 1)"]),
        ("sharpness = -0.1", ["material.sharpness = -0.1", "[0, 1)"]),
        ('sharpness = "high"', ["material.sharpness = 'high'", "expected a number"]),
        ('tangent_field = "spiral"', ["material.tangent_field = 'spiral'", "axis, direction"]),
        ('tangent_axis = "w"', ["material.tangent_axis = 'w'", "x, y, z"]),
        ("tangent_axis = [0, 1, 0]", ["material.tangent_axis = [0, 1, 0]", "x, y, z"]),
        ('model = "lambert"', ["material.model = 'lambert'", "phong, microfacet, banks"]),
    ],
)
def test_bad_material_values_name_file_and_key(tmp_path, text, fragments):
    with pytest.raises(InputFileError) as info:
        load_scene(write_scene(tmp_path, text))
    message = str(info.value)
    assert "\n" not in message
    assert "scene.toml" in message and "object[0]" in message
    for fragment in fragments:
        assert fragment in message, message


MESH_SCENE = """[environment]
file = "hdr/studio.exr"
[[object]]
mesh = "mesh/teapot.obj"
components = [3]
{subdivide}
"""


def test_subdivide_refines_a_mesh_towards_its_smooth_surface(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text(MESH_SCENE.format(subdivide=""))
    coarse = load_scene(path).reflectors()[0].mesh
    path.write_text(MESH_SCENE.format(subdivide="subdivide = 2"))
    fine = load_scene(path).reflectors()[0].mesh
    assert fine.triangle_count == 16 * coarse.triangle_count
    # the smooth surface stays close to the coarse one: within 3 % of the lid's size
    size = float(np.ptp(coarse.positions, axis=0).max())
    surface = trimesh.Trimesh(coarse.positions, coarse.indices, process=False)
    samples, _ = trimesh.sample.sample_surface(surface, 200_000, seed=1)
    distance, _ = cKDTree(samples).query(fine.positions)
    assert distance.max() < 0.03 * size

    # and smoother: neighbouring normals turn less across each edge than before
    def turn(mesh):
        n = mesh.normals[mesh.indices]
        return np.degrees(np.arccos(np.clip((n[:, 0] * n[:, 1]).sum(-1), -1, 1))).mean()

    assert turn(fine) < 0.5 * turn(coarse)
    for bad in ("subdivide = 9", "subdivide = 1.5", "subdivide = true"):
        path.write_text(MESH_SCENE.format(subdivide=bad))
        with pytest.raises(InputFileError, match=r"object\[0\]\.subdivide = .*0\.\.4"):
            load_scene(path)


SCENE_TOP = """{top}
[environment]
file = {file}
[camera]
{camera}
[[object]]
primitive = "sphere"
{object}
"""


@pytest.mark.parametrize(
    ("parts", "fragments"),
    [
        ({"file": "5"}, ["environment.file = 5", "expected a string"]),
        ({"camera": "zoom = 2.0"}, ["camera.zoom: unknown key", "azimuth, elevation"]),
        ({"camera": "distanse = 2.0"}, ["camera.distanse: unknown key", "did you mean 'distance'"]),
        ({"top": 'nmae = "x"'}, ["nmae: unknown key", "did you mean 'name'"]),
        ({"object": "scael = 2.0"}, ["object[0].scael: unknown key", "did you mean 'scale'"]),
        ({"camera": "fov = 180.0"}, ["camera.fov = 180.0", "in (0, 180)"]),
        ({"camera": "fov = 0"}, ["camera.fov = 0", "in (0, 180)"]),
        ({"camera": "distance = 0"}, ["camera.distance = 0", "> 0"]),
        ({"camera": "distance = inf"}, ["camera.distance = inf", "> 0"]),
        ({"camera": "azimuth = nan"}, ["camera.azimuth = nan", "finite"]),
        ({"camera": "target = [0, nan, 0]"}, ["camera.target[1] = nan", "finite"]),
        ({"object": "scale = 0"}, ["object[0].scale = 0", "> 0"]),
        ({"object": "fit = -1.0"}, ["object[0].fit = -1.0", "> 0"]),
        ({"object": "size = 0"}, ["object[0].size = 0", "> 0"]),
        ({"object": "translation = [1, 2]"}, ["object[0].translation = [1, 2]", "[x, y, z]"]),
        ({"object": "role = 7"}, ["object[0].role = 7", "reflector, local"]),
    ],
)
def test_scene_files_are_checked_against_the_schema(tmp_path, parts, fragments):
    """Wrong types, values out of range, NaN and Inf, unknown keys (with a suggestion):
    one line naming the file and the key path, before anything is loaded."""
    fields = {"top": "", "file": '"hdr/studio.exr"', "camera": "", "object": ""} | parts
    path = tmp_path / "scene.toml"
    path.write_text(SCENE_TOP.format(**fields))
    with pytest.raises(InputFileError) as info:
        load_scene(path)
    message = str(info.value)
    assert "\n" not in message and message.startswith(f"{path}: ")
    for fragment in fragments:
        assert fragment in message, message


def test_a_scene_with_its_environment_or_reflector_replaced_is_named_so():
    """compare's title and compare.json name what was compared, not the scene file alone."""
    from envstudio.io.scene_setup import build_scene
    from envstudio.resources import asset_root

    env, mesh = asset_root() / "hdr" / "studio.exr", asset_root() / "mesh" / "bunny.ply"
    assert build_scene("studio").label == "studio"
    assert build_scene("room", env).label == "room with env studio.exr"
    assert build_scene("studio", env, mesh).label == "studio with env studio.exr, mesh bunny.ply"
    assert build_scene("room", env).name == "room"  # bakes and files keep keying on the name
