"""A sun of 1e7 (real HDR captures reach it) stays finite in every EXR the commands write:
float32 where a value exceeds the half range. The prefilters and chains keep its energy
within 1 % (the lat-long and cube conversions resample a 2×2-texel sun within 3 %)."""

from __future__ import annotations

import numpy as np
import pytest
from OpenImageIO import ImageInput

from envstudio.cli import main
from envstudio.core import cubemap, latlong
from envstudio.core.cubemap import cross_to_faces
from envstudio.io.images import HALF_MAX, read_image, write_image

SUN = 1e7


@pytest.fixture(scope="module")
def sun_map(tmp_path_factory):
    radiance = np.full((64, 128, 3), 0.5, np.float32)
    radiance[20:22, 40:42] = SUN
    path = tmp_path_factory.mktemp("sun") / "sun.exr"
    write_image(path, radiance)
    return path, radiance


def _energy_latlong(image: np.ndarray) -> float:
    h, w = image.shape[:2]
    return float((image[..., :3].mean(axis=2) * latlong.texel_solid_angles(h, w)).sum())


def _energy_cross(image: np.ndarray) -> float:
    faces = cross_to_faces(image[..., :3])
    return float((faces.mean(axis=3) * cubemap.texel_solid_angles(faces.shape[1])).sum())


def _format(path) -> str:
    image = ImageInput.open(str(path))
    try:
        return str(image.spec().format)
    finally:
        image.close()


def test_exr_is_half_where_it_fits_and_float_where_it_does_not(tmp_path, sun_map):
    path, radiance = sun_map
    assert _format(path) == "float" and np.array_equal(read_image(path), radiance)
    dim = tmp_path / "dim.exr"
    write_image(dim, np.full((4, 8, 3), HALF_MAX, np.float32))
    assert _format(dim) == "half" and np.isfinite(read_image(dim)).all()


PHONG = ["prefilter", "--kernel", "phong", "--exponent", "10", "--param", "cube", "--size", "16"]
CHAIN = ["prefilter", "--chain", "--param", "cube", "--size", "16", "--levels", "3"]
OUTPUTS = {
    "envmap latlong": (["envmap", "--to", "latlong", "--size", "32"], "", 0.03),
    "envmap cube": (["envmap", "--to", "cube", "--size", "32"], "", 0.03),
    "envmap paraboloid": (["envmap", "--to", "paraboloid", "--size", "32"], "", None),
    "render rsibr": (
        ["render", "--method", "rsibr", "--size", "32x32", "--param", "map_size=16"],
        "",
        None,
    ),
    "envmap spheremap": (["envmap", "--to", "spheremap", "--size", "32"], "", None),
    "prefilter brute": (
        [*PHONG, "--algo", "brute"],
        "",
        0.01,
    ),
    "prefilter hierarchical": (
        [*PHONG, "--algo", "hierarchical"],
        "",
        0.01,
    ),
    "chain spectral": (CHAIN, "_mip2", 0.01),
    "chain gpu": (
        [*CHAIN, "--device", "gpu"],
        "_mip2",
        0.01,
    ),
    "chain hierarchical": (
        [*CHAIN, "--algo", "hierarchical", "--device", "cpu"],
        "_mip2",
        0.01,
    ),
}


@pytest.mark.parametrize("name", list(OUTPUTS))
def test_every_output_of_a_sun_is_finite_and_keeps_its_energy(tmp_path, sun_map, name):
    path, radiance = sun_map
    argv, written, tolerance = OUTPUTS[name]
    assert main([*argv, "--env", str(path), "-o", str(tmp_path / "out.exr")]) == 0
    for output in tmp_path.glob("out*.exr"):
        assert np.isfinite(read_image(output)).all(), output.name
    if tolerance is not None:
        image = read_image(tmp_path / f"out{written}.exr")
        energy = _energy_latlong(image) if "latlong" in name else _energy_cross(image)
        assert energy == pytest.approx(_energy_latlong(radiance), rel=tolerance)


def test_radiance_beyond_range_is_refused(tmp_path, capsys):
    radiance = np.full((16, 32, 3), 1.0, np.float32)
    radiance[3, 4] = 1e30
    path = tmp_path / "absurd.exr"
    write_image(path, radiance)
    assert main(["sh", "--env", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "1e+30" in err and "out of range" in err
